#!/usr/bin/env bash
# The capdyn demo (`make demo`): the paper's Fig. 5 envelope grasp with its
# force-profile and snapshot figures, then a free-floating arm manoeuvre whose
# run summary shows momentum conservation.
#
# Environment: CAPDYN (default build/capdyn), FIGURES_DIR (default figures).
set -euo pipefail
cd "$(dirname "$0")/.."
CAPDYN=${CAPDYN:-build/capdyn}
OUT=${FIGURES_DIR:-figures}/demo
if [ ! -x "$CAPDYN" ]; then echo "demo.sh: $CAPDYN not found; run 'make' first" >&2; exit 1; fi
if ! command -v gnuplot > /dev/null; then echo "demo.sh: gnuplot not found; run 'make deps'" >&2; exit 1; fi
mkdir -p "$OUT"

echo "== 1. Paper Fig. 5: two 2-link fingers close on a free cylinder (envelope grasp)"
"$CAPDYN" run scenarios/paper_fig5_envelope_grasp.toml -o "$OUT/fig5.h5"
"$CAPDYN" export "$OUT/fig5.h5" outline --at 0,0.04,0.08,end > "$OUT/fig5_outline.dat"
"$CAPDYN" export "$OUT/fig5.h5" checkpoints --at 0,0.04,0.08,end > "$OUT/fig5_checkpoints.dat"
CAPDYN="$CAPDYN" bash plots/force_profile.sh "$OUT/fig5.h5" "$OUT/fig5_force.png" \
    "Fig. 5: contact forces of the envelope grasp"
CAPDYN="$CAPDYN" bash plots/force_profile.sh "$OUT/fig5.h5" "$OUT/fig5_force_closing.png" \
    "Fig. 5: closing on the cylinder (first 0.3 s)" 0.3
gnuplot -c plots/snapshots.gp "$OUT/fig5_outline.dat" "$OUT/fig5_checkpoints.dat" "$OUT/fig5_snapshots.png" \
    "Fig. 5: envelope grasp (grey open, green stick, red slip)" 4

echo
echo "== 2. A free-floating base with a 3-link arm: momentum must be conserved"
"$CAPDYN" run scenarios/free_floating_arm.toml -o "$OUT/free_floating_arm.h5" > "$OUT/free_floating_arm.txt"
grep -A2 '^momentum' "$OUT/free_floating_arm.txt"
echo "(full summary: $OUT/free_floating_arm.txt)"

echo
echo "figures: $OUT/fig5_force.png $OUT/fig5_force_closing.png $OUT/fig5_snapshots.png"
