#!/usr/bin/env bash
# Runs the paper scenarios with build/capdyn and renders their figures (PNG and
# SVG, plus an animated GIF of the grasp) into figures/ (git-ignored).
#
#   plots/figures.sh                 (what `make figures` runs)
#
# Environment:
#   CAPDYN         the capdyn binary (default build/capdyn)
#   FIGURES_DIR    where to write (default figures)
#   CAPDYN_RUN_ARGS  extra arguments for every `capdyn run`, e.g.
#                  "--set simulation.duration=0.2" for a quick look
# Progress: every step prints "[k/N] NAME: what (expected ~S s)" before it
# starts and its wall time after it; the expected times are those of the last
# complete run on this machine ($OUT/data/times.txt), else the defaults below
# (measured with `make figures` on the 2-core development machine, see
# docs/figures.md).
#   CAPTURE_MAP    1: also the capture-success map of plots/capture_map.sh
#                  (25 capture runs: 9 min of CPU, 25 min of wall time with -j 1
#                  on a shared 2-core machine, docs/capture.md; `make capture-map`
#                  alone); the capture scenarios' figures (plots/capture.sh,
#                  three runs) are always drawn
set -euo pipefail
cd "$(dirname "$0")/.."
CAPDYN=${CAPDYN:-build/capdyn}
OUT=${FIGURES_DIR:-figures}
read -r -a RUN_ARGS <<< "${CAPDYN_RUN_ARGS:-}"
if [ ! -x "$CAPDYN" ]; then echo "figures.sh: $CAPDYN not found; run 'make' first" >&2; exit 1; fi
if ! command -v gnuplot > /dev/null; then echo "figures.sh: gnuplot not found; run 'make deps'" >&2; exit 1; fi
mkdir -p "$OUT/data"
D="$OUT/data"

# ---- progress: step names, expected wall times [s] --------------------------
# defaults measured on the development machine (docs/figures.md, "Durations");
# a complete run writes its own into $D/times.txt and the next run uses them
declare -A EXPECT=([fig3]=2 [fig5]=16 [space_gripper_cylinder]=16 [space_gripper_irregular]=12
    [space_gripper_handrail]=18 [tako_centred]=11 [tako_off_centre]=9 [soft_wrap]=35 [region]=426
    [capture_handrail_tumbling]=17 [capture_body_offset]=42 [capture_too_fast]=21 [capture_map]=1134)
if [ -f "$D/times.txt" ]; then
    while read -r k v; do EXPECT[$k]=$v; done < "$D/times.txt"
fi
STEPS=(fig3 fig5 space_gripper_cylinder space_gripper_irregular space_gripper_handrail tako_centred tako_off_centre
       soft_wrap region capture_handrail_tumbling capture_body_offset capture_too_fast)
[ "${CAPTURE_MAP:-0}" = 1 ] && STEPS+=(capture_map)
NSTEP=${#STEPS[@]}
TOTAL=0; for k in "${STEPS[@]}"; do TOTAL=$((TOTAL + ${EXPECT[$k]})); done
echo "figures.sh: $NSTEP steps, expected ~$TOTAL s in all (with CAPDYN_RUN_ARGS: less)"
KSTEP=0
: > "$D/times.new"
step() { # name description
    KSTEP=$((KSTEP + 1)); STEP_NAME=$1; STEP_T0=$(date +%s)
    echo "[$KSTEP/$NSTEP] $1: $2 (expected ~${EXPECT[$1]} s)"
}
done_step() {
    local dt=$(( $(date +%s) - STEP_T0 ))
    echo "      done in $dt s"
    echo "$STEP_NAME $dt" >> "$D/times.new"
}

run() { # name scenario
    echo "      capdyn run $2"
    "$CAPDYN" run "$2" -o "$D/$1.h5" --quiet ${RUN_ARGS[@]+"${RUN_ARGS[@]}"}
    "$CAPDYN" export "$D/$1.h5" diagnostics > "$D/$1_diagnostics.dat"
}
force() { # name out-stem title [t_max]: PNG and SVG
    for ext in png svg; do DATA_DIR="$D" CAPDYN="$CAPDYN" bash plots/force_profile.sh "$D/$1.h5" "$OUT/$2.$ext" "$3" ${4:+"$4"}; done
}

# ---- Fig. 3: compliant mechanism hitting a rigid wall -----------------------
step fig3 "paper Fig. 3 impact: force profiles, diagnostics"
run fig3 scenarios/paper_fig3_impact.toml
force fig3 fig3_force "Fig. 3: impact force of a compliant mechanism on a rigid wall"
force fig3 fig3_force_first_strike "Fig. 3: the first strike (first 30 ms)" 0.03
for ext in png svg; do
    gnuplot -c plots/diagnostics.gp "$D/fig3_diagnostics.dat" "$OUT/fig3_diagnostics.$ext" "Fig. 3: energy, momentum, step size"
done
done_step

# ---- Fig. 5: envelope grasp of a free cylinder --------------------------------
step fig5 "paper Fig. 5 envelope grasp: force profiles, snapshots, diagnostics, GIF"
run fig5 scenarios/paper_fig5_envelope_grasp.toml
"$CAPDYN" export "$D/fig5.h5" outline --at 0,0.04,0.08,end > "$D/fig5_outline.dat"
"$CAPDYN" export "$D/fig5.h5" checkpoints --at 0,0.04,0.08,end > "$D/fig5_checkpoints.dat"
"$CAPDYN" export "$D/fig5.h5" outline --frames 120 > "$D/fig5_outline_anim.dat"
"$CAPDYN" export "$D/fig5.h5" checkpoints --frames 120 > "$D/fig5_checkpoints_anim.dat"
force fig5 fig5_force "Fig. 5: contact forces of the envelope grasp"
force fig5 fig5_force_closing "Fig. 5: closing on the cylinder (first 0.3 s)" 0.3
for ext in png svg; do
    gnuplot -c plots/snapshots.gp "$D/fig5_outline.dat" "$D/fig5_checkpoints.dat" "$OUT/fig5_snapshots.$ext" \
        "Fig. 5: envelope grasp (grey open, green stick, red slip)" 4
    gnuplot -c plots/diagnostics.gp "$D/fig5_diagnostics.dat" "$OUT/fig5_diagnostics.$ext" "Fig. 5: energy, momentum, step size"
done
gnuplot -c plots/animation.gp "$D/fig5_outline_anim.dat" "$D/fig5_checkpoints_anim.dat" "$OUT/fig5_grasp.gif" "Fig. 5 envelope grasp" 4
done_step

# ---- Figs. 9-11 and TAKO: grippers (docs/grippers.md) -------------------------
for g in space_gripper_cylinder space_gripper_irregular space_gripper_handrail tako_centred tako_off_centre soft_wrap; do
    step "$g" "gripper run: force profile, snapshots, close-up views"
    run "$g" "scenarios/$g.toml"
    "$CAPDYN" export "$D/$g.h5" outline --at 0,0.1,0.3,end > "$D/${g}_outline.dat"
    "$CAPDYN" export "$D/$g.h5" checkpoints --at 0,0.1,0.3,end > "$D/${g}_checkpoints.dat"
    force "$g" "${g}_force" "$g: contact forces"
    for ext in png svg; do
        gnuplot -c plots/snapshots.gp "$D/${g}_outline.dat" "$D/${g}_checkpoints.dat" "$OUT/${g}_snapshots.$ext" \
            "$g: t = 0, 0.1, 0.3 s and the end (grey open, green stick, red slip)" 4
    done
    # the close-up views (not in a quick look with CAPDYN_RUN_ARGS: the capture
    # scenarios below still draw theirs)
    [ -n "${CAPDYN_RUN_ARGS:-}" ] || FIGURES_DIR="$OUT" CAPDYN="$CAPDYN" bash plots/capture.sh "$D/$g.h5" > /dev/null
    done_step
done
# ---- Issue 9: TAKO vs Space Gripper, the graspable region (docs/sweep.md) ----
# The same grid for both scenarios (same fingers, object, contact law,
# torque); REGION_X / REGION_Y override it (A:B:N), SWEEP_ARGS adds options
# (e.g. "-j 1"), CAPDYN_RUN_ARGS applies too (and makes the default grid 2x3).
# Positions and areas normalised by the finger length 0.15 m.
REGION_L=0.15
if [ -n "${CAPDYN_RUN_ARGS:-}" ]; then # a quick look: a 2x3 grid of shortened runs
    RX=${REGION_X:--0.006:0.006:2}
    RY=${REGION_Y:-0.07:0.19:3}
else
    RX=${REGION_X:--0.006:0.006:5}
    RY=${REGION_Y:-0.07:0.21:8}
fi
read -r -a SWEEP_EXTRA <<< "${SWEEP_ARGS:-}"
step region "TAKO vs Space Gripper graspable region: two sweeps, maps"
for g in tako space; do
    sc=scenarios/tako_vs_space_region.toml
    [ "$g" = space ] && sc=scenarios/tako_vs_space_region_space.toml
    echo "== region_$g: capdyn sweep $sc (x $RX, y $RY)"
    "$CAPDYN" sweep "$sc" --vary "target.object.position[0]=$RX" --vary "target.object.position[1]=$RY" \
        --until-verdict --length "$REGION_L" -q -o "$D/region_$g.h5" ${RUN_ARGS[@]+"${RUN_ARGS[@]}"} \
        ${SWEEP_EXTRA[@]+"${SWEEP_EXTRA[@]}"}
    "$CAPDYN" sweep --table "$D/region_$g.h5" > "$D/region_$g.dat"
done
# the hand at its initial pose (a 1 ms run of the scenario)
"$CAPDYN" run scenarios/tako_vs_space_region.toml --set simulation.duration=0.001 -q -o "$D/region_pose.h5"
"$CAPDYN" export "$D/region_pose.h5" outline --at 0 > "$D/region_outline.dat"
area_t=$(sed -n 's/^# region .* area //p' "$D/region_tako.dat")
area_s=$(sed -n 's/^# region .* area //p' "$D/region_space.dat")
echo "   region area / L^2: TAKO $area_t, Space Gripper $area_s"
for ext in png svg; do
    for m in verdict peak_fn t_capture; do
        case $m in
            verdict) what="capture verdict" ;;
            peak_fn) what="peak contact force on the object" ;;
            t_capture) what="time to capture" ;;
        esac
        gnuplot -c plots/region.gp "$D/region_tako.dat" "$D/region_space.dat" "$D/region_outline.dat" \
            "$OUT/region_$m.$ext" "$m" "$REGION_L" "TAKO (region area $area_t L^2)" \
            "Space Gripper (region area $area_s L^2)" "Graspable region: $what over the object's initial position"
    done
done

done_step

# ---- Issue 10: capture of a tumbling satellite (docs/capture.md) ----------
for n in capture_handrail_tumbling capture_body_offset capture_too_fast; do
    step "$n" "capture run: close-up views, GIF, histories, force profile"
    FIGURES_DIR="$OUT" CAPDYN="$CAPDYN" bash plots/capture.sh "scenarios/$n.toml" | sed 's/^/   /'
    force "$n" "${n}_force" "$n: contact forces"
    done_step
done
if [ "${CAPTURE_MAP:-0}" = 1 ]; then
    step capture_map "capture-success map (plots/capture_map.sh)"
    FIGURES_DIR="$OUT" CAPDYN="$CAPDYN" bash plots/capture_map.sh
    done_step
fi
# a complete run: its step times are the next run's expectations (not with
# CAPDYN_RUN_ARGS, a shortened run)
[ -z "${CAPDYN_RUN_ARGS:-}" ] && mv "$D/times.new" "$D/times.txt" || rm -f "$D/times.new"

echo "figures written to $OUT/:"
ls -1 "$OUT" | grep -v '^data$' | sed 's/^/  /'
echo "(results and exported columns in $D/)"
