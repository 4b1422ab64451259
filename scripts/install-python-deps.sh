#!/usr/bin/env bash
# The Python side of capdyn (docs/python.md): a virtual environment at
# $VENV (default build/venv) with the pinned PyPI packages of
# python/requirements.txt, and capdyn's own package (python/) installed into
# it, compiled against the source tree's headers and shared libraries
# (make builds them first: make python-test).
#  - Debian packages python3, python3-venv, python3-dev (the extension is
#    compiled) are installed only when missing, through scripts/install-deps.sh
#    (root or sudo);
#  - the requirements are (re)installed only when python/requirements.txt
#    changed since the last time (a stamp in the venv);
#  - the package is reinstalled every time (pip --no-build-isolation, with
#    the pinned setuptools and cffi: no network needed for it).
# Usage: scripts/install-python-deps.sh      (env: VENV, BUILD, PYTHON=python3)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
BUILD=${BUILD:-build}
VENV=${VENV:-$BUILD/venv}
PYTHON=${PYTHON:-python3}
req=python/requirements.txt

CAPDYN_EXTRA_PKGS="python3 python3-venv python3-dev" bash scripts/install-deps.sh

if [ ! -x "$VENV/bin/python" ] || ! "$VENV/bin/python" -c 'import sys' 2>/dev/null; then
  echo "install-python-deps: creating the virtual environment $VENV" >&2
  rm -rf "$VENV"
  "$PYTHON" -m venv "$VENV"
fi
stamp=$VENV/.capdyn-requirements
if ! cmp -s "$req" "$stamp" 2>/dev/null; then
  echo "install-python-deps: installing $req into $VENV (PyPI)" >&2
  "$VENV/bin/python" -m pip install -q --disable-pip-version-check -r "$req"
  cp "$req" "$stamp"
fi
# the package: rebuilt against the current headers and libraries
rm -rf python/build python/capdyn.egg-info
CAPDYN_BUILD="$BUILD" "$VENV/bin/python" -m pip install -q --disable-pip-version-check --no-build-isolation \
  --no-deps --force-reinstall ./python >&2
"$VENV/bin/python" -c 'import capdyn; print("install-python-deps: capdyn", capdyn.version(), "in", capdyn.__file__)' >&2
rm -rf python/build python/capdyn.egg-info
