#!/usr/bin/env bash
# Installs capdyn's build, test and plotting dependencies from Debian packages,
# only those that are missing. Idempotent; works as root or through sudo.
# Usage: scripts/install-deps.sh        (CAPDYN_NO_INSTALL=1 to only check;
#        CAPDYN_EXTRA_PKGS="a b" adds packages, e.g. scripts/install-bench-deps.sh)
#        scripts/install-deps.sh --fuzz adds clang and libFuzzer's runtime,
#        for `make fuzz` only (scripts/install-fuzz-deps.sh)
set -euo pipefail

pkgs=(build-essential pkg-config libgsl-dev libhdf5-dev zlib1g-dev hdf5-tools libccd-dev
      libtomlplusplus-dev libqhull-dev libcriterion-dev liburdfdom-dev gnuplot-nox strace)
# shellcheck disable=SC2206
pkgs+=(${CAPDYN_EXTRA_PKGS:-})
if [ "${1:-}" = --fuzz ]; then
  pkgs+=(clang libclang-rt-dev)
fi

missing=()
for p in "${pkgs[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

if [ "${CAPDYN_NO_INSTALL:-0}" = 1 ]; then
  echo "install-deps: missing Debian packages: ${missing[*]}" >&2
  exit 1
fi

if [ "$(id -u)" -eq 0 ]; then
  SUDO=()
elif command -v sudo >/dev/null 2>&1; then
  SUDO=(sudo)
else
  echo "install-deps: need root or sudo to install: ${missing[*]}" >&2
  exit 1
fi

echo "install-deps: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
"${SUDO[@]}" apt-get update -qq
"${SUDO[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done" >&2
