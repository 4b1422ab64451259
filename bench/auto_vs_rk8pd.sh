#!/usr/bin/env bash
# Every shipped scenario with its own settings, once with
# simulation.integrator = "rk8pd" (the default before issue 18, with which the
# scenarios were tuned) and once with "auto" (the default since; item 3): verdict, capture time,
# physical events, evaluations, steps, wall time and RTF side by side, run
# interleaved (rk8pd then auto for each scenario) so both see the same load.
# The verdicts must agree; the capture times within the sample interval or
# the dwell (docs/performance.md, "auto against rk8pd on every scenario").
#
# Usage: bash bench/auto_vs_rk8pd.sh [SCENARIO.toml ...]   (default: scenarios/*.toml)
#        BIN=build/capdyn OUT=bench/results/DATE-auto.txt
set -u
cd "$(dirname "$0")/.."
BIN=${BIN:-build/capdyn}
OUT=${OUT:-bench/results/$(date -u +%Y-%m-%d)-auto-vs-rk8pd.txt}
[ -x "$BIN" ] || { echo "build $BIN first (make)" >&2; exit 2; }
mkdir -p "$(dirname "$OUT")"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
list=("$@")
[ ${#list[@]} -gt 0 ] || list=(scenarios/*.toml)

field() { # FILE KEY -> the rest of the summary line that starts with KEY
  sed -n "s/^$2 *//p" "$1" | head -n 1
}

summary() { # LOG -> verdict | events (physical) | evals | steps | wall | rtf
  local log=$1 verdict ev evals steps wall dur
  verdict=$(field "$log" capture | sed 's/^\(captured\|escaped\|unresolved\|caged\)\( at t = [0-9.e+-]* s\)\?.*/\1\2/')
  [ -n "$verdict" ] || verdict=$(field "$log" status)
  ev=$(field "$log" events)
  evals=$(field "$log" integrator | sed -n 's/.* \([0-9]*\) rhs evaluations.*/\1/p')
  steps=$(field "$log" integrator | sed -n 's/.*: \([0-9]*\) steps.*/\1/p')
  wall=$(field "$log" "wall time" | sed 's/ s$//')
  dur=$(field "$log" status | sed -n 's/.*t = \([0-9.e+-]*\) s.*/\1/p')
  rtf=$(awk -v d="${dur:-0}" -v w="${wall:-0}" 'BEGIN { if (w > 0) printf "%.3g", d / w; else print "-" }')
  printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$verdict" "$ev" "$evals" "$steps" "$wall" "$rtf"
}

{
  echo "# capdyn run of every scenario with its own settings: simulation.integrator=\"rk8pd\" vs \"auto\"; $(date -u +%FT%TZ)"
  echo "# load average at start: $(cut -d' ' -f1-3 /proc/loadavg)"
  printf '# scenario\tstepper\tverdict/status\tevents\tevals\tsteps\twall_s\tRTF\n'
  for s in "${list[@]}"; do
    name=$(basename "$s" .toml)
    for st in rk8pd auto; do
      set_arg=(--set "simulation.integrator=\"$st\"")
      "$BIN" run "$s" "${set_arg[@]}" -o "$tmp/$name-$st.h5" > "$tmp/$name-$st.log" 2>&1
      printf '%s\t%s\t%s\n' "$name" "$st" "$(summary "$tmp/$name-$st.log")"
    done
  done
} | tee "$OUT"
echo "written: $OUT" >&2
