#!/usr/bin/env bash
# Copies the non-system shared libraries an FMU binary needs next to it
# (docs/fmu.md, "What is inside"): the binary is linked with the rpath
# $ORIGIN, so they are found in the FMU's binaries/linux64/ with capdyn not
# installed and LD_LIBRARY_PATH unset. System libraries (the C and C++
# runtimes, libm, the loader) are left to the importer's system.
# usage: src/fmu/bundle.sh build/fmu/linux64/capdyn_fmu.so
set -euo pipefail
so=$1
dir=$(dirname "$so")
system='^(linux-vdso|ld-linux|libc|libm|libdl|libpthread|librt|libstdc\+\+|libgcc_s)\.'
# ldd lists the whole closure; copy each library under its soname
ldd "$so" | awk '$2 == "=>" && $3 ~ /^\// { print $1, $3 }' | while read -r name path; do
  if [[ $name =~ $system ]]; then continue; fi
  cp -L "$path" "$dir/$name"
  chmod 644 "$dir/$name"
done
# every dependency must now resolve inside dir or the system
if env -u LD_LIBRARY_PATH ldd "$so" | grep -q 'not found'; then
  echo "bundle.sh: $so: a dependency is not found:" >&2
  ldd "$so" | grep 'not found' >&2
  exit 1
fi
