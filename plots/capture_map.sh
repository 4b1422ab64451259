#!/usr/bin/env bash
# The capture-success map of issue 10 (docs/capture.md, "The capture map"):
# capdyn sweep over the aim error across the handrail's bar x the target's
# tumbling rate on scenarios/capture_handrail_tumbling.toml, each variant
# ended at its verdict, then the map rendered into figures/:
#   capture_map.png, capture_map.svg   verdict (cells labelled with the peak
#                                      contact force on the target) and time
#                                      to capture, over aim error x rate
#   data/capture_map.h5, .dat          the sweep summary and its table
#
#   plots/capture_map.sh              (what `make capture-map` runs;
#                                      CAPTURE_MAP=1 make figures runs it too)
#
# Environment (defaults = the documented map):
#   CAPDYN           the capdyn binary (default build/capdyn)
#   FIGURES_DIR      where to write (default figures)
#   CAPMAP_AIM       aim errors control.misalign.position[0], A:B:N [m] (-0.02:0.02:5)
#   CAPMAP_RATE      tumbling rates about the target's x, A:B:N [deg/s] (0:8:5)
#   CAPMAP_DURATION  simulation.duration of each variant [s] (8)
#   SWEEP_ARGS       extra capdyn sweep options (default "-j 1")
#   CAPMAP_MC        N > 0: N Monte Carlo draws per cell of CAPMAP_DISPERSE; the
#                    map is then the capture probability and its Wilson 95 %
#                    interval (capture_map_mc.png/.svg, data/capture_map_mc.*)
#   CAPMAP_DISPERSE  the dispersion of each draw (default: the target's principal
#                    moments 5 %, 'target.target.inertia=inertia(116,137,154,0.05)')
#   CAPMAP_SEED      the draws' seed (default 1)
set -euo pipefail
cd "$(dirname "$0")/.."
CAPDYN=${CAPDYN:-build/capdyn}
OUT=${FIGURES_DIR:-figures}
D="$OUT/data"
AIM=${CAPMAP_AIM:--0.02:0.02:5}
RATE=${CAPMAP_RATE:-0:8:5}
DUR=${CAPMAP_DURATION:-8}
read -r -a SWEEP_EXTRA <<< "${SWEEP_ARGS:--j 1}"
[ -x "$CAPDYN" ] || { echo "capture_map.sh: $CAPDYN not found; run 'make' first" >&2; exit 1; }
command -v gnuplot > /dev/null || { echo "capture_map.sh: gnuplot not found; run 'make deps'" >&2; exit 1; }
mkdir -p "$D"
sc=scenarios/capture_handrail_tumbling.toml
MC=${CAPMAP_MC:-0}
if [ "$MC" != 0 ]; then
    DISP=${CAPMAP_DISPERSE:-target.target.inertia=inertia(116,137,154,0.05)}
    echo "== capture_map: capdyn sweep $sc --mc $MC --disperse $DISP (aim $AIM m, rate $RATE deg/s, duration $DUR s)"
    "$CAPDYN" sweep "$sc" --vary "control.misalign.position[0]=$AIM" --vary "target.target.angular_velocity_deg_s[0]=$RATE" \
        --mc "$MC" --disperse "$DISP" --seed "${CAPMAP_SEED:-1}" --set "simulation.duration=$DUR" --until-verdict -q \
        -o "$D/capture_map_mc.h5" ${SWEEP_EXTRA[@]+"${SWEEP_EXTRA[@]}"}
    "$CAPDYN" sweep --table "$D/capture_map_mc.h5" > "$D/capture_map_mc.dat"
    for ext in png svg; do
        gnuplot -c plots/capture_map.gp "$D/capture_map_mc.dat" "$OUT/capture_map_mc.$ext" \
            "Capture probability of a tumbling target by its handrail: aim error x tumbling rate, $MC draws per cell" mc
    done
    echo "   $OUT/capture_map_mc.png $OUT/capture_map_mc.svg ($D/capture_map_mc.dat)"
    exit 0
fi
echo "== capture_map: capdyn sweep $sc (aim $AIM m, rate $RATE deg/s, duration $DUR s)"
"$CAPDYN" sweep "$sc" --vary "control.misalign.position[0]=$AIM" --vary "target.target.angular_velocity_deg_s[0]=$RATE" \
    --set "simulation.duration=$DUR" --until-verdict -q -o "$D/capture_map.h5" ${SWEEP_EXTRA[@]+"${SWEEP_EXTRA[@]}"}
"$CAPDYN" sweep --table "$D/capture_map.h5" > "$D/capture_map.dat"
# the counts per rate (table columns: 3 rate, 6 verdict, 7 status)
echo "   rate [deg/s]  captured  escaped  unresolved  failed"
awk '!/^#/ { r = $3; n[r]++; if ($7 != 0) f[r]++; else if ($6 == 1) c[r]++; else if ($6 == 2) e[r]++; else u[r]++ }
     END { for (r in n) printf "   %12s  %8d  %7d  %10d  %6d\n", r, c[r], e[r], u[r], f[r] }' "$D/capture_map.dat" | sort -g
for ext in png svg; do
    gnuplot -c plots/capture_map.gp "$D/capture_map.dat" "$OUT/capture_map.$ext" \
        "Capture of a tumbling target by its handrail: aim error x tumbling rate ($DUR s runs)"
done
echo "   $OUT/capture_map.png $OUT/capture_map.svg ($D/capture_map.dat)"
