#!/usr/bin/env bash
# TAKO vs Space Gripper graspable region in three physical settings
# (docs/sweep.md, "Does the ordering emerge?"; issue 9). For each setting and
# gripper it runs one `capdyn sweep` and prints the captured / escaped /
# unresolved counts, the normalised region area, and the positions where the
# two grippers' verdicts differ.
#
#   bash bench/region_settings.sh [SETTING ...]   (default: paper heavy small open)
#
#   paper  the scenario files as shipped: cylinder r 0.035 m, 0.3 kg, between
#          fingers 0.1 m apart (x offsets +-6 mm are all the room there is),
#          5 x 8 grid, y 0.07 .. 0.21 m (the fingertips are at 0.17 m)
#   heavy  the same cylinder 100 times heavier (30 kg): a fixture on a large
#          body that the fingers cannot push away; 3 x 6 grid
#   small  a cylinder of radius 0.02 m (0.3 kg): lateral room +-0.02 m;
#          5 x 6 grid, y 0.05 .. 0.15 m
#   open   the hand starts open, base joints at -30 deg against their stops
#          (tips straight): 5 x 5 grid, x -0.04 .. 0.04 m, y 0.10 .. 0.18 m
#          (nearer the palm the open fingers leave less room: at y 0.06 m a
#          cylinder at |x| > 0.023 m would start inside a finger)
#
# Each variant runs up to 8 s (--until-verdict ends decided ones early); -j 1
# by default (JOBS=2 for both cores). About 10-25 min per setting on a quiet
# 2-core machine. Summaries are kept in OUT (default a temporary directory).
set -euo pipefail
cd "$(dirname "$0")/.."
B=${CAPDYN:-build/capdyn}
JOBS=${JOBS:-1}
OUT=${OUT:-$(mktemp -d /tmp/capdyn_region.XXXXXX)}
mkdir -p "$OUT"
[ $# -gt 0 ] || set -- paper heavy small open
for s in "$@"; do
    case $s in
    paper) SET=(); VX=-0.006:0.006:5; VY=0.07:0.21:8 ;;
    heavy) SET=(--set target.object.mass=30 --set 'target.object.inertia=[1.81875e-2,1.81875e-2,1.8375e-2]')
           VX=-0.006:0.006:3; VY=0.07:0.17:6 ;;
    small) SET=(--set target.object.shape.radius=0.02 --set 'target.object.inertia=[1.2e-4,1.2e-4,6e-5]')
           VX=-0.02:0.02:5; VY=0.05:0.15:6 ;;
    open)  SET=(--set 'gripper.finger_joint.q0_deg=[-30.0,0.0]' --set 'gripper.finger_joint.limit_deg=[[-30.0,180.0],[0.0,180.0]]')
           VX=-0.04:0.04:5; VY=0.10:0.18:5 ;;
    *) echo "unknown setting '$s' (expected paper, heavy, small or open)" >&2; exit 2 ;;
    esac
    for g in tako_vs_space_region tako_vs_space_region_space; do
        "$B" sweep "scenarios/$g.toml" --until-verdict --length 0.15 -j "$JOBS" -q -o "$OUT/${s}_$g.h5" \
            --set simulation.duration=8 ${SET[@]+"${SET[@]}"} \
            --vary "target.object.position[0]=$VX" --vary "target.object.position[1]=$VY"
    done
    echo "== setting $s (summaries in $OUT)"
    for g in tako_vs_space_region tako_vs_space_region_space; do
        "$B" sweep --table "$OUT/${s}_$g.h5" | awk -v g="$g" '
            /^# region/ { area = $NF }
            !/^#/ { n[$6]++ }
            END { printf "  %-28s captured %2d  escaped %2d  unresolved %2d  caged %2d  area %.4f L^2\n",
                         g, n[1], n[2], n[0], n[3], area }'
    done
    paste <("$B" sweep --table "$OUT/${s}_tako_vs_space_region.h5" | grep -v '^#') \
          <("$B" sweep --table "$OUT/${s}_tako_vs_space_region_space.h5" | grep -v '^#') |
        awk 'BEGIN { split("unresolved captured escaped caged", v, " ") }
             { w = NF / 2; if ($6 != $(w + 6)) printf "  differs at x = %s, y = %s: TAKO %s, Space %s\n",
                                                     $2, $3, v[$6 + 1], v[$(w + 6) + 1] }'
done
