#!/usr/bin/env bash
# Times every Criterion test one at a time (-j1) and prints them longest
# first, with each suite's total: what decides which tests `make test` runs
# and which move to `make test-long` (Makefile, TEST_LONG).
#
#   tests/test_times.sh [CRITERION ARGS...]     e.g. --filter 'capture/*'
#
# Times are the wall seconds Criterion prints per test with --verbose
# ("[PASS] suite::name: (1.23s)"); the raw output is kept in
# $BUILD/test_times.log. On a shared machine read them as ratios and an
# ordering, not as absolute costs.
set -uo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
log=$BUILD/test_times.log
cpu=$BUILD/test_times.cpu
CAPDYN_BIN=$PWD/$BUILD/capdyn CAPDYN_ROOT=$PWD /usr/bin/time -o "$cpu" -f "%e %U %S" \
    "$BUILD/capdyn_tests" -j1 --verbose "$@" > "$log" 2>&1
rc=$?
read -r wall u s < <(tail -1 "$cpu")
echo "# $(date -u +%FT%TZ), at -j1: wall $wall s, CPU $u + $s s (user + system, the tests' processes included), exit $rc, load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "# on an idle machine a test's wall time is about its wall time here x (CPU / wall) = x $(awk -v c="$u" -v s="$s" -v w="$wall" 'BEGIN { printf "%.2f", (c + s) / w }')"
awk '
/^\[(PASS|FAIL)\] [^ ]+::[^ ]+:.*\([0-9.]+s\)$/ {
    st = substr($1, 2, 4); name = $2; sub(/:$/, "", name)
    t = $NF; gsub(/[()s]/, "", t)
    split(name, p, "::")
    printf "%9.2f  %-4s  %s/%s\n", t, st, p[1], p[2]
    tot[p[1]] += t; all += t
}
END {
    for (s in tot) printf "%9.2f  SUITE %s\n", tot[s], s
    printf "%9.2f  TOTAL\n", all
}' "$log" | sort -k1,1 -g -r
