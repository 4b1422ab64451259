#!/usr/bin/env bash
# Runs the Criterion test binary for `make test` / `make test-long` with a
# line of progress at least every 20 s: Criterion's own lines except the
# per-test [RUN ]/[PASS]/[SKIP] ones (failures, the tests' [----] figures
# and the synthesis line all show), a count every 25 passed tests, and a
# "still running" line every 20 s while a long test runs. A filter that
# matches no test is an error.
#
#   tests/run_tests.sh BUILD/capdyn_tests [CRITERION ARGS...]
set -uo pipefail
bin=$1; shift
( while sleep 20; do echo "[....] tests still running ($SECONDS s)"; done ) &
tick=$!
trap 'kill "$tick" 2> /dev/null' EXIT
"$bin" --verbose "$@" 2>&1 | awk '
    /^\[PASS\]/ { n++; if (n % 25 == 0) { printf "[....] %d tests passed\n", n; fflush() } next }
    /^\[(RUN |SKIP)\]/ || /^\[====\] Running/ { next }
    /Synthesis: Tested: 0 / { none = 1 }
    { print; fflush() }
    END { if (none) { print "run_tests.sh: no test matched the filter"; exit 1 } }'
