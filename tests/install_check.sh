#!/usr/bin/env bash
# Install capdyn into a temporary prefix, then build and run each given C
# program against the installed copy only (headers and libraries found
# through pkg-config, PKG_CONFIG_PATH pointing at the prefix; the program is
# compiled in a scratch directory, away from the source tree's include/).
# A program that includes <capdyn/io.h> links capdyn-io, any other capdyn.
# Each program runs from the repository root and must exit 0. Finally
# `make uninstall` must leave no file behind in the prefix.
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

mkdir -p "$tmp/work"
n=0
for src in "$@"; do
  [ -f "$src" ] || fail "no such program: $src"
  name=$(basename "$src" .c)
  pkg=capdyn
  if grep -q '#include *<capdyn/io.h>' "$src"; then pkg=capdyn-io; fi
  cp "$src" "$tmp/work/$name.c"
  # shellcheck disable=SC2046
  (cd "$tmp/work" && $cc_cmd -std=c99 -Wall -Wextra -Wpedantic -Werror $(pkg-config --cflags "$pkg") \
     "$name.c" -o "$name" $(pkg-config --static --libs "$pkg")) ||
    fail "$src does not build against the installed copy (pkg-config $pkg)"
  "$tmp/work/$name" > "$tmp/work/$name.out" 2>&1 ||
    { cat "$tmp/work/$name.out" >&2; fail "$src built against the installed copy exits non-zero"; }
  echo "install check: $src (pkg-config $pkg): $(tail -n 1 "$tmp/work/$name.out")"
  n=$((n + 1))
done

$make_cmd --no-print-directory uninstall PREFIX="$prefix" BUILD="${BUILD:-build}" > "$tmp/uninstall.log" 2>&1 ||
  { cat "$tmp/uninstall.log" >&2; fail "make uninstall failed"; }
left=$(find "$prefix" -type f | head -n 5)
[ -z "$left" ] || fail "make uninstall left files behind: $left"
echo "install check: $n program(s) built and run against the installed copy; uninstall left nothing"
