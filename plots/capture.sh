#!/usr/bin/env bash
# The capture scenarios (docs/capture.md): runs them with build/capdyn and
# renders, into figures/ (git-ignored):
#   NAME_snapshots.png   3-D snapshots (gnuplot splot) through the capture: the
#                        chaser's base and arm (joint origins), the gripper's
#                        check points coloured by contact mode, the target box
#                        and its handrail bar
#   NAME_history.png     time histories: contact forces, arm joint torques,
#                        base attitude, linear and angular momentum of the
#                        chaser, the target and the whole
#   NAME.gif             an animated GIF of the 3-D view
#
#   plots/capture.sh [NAME ...]      (default: the three capture_* scenarios)
#
# Environment: CAPDYN (default build/capdyn), FIGURES_DIR (default figures),
# CAPDYN_RUN_ARGS (extra `capdyn run` arguments). Needs gnuplot and h5dump
# (hdf5-tools), both installed by scripts/install-deps.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
CAPDYN=${CAPDYN:-build/capdyn}
OUT=${FIGURES_DIR:-figures}
D="$OUT/data"
read -r -a RUN_ARGS <<< "${CAPDYN_RUN_ARGS:-}"
for tool in gnuplot h5dump; do
    command -v $tool > /dev/null || { echo "capture.sh: $tool not found; run 'make deps'" >&2; exit 1; }
done
[ -x "$CAPDYN" ] || { echo "capture.sh: $CAPDYN not found; run 'make' first" >&2; exit 1; }
mkdir -p "$D"
names=("$@")
[ ${#names[@]} -gt 0 ] || names=(capture_handrail_tumbling capture_body_offset capture_too_fast)

# the target's box half extents and handrail bar (centre, target frame; the
# bar runs along the target's z, 0.3 m long) of each scenario
# (capture_docking_fixture: its cylinder, drawn as a bar; the solar-panel
# targets' wings are not drawn)
bar_of() { case "$1" in capture_body_offset) echo "-0.95 0.25 0.2" ;; capture_docking_fixture) echo "-0.95 -0.3 0.2" ;; *) echo "-0.95 0.0 0.2" ;; esac; }

for n in "${names[@]}"; do
    h5="$D/$n.h5"
    echo "== $n: capdyn run scenarios/$n.toml"
    "$CAPDYN" run "scenarios/$n.toml" -o "$h5" --quiet ${RUN_ARGS[@]+"${RUN_ARGS[@]}"}
    "$CAPDYN" export "$h5" time > "$D/${n}_time.dat"
    "$CAPDYN" export "$h5" contacts > "$D/${n}_contacts.dat"
    "$CAPDYN" export "$h5" system chaser > "$D/${n}_chaser.dat"
    "$CAPDYN" export "$h5" system target > "$D/${n}_target.dat"
    for s in chaser target; do "$CAPDYN" export "$h5" diagnostics $s > "$D/${n}_diag_$s.dat"; done
    "$CAPDYN" export "$h5" diagnostics > "$D/${n}_diag_all.dat"
    # arm joint torques (the controller's, /systems/chaser/tau_applied) and
    # the chaser's joint origins (/systems/chaser/body_x), one row per sample
    h5dump -d /systems/chaser/tau_applied -y -w 0 -o "$D/${n}_tau.raw" "$h5" > /dev/null
    h5dump -d /systems/chaser/body_x -y -w 0 -o "$D/${n}_bx.raw" "$h5" > /dev/null
    nb=$(h5dump -H -d /systems/chaser/body_x "$h5" | sed -n 's/.*SIMPLE { ( [0-9]*, \([0-9]*\), 3 ).*/\1/p')
    grep -v '^#' "$D/${n}_time.dat" | paste -d' ' - <(grep -v '^ *$' "$D/${n}_tau.raw" | tr -d ',') > "$D/${n}_tau.dat"
    ns=$(grep -vc '^#' "$D/${n}_time.dat")
    # frames: 4 snapshots and 60 animation frames, as sample indices
    snaps=$(awk -v n="$ns" 'BEGIN { for (i = 0; i < 4; i++) printf "%d ", int(i * (n - 1) / 3 + 0.5) }')
    anim=$(awk -v n="$ns" 'BEGIN { for (i = 0; i < 60; i++) printf "%d ", int(i * (n - 1) / 59 + 0.5) }')
    for kind in snaps anim; do
        idx=${!kind}
        times=$(grep -v '^#' "$D/${n}_time.dat" | awk -v l="$idx" 'BEGIN { split(l, a, " "); for (k in a) w[a[k]] = 1 } (NR - 1) in w { printf "%s%s", s, $1; s = "," }')
        "$CAPDYN" export "$h5" checkpoints --at "$times" > "$D/${n}_${kind}_cps.dat"
        # arm polylines, the target's box edges and bar per frame (gnuplot index)
        read -r bx by bz <<< "$(bar_of "$n")"
        grep -v '^ *$' "$D/${n}_bx.raw" | tr -d ',' | awk -v nb="$nb" -v l="$idx" -v bx="$bx" -v by="$by" -v bz="$bz" \
            -v tg="$D/${n}_target.dat" -v ch="$D/${n}_chaser.dat" '
            function load(file, A,   i, line) { i = 0; while ((getline line < file) > 0) if (line !~ /^#/) A[i++] = line }
            BEGIN { split(l, a, " "); for (k in a) { w[a[k]] = 1; ord[k] = a[k] }; load(tg, T); load(ch, C) }
            { s = int((NR - 1) / nb); b = (NR - 1) % nb; if (s in w) { X[s, b] = $1; Y[s, b] = $2; Z[s, b] = $3 } }
            function pose(line,   f) { split(line, f, " "); cx = f[2]; cy = f[3]; cz = f[4]; qw = f[5]; qx = f[6]; qy = f[7]; qz = f[8] }
            function rot(px, py, pz) { # body -> world by the quaternion (w, x, y, z)
                rx = (1 - 2*(qy*qy + qz*qz))*px + 2*(qx*qy - qw*qz)*py + 2*(qx*qz + qw*qy)*pz
                ry = 2*(qx*qy + qw*qz)*px + (1 - 2*(qx*qx + qz*qz))*py + 2*(qy*qz - qw*qx)*pz
                rz = 2*(qx*qz - qw*qy)*px + 2*(qy*qz + qw*qx)*py + (1 - 2*(qx*qx + qy*qy))*pz }
            function seg(x1, y1, z1, x2, y2, z2,   ax, ay, az) { # one line: start and displacement (gnuplot vectors)
                rot(x1, y1, z1); ax = cx + rx; ay = cy + ry; az = cz + rz; rot(x2, y2, z2)
                print ax, ay, az, cx + rx - ax, cy + ry - ay, cz + rz - az }
            function box(hx, hy, hz,   e, c, u, v) { # the 12 edges
                for (e = 0; e < 12; e++) {
                    c = int(e / 4); u = (e % 2) ? 1 : -1; v = (int(e / 2) % 2) ? 1 : -1
                    if (c == 0) seg(-hx, u*hy, v*hz, hx, u*hy, v*hz)
                    if (c == 1) seg(u*hx, -hy, v*hz, u*hx, hy, v*hz)
                    if (c == 2) seg(u*hx, v*hy, -hz, u*hx, v*hy, hz)
                } }
            END {
                for (k = 1; k in ord; k++) {
                    s = ord[k]
                    for (b = 0; b < 7; b++) print X[s, b], Y[s, b], Z[s, b]   # base CoM and the arm joints
                    print ""
                    pose(C[s]); box(1.0, 1.0, 1.0)                           # the chaser bus (2 m cube)
                    pose(T[s]); box(0.8, 0.7, 0.6)                           # the target (1.6 x 1.4 x 1.2 m)
                    seg(bx, by, bz - 0.15, bx, by, bz + 0.15)                # its handrail bar
                    print ""; print ""
                }
            }' > "$D/${n}_${kind}_geom.dat"
    done
    title=$(sed -n 's/^title = "\(.*\)"/\1/p' "scenarios/$n.toml")
    gnuplot -c plots/capture_snapshots.gp "$D/${n}_snaps_geom.dat" "$D/${n}_snaps_cps.dat" "$OUT/${n}_snapshots.png" "$title"
    gnuplot -c plots/capture_history.gp "$D/$n" "$OUT/${n}_history.png" "$title"
    gnuplot -c plots/capture_animation.gp "$D/${n}_anim_geom.dat" "$D/${n}_anim_cps.dat" "$OUT/$n.gif" "$title"
    echo "   $OUT/${n}_snapshots.png $OUT/${n}_history.png $OUT/$n.gif"
done
