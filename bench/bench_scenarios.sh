#!/usr/bin/env bash
# Wall time and integrator counts of the paper scenarios through the CLI.
set -euo pipefail
cd "$(dirname "$0")/.."
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for s in scenarios/paper_fig3_impact.toml scenarios/paper_fig5_envelope_grasp.toml; do
  [ -f "$s" ] || continue
  best=""
  for rep in 1 2 3; do
    start=$(date +%s%N)
    build/capdyn run "$s" -o "$out/r.h5" --quiet > "$out/summary.txt"
    end=$(date +%s%N)
    ms=$(( (end - start) / 1000000 ))
    if [ -z "$best" ] || [ "$ms" -lt "$best" ]; then best=$ms; fi
  done
  printf '\n%s: best of 3 runs %d ms wall (including HDF5 output)\n' "$s" "$best"
  build/capdyn info "$out/r.h5" | grep -E "^(events|integrator)" | sed "s/^/  /" || true
done
