#!/usr/bin/env bash
# Bit-flip campaign on a small results file (docs/reliability.md,
# "Untrusted results files"): N single-bit flips (fixed seed), each file read
# by capdyn info or export; prints how many gave the same output, another
# output, a clean error, a contained HDF5 crash, and anything else ("bad").
# Usage: bench/bitflips.sh [N]   (default 5000; about 20 flips a second)
set -euo pipefail
cd "$(dirname "$0")/.."
make --no-print-directory build/capdyn_tests build/capdyn >/dev/null
CAPDYN_FLIP_COUNT="${1:-5000}" CAPDYN_BIN="$PWD/build/capdyn" CAPDYN_ROOT="$PWD" \
  build/capdyn_tests --filter 'results_safety/full_bit_flip_campaign' --verbose=0 -j1
