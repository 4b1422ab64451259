#!/usr/bin/env bash
# Full-length kill-point measurement (docs/reliability.md, "Kill safety"):
# runs a whole scenario as shipped once per write it makes, killing it
# (SIGKILL through strace's fault injection) at that write, and checks
# after each kill that every committed sample reads back bit-identical to
# the uninterrupted run. Prints "kill points N (killed K), intact M".
# The run commits when a buffer of rows is full (1005 rows) and at its close (flush_every
# 1e9 s), so that every run makes the same writes.
# Usage: bench/killpoints.sh [SCENARIO.toml, relative to scenarios/]
# (default paper_fig5_envelope_grasp.toml: 715 kill points, about 4 minutes alone, 2026-11-27).
set -euo pipefail
cd "$(dirname "$0")/.."
make --no-print-directory build/capdyn_tests build/capdyn >/dev/null
CAPDYN_KILL_FULL=1 CAPDYN_KILL_SCENARIO="${1:-paper_fig5_envelope_grasp.toml}" \
  CAPDYN_BIN="$PWD/build/capdyn" CAPDYN_ROOT="$PWD" \
  build/capdyn_tests --filter 'results_safety/full_length_kill_campaign' --verbose=0 -j1
