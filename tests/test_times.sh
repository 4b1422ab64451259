#!/usr/bin/env bash
# Times every Criterion test one at a time (-j1) and prints them longest
# first, with each suite's total: what decides which tests `make test` runs
# and which move to `make test-long` (Makefile, TEST_LONG).
#
#   tests/test_times.sh [CRITERION ARGS...]     e.g. --filter 'capture/*'
#
# Times are wall seconds from Criterion's XML report; on a shared machine
# read them as ratios and an ordering, not as absolute costs.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
xml=$(mktemp /tmp/capdyn_test_times.XXXXXX.xml)
trap 'rm -f "$xml"' EXIT
start=$(date +%s)
CAPDYN_BIN=$PWD/$BUILD/capdyn CAPDYN_ROOT=$PWD "$BUILD/capdyn_tests" -j1 --xml="$xml" "$@" > /dev/null 2>&1 || true
echo "# $(date -u +%FT%TZ), wall $(( $(date +%s) - start )) s at -j1, load $(cut -d' ' -f1-3 /proc/loadavg)"
awk '
/<testsuite / { match($0, /name="[^"]*"/); suite = substr($0, RSTART + 6, RLENGTH - 7) }
/<testcase / {
    match($0, /name="[^"]*"/); name = substr($0, RSTART + 6, RLENGTH - 7)
    match($0, /status="[^"]*"/); st = substr($0, RSTART + 8, RLENGTH - 9)
    match($0, / time="[^"]*"/); t = substr($0, RSTART + 7, RLENGTH - 8)
    if (st == "SKIPPED") next
    printf "%9.3f  %-8s %s/%s\n", t, st, suite, name
    tot[suite] += t; all += t
}
END {
    for (s in tot) printf "%9.3f  SUITE    %s\n", tot[s], s
    printf "%9.3f  TOTAL\n", all
}' "$xml" | sort -k1,1 -g -r
