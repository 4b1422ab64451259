#!/usr/bin/env bash
# Install capdyn into a temporary prefix, then build and run each given C
# program against the installed copy only (headers and libraries found
# through pkg-config, PKG_CONFIG_PATH pointing at the prefix; the program is
# compiled in a scratch directory, away from the source tree's include/).
# A program that includes <capdyn/io.h> links capdyn-io, any other capdyn.
# Each program is built twice: against the static archives (the flags of
# `pkg-config --static --libs`, -lcapdyn* replaced by the archives' paths)
# and against the shared libraries (`pkg-config --libs`, no --static; the
# program must then need libcapdyn.so.SOVERSION), and each build runs from
# the repository root and must exit 0.
# The shared libraries: real name libcapdyn[_io].so.VERSION, soname
# libcapdyn[_io].so.MAJOR.MINOR, and `nm -D --defined-only` of the two
# together lists exactly the public functions, the cd_* names declared in
# the installed include/capdyn/*.h (scripts/public-symbols.sh), each in one
# library only: no internal symbol is exported (issue 24).
# Finally `make uninstall` must leave no file behind in the prefix.
#
# Usage: tests/install_check.sh prog1.c [prog2.c ...]
#   (env: BUILD = build directory to install from, MAKE, CC)
# Run by `make test` (target install-check) on tests/embed/*.c; the
# examples/ programs join through INSTALL_CHECK_SRC in the Makefile.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
[ $# -ge 1 ] || { echo "usage: $0 prog.c [prog.c ...]" >&2; exit 2; }
make_cmd=${MAKE:-make}
cc_cmd=${CC:-cc}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
fail() { echo "install check: $*" >&2; exit 1; }

$make_cmd --no-print-directory install PREFIX="$prefix" BUILD="${BUILD:-build}" > "$tmp/install.log" 2>&1 ||
  { cat "$tmp/install.log" >&2; fail "make install PREFIX=$prefix failed"; }

export PKG_CONFIG_PATH=$prefix/lib/pkgconfig
want=$(sed -n 's/^#define CD_VERSION_STRING "\(.*\)"/\1/p' include/capdyn/model.h)
got=$(pkg-config --modversion capdyn) || fail "pkg-config does not find capdyn.pc in $PKG_CONFIG_PATH"
[ "$got" = "$want" ] || fail "capdyn.pc version $got, expected $want"
case "$(pkg-config --cflags capdyn)" in
  *"-I$prefix/include"*) ;;
  *) fail "pkg-config --cflags capdyn does not point into $prefix/include" ;;
esac

# ---- the shared libraries: names, soname, exported symbols ----
lib=$prefix/lib
soversion=$(echo "$want" | cut -d. -f1-2)
for so in libcapdyn libcapdyn_io; do
  [ -f "$lib/$so.so.$want" ] && [ ! -L "$lib/$so.so.$want" ] || fail "$lib/$so.so.$want is not installed"
  [ "$(readlink "$lib/$so.so.$soversion")" = "$so.so.$want" ] || fail "$lib/$so.so.$soversion does not point to $so.so.$want"
  [ "$(readlink "$lib/$so.so")" = "$so.so.$soversion" ] || fail "$lib/$so.so does not point to $so.so.$soversion"
  [ -f "$lib/$so.a" ] || fail "the static archive $lib/$so.a is not installed"
  soname=$(readelf -d "$lib/$so.so.$want" | sed -n 's/.*(SONAME).*\[\(.*\)\].*/\1/p')
  [ "$soname" = "$so.so.$soversion" ] || fail "$so.so.$want has soname '$soname', expected $so.so.$soversion"
done
readelf -d "$lib/libcapdyn_io.so.$want" | grep -q "NEEDED.*\[libcapdyn.so.$soversion\]" ||
  fail "libcapdyn_io.so does not need libcapdyn.so.$soversion"
bash "$root/scripts/public-symbols.sh" "$prefix"/include/capdyn/*.h > "$tmp/public.txt"
for so in libcapdyn libcapdyn_io; do
  nm -D --defined-only "$lib/$so.so.$want" | awk '{print $NF}' | sort > "$tmp/$so.sym"
done
internal=$(cat "$tmp/libcapdyn.sym" "$tmp/libcapdyn_io.sym" | sort | comm -23 - "$tmp/public.txt")
[ -z "$internal" ] || fail "symbols exported but not declared in include/capdyn/*.h: $(echo $internal)"
missing=$(cat "$tmp/libcapdyn.sym" "$tmp/libcapdyn_io.sym" | sort | comm -13 - "$tmp/public.txt")
[ -z "$missing" ] || fail "public functions not exported by either library: $(echo $missing)"
twice=$(comm -12 "$tmp/libcapdyn.sym" "$tmp/libcapdyn_io.sym")
[ -z "$twice" ] || fail "exported by both libraries: $(echo $twice)"
echo "install check: libcapdyn.so.$want ($(wc -l < "$tmp/libcapdyn.sym") symbols) + libcapdyn_io.so.$want" \
     "($(wc -l < "$tmp/libcapdyn_io.sym")) export exactly the $(wc -l < "$tmp/public.txt") public functions; soname .so.$soversion"

# ---- each program, static then shared ----
mkdir -p "$tmp/work"
n=0
for src in "$@"; do
  [ -f "$src" ] || fail "no such program: $src"
  name=$(basename "$src" .c)
  pkg=capdyn
  if grep -q '#include *<capdyn/io.h>' "$src"; then pkg=capdyn-io; fi
  cp "$src" "$tmp/work/$name.c"
  # the program's own headers beside it (#include "x.h"), as an embedder keeps them
  for h in $(sed -n 's/^ *# *include *"\([^"/]*\)".*/\1/p' "$src"); do
    [ -f "$(dirname "$src")/$h" ] && cp "$(dirname "$src")/$h" "$tmp/work/$h"
  done
  # static: the archives by path (with the .so installed next to them, -lcapdyn would pick the .so)
  static_libs=$(pkg-config --static --libs "$pkg" | sed -e "s|-lcapdyn_io\b|$lib/libcapdyn_io.a|" -e "s|-lcapdyn\b|$lib/libcapdyn.a|")
  # shellcheck disable=SC2046,SC2086
  (cd "$tmp/work" && $cc_cmd -std=c99 -Wall -Wextra -Wpedantic -Werror $(pkg-config --cflags "$pkg") \
     "$name.c" -o "$name" $static_libs) ||
    fail "$src does not build against the installed static archives (pkg-config --static $pkg)"
  ! readelf -d "$tmp/work/$name" | grep -q 'NEEDED.*libcapdyn' || fail "$src (static) needs a capdyn shared library"
  "$tmp/work/$name" > "$tmp/work/$name.out" 2>&1 ||
    { cat "$tmp/work/$name.out" >&2; fail "$src built against the installed copy exits non-zero"; }
  echo "install check: $src (pkg-config --static $pkg, archives): $(tail -n 1 "$tmp/work/$name.out")"
  # shared: pkg-config --libs without --static; -lm for the program's own maths
  # shellcheck disable=SC2046
  (cd "$tmp/work" && $cc_cmd -std=c99 -Wall -Wextra -Wpedantic -Werror $(pkg-config --cflags "$pkg") \
     "$name.c" -o "$name.so-linked" $(pkg-config --libs "$pkg") -lm -Wl,-rpath,"$lib") ||
    fail "$src does not build against the installed shared libraries (pkg-config --libs $pkg)"
  readelf -d "$tmp/work/$name.so-linked" | grep -q "NEEDED.*\[libcapdyn.*\.so\.$soversion\]" ||
    fail "$src linked with pkg-config --libs $pkg does not need libcapdyn*.so.$soversion"
  "$tmp/work/$name.so-linked" > "$tmp/work/$name.out" 2>&1 ||
    { cat "$tmp/work/$name.out" >&2; fail "$src built against the installed shared libraries exits non-zero"; }
  echo "install check: $src (pkg-config $pkg, shared): $(tail -n 1 "$tmp/work/$name.out")"
  n=$((n + 1))
done

$make_cmd --no-print-directory uninstall PREFIX="$prefix" BUILD="${BUILD:-build}" > "$tmp/uninstall.log" 2>&1 ||
  { cat "$tmp/uninstall.log" >&2; fail "make uninstall failed"; }
left=$(find "$prefix" -type f | head -n 5)
[ -z "$left" ] || fail "make uninstall left files behind: $left"
echo "install check: $n program(s) built and run against the installed copy (static and shared); uninstall left nothing"
