#!/usr/bin/env bash
# Wall time and integrator counts of the paper scenarios through the CLI.
set -euo pipefail
cd "$(dirname "$0")/.."
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for s in scenarios/paper_fig3_impact.toml scenarios/paper_fig5_envelope_grasp.toml; do
  [ -f "$s" ] || continue
  start=$(date +%s.%N)
  build/capdyn run "$s" -o "$out/r.h5" --quiet > "$out/summary.txt"
  end=$(date +%s.%N)
  printf '\n%s: %.2f s wall\n' "$s" "$(echo "$end - $start" | bc -l)"
  grep -Ei 'rhs|steps|events' "$out/summary.txt" | sed 's/^/  /' || true
done
