#!/usr/bin/env bash
# Capture views of any run: renders into figures/ (git-ignored), from what
# the results file holds (bodies, shapes, slots, names; docs/figures.md):
#   NAME_views.png  four instants (start, first contact with the target,
#                       half way to the end, the end): the whole scene (world
#                       frame, top row) and a close-up of the hand and the
#                       grasped feature in a frame fixed to the target (bottom
#                       row, a cube about the hand at the instant with the
#                       most contacts); one set of axes per row, the same for all four
#                       panels; check points coloured by contact mode; contact
#                       forces on the target as arrows, their scale in the legend
#   NAME_closeup.gif    the close-up animated (60 frames, gnuplot gif animate)
#   NAME_history.png    time histories: forces on the target and between the
#                       bodies of one system (finger on finger), joint torques
#                       of the system with the most joints, the rotation of
#                       every free-floating system, momenta
#
#   plots/capture.sh RUN [RUN ...]
#     RUN: a results file (NAME.h5) or a scenario (NAME.toml: run first, into
#     figures/data/NAME.h5)
#
# The target is the body that check points of another system touch most
# often (or, if nothing ever touches, that most slots of another system point
# at); the hand is the set of bodies whose check points have slots against it.
# Environment: CAPDYN (default build/capdyn), FIGURES_DIR (default figures),
# CAPDYN_RUN_ARGS (extra `capdyn run` arguments). Needs gnuplot and h5dump.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
CAPDYN=${CAPDYN:-$ROOT/build/capdyn}
OUT=${FIGURES_DIR:-figures}
D="$OUT/data"
read -r -a RUN_ARGS <<< "${CAPDYN_RUN_ARGS:-}"
for tool in gnuplot h5dump; do
    command -v $tool > /dev/null || { echo "capture.sh: $tool not found; run 'make deps'" >&2; exit 1; }
done
[ -x "$CAPDYN" ] || { echo "capture.sh: $CAPDYN not found; run 'make' first" >&2; exit 1; }
[ $# -gt 0 ] || { echo "usage: plots/capture.sh RESULTS.h5|SCENARIO.toml ..." >&2; exit 2; }
mkdir -p "$D"

for run in "$@"; do
    case "$run" in
        *.h5) n=$(basename "$run" .h5); h5=$run ;;
        *.toml) n=$(basename "$run" .toml); h5="$D/$n.h5"
                echo "   capdyn run $run"
                "$CAPDYN" run "$run" -o "$h5" --quiet ${RUN_ARGS[@]+"${RUN_ARGS[@]}"} ;;
        *) echo "capture.sh: '$run' is neither a results file (.h5) nor a scenario (.toml)" >&2; exit 2 ;;
    esac
    p="$D/$n"
    title=$("$CAPDYN" info "$h5" | sed -n 's/^title  *//p' | head -1)
    "$CAPDYN" export "$h5" time > "${p}_time.dat"
    "$CAPDYN" export "$h5" slots > "${p}_slots.dat"
    "$CAPDYN" export "$h5" forces --every 1 > "${p}_forces_all.dat"
    # the target: the body most often touched by another system's check points
    sysof='function sys(b) { sub(/\/.*/, "", b); return b }'
    target=$(awk '!/^#/ && $11 == 1 { c[$13]++ } END { for (b in c) if (c[b] > m) { m = c[b]; t = b }; print t }' "${p}_forces_all.dat")
    [ -n "$target" ] || target=$(awk "$sysof"' !/^#/ && sys($3) != sys($4) { c[$4]++ } END { for (b in c) if (c[b] > m) { m = c[b]; t = b }; print t }' "${p}_slots.dat")
    if [ -z "$target" ]; then echo "   $n: no slot between two systems: no capture views"; continue; fi
    # check points of the hand: those with a slot against the target
    awk -v t="$target" "$sysof"' !/^#/ && $4 == t && sys($3) != sys($4) { print $2 }' "${p}_slots.dat" | sort -un > "${p}_handcps.txt"
    # instants: start, first contact with the target, half way from there to the end, the end
    read -r t0 t1 t3 <<< "$(awk '!/^#/ { if (n == 0) a = $1; b = $1; n++ } END { print a, b, b }' "${p}_time.dat")"
    tc=$(awk '!/^#/ && $11 == 1 { print $14; exit }' "${p}_forces_all.dat")
    [ -n "$tc" ] || tc=$(awk -v a="$t0" -v b="$t3" 'BEGIN { print a + (b - a) / 3 }')
    # in contact from the start (an initial overlap): a tenth of the run instead
    tc=$(awk -v a="$t0" -v b="$t3" -v c="$tc" 'BEGIN { print (c > a ? c : a + (b - a) / 10) }')
    at=$(awk -v a="$t0" -v c="$tc" -v b="$t3" 'BEGIN { printf "%.9g,%.9g,%.9g,%.9g", a, c, c + (b - c) / 2, b }')
    "$CAPDYN" export "$h5" edges --at "$at" > "${p}_w_edges.dat"
    "$CAPDYN" export "$h5" checkpoints --at "$at" > "${p}_w_cps.dat"
    "$CAPDYN" export "$h5" edges --at "$at" --frame "$target" > "${p}_c_edges.dat"
    "$CAPDYN" export "$h5" checkpoints --at "$at" --frame "$target" > "${p}_c_cps.dat"
    "$CAPDYN" export "$h5" forces --at "$at" --frame "$target" > "${p}_c_forces.dat"
    "$CAPDYN" export "$h5" edges --frames 60 --frame "$target" > "${p}_a_edges.dat"
    "$CAPDYN" export "$h5" checkpoints --frames 60 --frame "$target" > "${p}_a_cps.dat"
    "$CAPDYN" export "$h5" forces --frames 60 --frame "$target" > "${p}_a_forces.dat"
    # axes: the whole scene over the four instants; the close-up: a cube about
    # the hand's check points (in the target's frame) at one instant
    wr=$(awk '!/^#/ && NF >= 3 && $1 == $1 + 0 { for (k = 1; k <= 3; k++) { if (!(k in lo) || $k < lo[k]) lo[k] = $k; if (!(k in hi) || $k > hi[k]) hi[k] = $k } }
              END { for (k = 1; k <= 3; k++) { m = 0.05 * (hi[k] - lo[k]) + 1e-3; printf "%.6g %.6g ", lo[k] - m, hi[k] + m } }' \
              "${p}_w_edges.dat" <(awk '!/^#/ && NF { print $5, $6, $7 }' "${p}_w_cps.dat"))
    # the close-up's instant: of the four, the one with the most contacts on the
    # target (the later one if tied: the closed grasp; an escape: its first contact)
    fc=$(awk '/^# frame/ { f++ } !/^#/ && NF && $11 == 1 { c[f]++ } END { b = 4; for (f = 4; f >= 1; f--) if (c[f] > c[b]) b = f; print b }' "${p}_c_forces.dat")
    cr=$(awk -v F="${p}_handcps.txt" -v fc="$fc" 'BEGIN { while ((getline l < F) > 0) h[l] = 1 }
              /^# frame/ { f++; go = f == fc }
              go && !/^#/ && NF && ($9 in h) { P[++np, 1] = $5; P[np, 2] = $6; P[np, 3] = $7 }
              END { for (i = 1; i <= np; i++) for (k = 1; k <= 3; k++) { if (i == 1 || P[i, k] < lo[k]) lo[k] = P[i, k]; if (i == 1 || P[i, k] > hi[k]) hi[k] = P[i, k] }
                    s = 0; for (k = 1; k <= 3; k++) if (hi[k] - lo[k] > s) s = hi[k] - lo[k]
                    hh = 0.7 * s; if (hh < 0.02) hh = 0.02
                    for (k = 1; k <= 3; k++) { c = 0.5 * (lo[k] + hi[k]); printf "%.6g %.6g ", c - hh, c + hh } }' "${p}_c_cps.dat")
    # force arrows: a reference length (1, 2, 5 x 10^k m, about an eighth of
    # the close-up's width) for a reference force (the same steps, about the
    # 95th percentile of the forces on the target in the animation)
    read -r fref lref <<< "$(awk -v cr="$cr" '
        function nice(x,   e, f) { if (x <= 0) return 1; e = 10 ^ int(log(x) / log(10) - (x < 1)); f = x / e; return (f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10) * e }
        !/^#/ && NF && $11 == 1 && $7 > 0 { v[++n] = $7 }
        END { split(cr, r, " "); h = (r[2] - r[1]) / 2
              if (n == 0) { print 1, nice(0.25 * h); exit }
              for (i = 2; i <= n; i++) { x = v[i]; for (j = i - 1; j >= 1 && v[j] > x; j--) v[j + 1] = v[j]; v[j + 1] = x }
              f95 = v[int(0.95 * (n - 1)) + 1]; print nice(f95), nice(0.25 * h) }' "${p}_a_forces.dat")"
    # the close-up's lines clipped to its cube (splot does not clip)
    for f in c a; do
        awk -v box="$cr" -f "$ROOT/plots/clip_edges.awk" "${p}_${f}_edges.dat" > "${p}_${f}_edges_clip.dat"
    done
    gnuplot -c "$ROOT/plots/capture_snapshots.gp" "$p" "$OUT/${n}_views.png" "$title" "$wr" "$cr" "$fref" "$lref" "$target"
    gnuplot -c "$ROOT/plots/capture_animation.gp" "$p" "$OUT/${n}_closeup.gif" "$title" "$cr" "$fref" "$lref" "$target"
    # histories: forces on the target and within a system (slots classified by their body pair)
    "$CAPDYN" export "$h5" contacts > "${p}_contacts.dat"
    awk -v S="${p}_slots.dat" "$sysof"' BEGIN { while ((getline l < S) > 0) if (l !~ /^#/) { split(l, f, " "); btw[f[1]] = sys(f[3]) != sys(f[4]) } }
        /^# t / { for (k = 7; k <= NF; k += 3) { s = $k; sub(/^fn\./, "", s); slot[k - 1] = s }; next }
        /^#/ { next }
        { a = 0; b = 0; ns = 0; nl = 0
          for (k = 6; k + 2 <= NF; k += 3) { if (btw[slot[k]]) { a += $k; if ($(k + 2) == 1) ns++; if ($(k + 2) == 2) nl++ } else b += $k }
          print $1, a, b, ns, nl }' "${p}_contacts.dat" > "${p}_fsplit.dat"
    # the system with the most joints: its joint torques (all sources, /systems/NAME/tau)
    arm=$(for g in $(h5ls "$h5/systems" | awk '{ print $1 }'); do
              nj=$(h5dump -H -d "/systems/$g/tau" "$h5" 2>/dev/null | sed -n 's/.*SIMPLE { ( [0-9]*, \([0-9]*\) ).*/\1/p' | head -1)
              echo "${nj:-0} $g"; done | sort -rn | awk 'NR == 1 && $1 > 0 { print $2 }')
    if [ -n "$arm" ]; then
        h5dump -d "/systems/$arm/tau" -y -w 0 -o "${p}_tau.raw" "$h5" > /dev/null
        grep -v '^#' "${p}_time.dat" | paste -d' ' - <(grep -v '^ *$' "${p}_tau.raw" | tr -d ',') > "${p}_tau.dat"
    else
        : > "${p}_tau.dat"
    fi
    # every free-floating system: rotation from its attitude at t = 0 [deg], and its diagnostics
    free=""
    for g in $(h5ls "$h5/systems" | awk '{ print $1 }'); do
        "$CAPDYN" export "$h5" system "$g" > "${p}_sys_$g.dat" 2>/dev/null || continue
        grep -q 'free-floating' "${p}_sys_$g.dat" || continue
        free="$free $g"
        awk '!/^#/ { if (!n++) { a = $5; b = $6; c = $7; d = $8 }; x = a*$5 + b*$6 + c*$7 + d*$8; x = x < 0 ? -x : x; x = x < 1 ? x : 1
                     print $1, 2 * atan2(sqrt(1 - x*x), x) * 45 / atan2(1, 1) }' "${p}_sys_$g.dat" > "${p}_rot_$g.dat"
        "$CAPDYN" export "$h5" diagnostics "$g" > "${p}_diag_$g.dat"
    done
    "$CAPDYN" export "$h5" diagnostics > "${p}_diag_all.dat"
    gnuplot -c "$ROOT/plots/capture_history.gp" "$p" "$OUT/${n}_history.png" "$title" "$target" "${arm:--}" "${free# }"
    echo "   $OUT/${n}_views.png $OUT/${n}_closeup.gif $OUT/${n}_history.png (target: $target)"
done
