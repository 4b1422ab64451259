#!/usr/bin/env bash
# The capture scenarios' report (docs/capture.md, issue 10): for each one,
# the verdict, wall time, real-time factor (simulated / wall seconds) and the
# momentum error of the whole system, as run (attitude control on: the wheel
# torque changes the angular momentum) and with attitude control off (both
# momenta conserved).
#
#   bench/capture_report.sh            (CAPDYN=build/capdyn, OUT=/tmp;
#                                       REPORT_ONLY=1 re-reads the last runs' summaries;
#                                       CAPTURE_SCENARIOS="NAME ..." other scenarios)
set -euo pipefail
cd "$(dirname "$0")/.."
CAPDYN=${CAPDYN:-build/capdyn}
OUT=${OUT:-/tmp}
for n in ${CAPTURE_SCENARIOS:-capture_handrail_tumbling capture_body_offset capture_too_fast}; do
    for att in on off; do
        args=()
        [ $att = off ] && args=(--set control.attitude.on=false)
        h5="$OUT/${n}_att_$att.h5"
        [ -n "${REPORT_ONLY:-}" ] || "$CAPDYN" run "scenarios/$n.toml" -o "$h5" ${args[@]+"${args[@]}"} > "$OUT/${n}_att_$att.txt"
        awk -v n="$n" -v att="$att" '
            /^capture / { verdict = $2 }
            /^wall time/ { wall = $3 }
            /^status/ { for (i = 1; i <= NF; i++) if ($i == "t" && $(i+1) == "=") dur = $(i+2) }
            function num(line, unit,   a, v, r, q) { # "max |X - X(0)| = V unit (R relative to ...)"
                split(line, a, "= "); split(a[2], v, " "); r = line; sub(/.* \(/, "", r); split(r, q, " ")
                return v[1] " " unit " (" q[1] " rel.)" }
            /linear: max/ { lin = num($0, "kg m/s") }
            /angular about the CoM: max/ { ang = num($0, "kg m^2/s") }
            END { printf "%-28s attitude %-3s  %-10s wall %7.2f s  RTF %6.3f  |dP| %s  |dL| %s\n", n, att, verdict, wall, dur / wall, lin, ang }' \
            "$OUT/${n}_att_$att.txt"
    done
done
