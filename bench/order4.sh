#!/usr/bin/env bash
# ros34pw2 (order 3, W-method, Jacobian kept up to 20 steps) against rodas4
# (order 4, Rosenbrock, finite-difference Jacobian renewed every step) on the
# Fig. 5 grasp and the capture twin at rtol 1e-6 and 1e-8 (issue 18 item 2).
# Runs are interleaved (repetition, scene, rtol, stepper) so both steppers see
# the same load; per cell: steps, rhs evaluations, Jacobians (the same in every
# repetition), wall time min and median over REPS, RTF at the median, and the
# largest difference of the final base positions of every system from an
# rk8pd run at rtol 1e-12 (the tight reference).
#
# Usage: bash bench/order4.sh    (REPS=3 BIN=build/capdyn OUT=bench/results/DATE-order4.txt)
set -u
cd "$(dirname "$0")/.."
BIN=${BIN:-build/capdyn}
REPS=${REPS:-3}
OUT=${OUT:-bench/results/$(date -u +%Y-%m-%d)-order4.txt}
[ -x "$BIN" ] || { echo "build $BIN first (make)" >&2; exit 2; }
command -v h5dump > /dev/null || { echo "h5dump (hdf5-tools) is needed" >&2; exit 2; }
mkdir -p "$(dirname "$OUT")"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
scenes=("fig5:scenarios/paper_fig5_envelope_grasp.toml" "twin:bench/capture_twin.toml")
steppers=(ros34pw2 rodas4)
rtols=(1e-6 1e-8)

field() { sed -n "s/^$2 *//p" "$1" | head -n 1; }

final_pos() { # H5 -> the base positions of every system at the last sample, one line
  local f=$1 s
  for s in $(h5ls "$f/systems" | awk '{print $1}'); do
    h5dump -y -w 0 -A 0 -m %.17g -d "/systems/$s/base_pos" "$f" | sed -n '/DATA {/,/}/p' | grep -v '[{}]' |
      tr ',' '\n' | tr -d ' ' | grep . | tail -n 3
  done | tr '\n' ' '
}

run() { # TAG SCENE STEPPER RTOL
  "$BIN" run "$2" --set "simulation.integrator=\"$3\"" --set "simulation.rtol=$4" --set simulation.h_max=0.05 \
    -o "$tmp/$1.h5" > "$tmp/$1.log" 2>&1 || { echo "run failed: $1" >&2; cat "$tmp/$1.log" >&2; }
  final_pos "$tmp/$1.h5" > "$tmp/$1.pos"
  rm -f "$tmp/$1.h5"
}

for sc in "${scenes[@]}"; do
  run "${sc%%:*}-ref" "${sc#*:}" rk8pd 1e-12
done
for r in $(seq 1 "$REPS"); do
  for sc in "${scenes[@]}"; do
    for tol in "${rtols[@]}"; do
      for st in "${steppers[@]}"; do run "${sc%%:*}-$tol-$st-$r" "${sc#*:}" "$st" "$tol"; done
    done
  done
done

{
  echo "# bash bench/order4.sh (REPS=$REPS), $(date -u +%FT%TZ), capdyn $(git rev-parse --short HEAD 2>/dev/null)"
  echo "# load average at the end: $(cut -d' ' -f1-3 /proc/loadavg); runs interleaved; h_max 0.05 s"
  echo "# reference: rk8pd rtol 1e-12; dpos = max |final base position - reference| over the systems [m]"
  printf '# scene\trtol\tstepper\tsteps\trejected\trhs\tjacobians\twall_min_s\twall_median_s\tRTF_median\tdpos_m\tstatus\n'
  for sc in "${scenes[@]}"; do
    n=${sc%%:*}
    for tol in "${rtols[@]}"; do
      for st in "${steppers[@]}"; do
        log="$tmp/$n-$tol-$st-1.log"
        integ=$(field "$log" integrator)
        steps=$(echo "$integ" | sed -n 's/.*: \([0-9]*\) steps.*/\1/p')
        rej=$(echo "$integ" | sed -n 's/.*steps (\([0-9]*\) rejected).*/\1/p')
        rhs=$(echo "$integ" | sed -n 's/.* \([0-9]*\) rhs evaluations.*/\1/p')
        jac=$(echo "$integ" | sed -n 's/.* \([0-9]*\) Jacobians.*/\1/p')
        dur=$(field "$log" status | sed -n 's/.*t = \([0-9.e+-]*\) s.*/\1/p')
        walls=$(for r in $(seq 1 "$REPS"); do field "$tmp/$n-$tol-$st-$r.log" "wall time" | sed 's/ s$//'; done | sort -g)
        wmin=$(echo "$walls" | head -n 1)
        wmed=$(echo "$walls" | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}')
        rtf=$(awk -v d="${dur:-0}" -v w="${wmed:-0}" 'BEGIN { if (w > 0) printf "%.3g", d / w; else print "-" }')
        dpos=$(paste <(tr ' ' '\n' < "$tmp/$n-$tol-$st-1.pos") <(tr ' ' '\n' < "$tmp/$n-ref.pos") |
          awk 'NF == 2 { d = $1 - $2; if (d < 0) d = -d; if (d > m) m = d } END { printf "%.2e", m }')
        printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$n" "$tol" "$st" "$steps" "$rej" "$rhs" "${jac:-0}" \
          "$wmin" "$wmed" "$rtf" "$dpos" "$(field "$log" status)"
      done
    done
  done
} | tee "$OUT"
echo "written: $OUT" >&2
