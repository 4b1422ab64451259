#!/usr/bin/env bash
# Every plot script on a user-written scenario (tests/plots/user_grasp.toml:
# a three-finger TAKO hand on a ball with a stem, names and shapes no shipped
# scenario has): plots/capture.sh, plots/force_profile.sh (PNG, SVG and a
# zoom), and the gnuplot scripts of plots/figures.sh (snapshots, animation,
# diagnostics) on its exports. Each output must be a real picture
# (tests/plots/png_check.py: PNG with >= 2 % of its pixels drawn and >= 6
# colours, GIF with >= 10 frames, SVG with >= 20 drawing elements), and a
# blank picture must fail that check. Run by `make plots-test` (make test);
# about 10 s.
set -euo pipefail
cd "$(dirname "$0")/../.."
BUILD=${BUILD:-build}
CAPDYN=$(cd "$(dirname "${CAPDYN:-$BUILD/capdyn}")" && pwd)/$(basename "${CAPDYN:-$BUILD/capdyn}")
export CAPDYN
for tool in gnuplot h5dump python3; do
    command -v $tool > /dev/null || { echo "plots-test: $tool not found; run 'make deps'" >&2; exit 1; }
done
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
F="$T/figures"; D="$F/data"
mkdir -p "$D"
FIGURES_DIR="$F" bash plots/capture.sh tests/plots/user_grasp.toml > "$T/capture.log" 2>&1 || { cat "$T/capture.log"; exit 1; }
h5="$D/user_grasp.h5"
for out in force.png force.svg force_zoom.png; do
    DATA_DIR="$D" bash plots/force_profile.sh "$h5" "$F/$out" "" $([ "$out" = force_zoom.png ] && echo 0.1) > "$T/force.log" 2>&1 ||
        { cat "$T/force.log"; exit 1; }
done
"$CAPDYN" export "$h5" outline --at 0,0.1,end > "$D/outline.dat"
"$CAPDYN" export "$h5" checkpoints --at 0,0.1,end > "$D/cps.dat"
"$CAPDYN" export "$h5" outline --frames 12 > "$D/outline_anim.dat"
"$CAPDYN" export "$h5" checkpoints --frames 12 > "$D/cps_anim.dat"
"$CAPDYN" export "$h5" diagnostics > "$D/diag.dat"
{
    gnuplot -c plots/snapshots.gp "$D/outline.dat" "$D/cps.dat" "$F/snapshots.png" "user scenario" 3
    gnuplot -c plots/animation.gp "$D/outline_anim.dat" "$D/cps_anim.dat" "$F/grasp.gif" "user scenario" 3
    gnuplot -c plots/diagnostics.gp "$D/diag.dat" "$F/diagnostics.png" "user scenario"
} > "$T/gp.log" 2>&1 || { cat "$T/gp.log"; exit 1; }
# the check itself must fail on a blank picture
gnuplot -e "set terminal pngcairo size 600,400; set output '$T/blank.png'; unset border; unset tics; set xrange [0:1]; set yrange [0:1]; plot 2 notitle" 2> /dev/null || true
if python3 tests/plots/png_check.py "$T/blank.png" > /dev/null; then
    echo "plots-test: FAIL: png_check.py accepts a blank picture" >&2; exit 1
fi
python3 tests/plots/png_check.py "$F"/user_grasp_views.png "$F"/user_grasp_history.png "$F"/user_grasp_closeup.gif \
    "$F"/force.png "$F"/force.svg "$F"/force_zoom.png "$F"/snapshots.png "$F"/grasp.gif "$F"/diagnostics.png
grep -q 'target: probe' "$T/capture.log" || { echo "plots-test: FAIL: capture.sh did not find the target 'probe'" >&2; cat "$T/capture.log"; exit 1; }
echo "plots-test: every plot script drew the user scenario"
