#!/usr/bin/env bash
# Bit-flip campaign on a small sweep summary (docs/reliability.md, "Sweeps"):
# N single-bit flips (fixed seed), each file read by capdyn sweep --table or
# (every fourth) continued by capdyn sweep --resume; prints how many gave the
# intact values, a clean refusal, a contained HDF5 crash or hang, and
# anything else ("bad": a signal, a hang, a silent change of values).
# Usage: bench/summary_bitflips.sh [N]   (default 2000; about 14 flips a second)
set -euo pipefail
cd "$(dirname "$0")/.."
make --no-print-directory build/capdyn_tests build/capdyn >/dev/null
CAPDYN_SUMMARY_FLIP_COUNT="${1:-2000}" CAPDYN_BIN="$PWD/build/capdyn" CAPDYN_ROOT="$PWD" \
  build/capdyn_tests --filter 'summary_flips/full_campaign' --verbose=0 -j1
