#!/usr/bin/env bash
# The W6S4OS trial of docs/performance.md section 19: an order-4 W-method
# (6 stages) with an embedded order-3 estimate (bench/trials/w6s4_embedded.py)
# in place of ROS34PW2, under several Jacobian policies, against ROS34PW2 as
# shipped. The trial lives in bench/trials/w6s4.patch (build-time flags only,
# not in the shipped source); this script applies it in a temporary worktree of
# HEAD, builds one capdyn per policy, and runs each on the grasp twin setting
# (rtol 1e-6 and 1e-8) and the capture twin, interleaved, REPS times.
# Per cell: the summary's integrator line (steps, rejections, evaluations,
# Jacobians: the same in every repetition) and the CPU time, min / median.
#
# Usage: bash bench/trials/w6s4.sh   (REPS=3 OUT=bench/results/DATE-w6s4.txt)
set -u
cd "$(dirname "$0")/../.."
ROOT=$PWD
REPS=${REPS:-3}
OUT=${OUT:-bench/results/$(date -u +%Y-%m-%d)-w6s4.txt}
case "$OUT" in /*) ;; *) OUT="$ROOT/$OUT" ;; esac
mkdir -p "$(dirname "$OUT")"
WT=$(mktemp -d)
tmp=$(mktemp -d)
trap 'git -C "$ROOT" worktree remove --force "$WT" > /dev/null 2>&1; rm -rf "$WT" "$tmp"' EXIT
git worktree add -f --detach "$WT" HEAD > /dev/null 2>&1 || { echo "git worktree add failed" >&2; exit 2; }
git -C "$WT" apply "$ROOT/bench/trials/w6s4.patch" || { echo "the patch does not apply to HEAD" >&2; exit 2; }

# name|build flags|run-time settings
variants=(
  "ros34pw2 (shipped)||"
  "w6s4, model J kept 20 steps|-DCD_TRIAL_W6S4=1|"
  "w6s4, difference J kept 20 steps|-DCD_TRIAL_W6S4=1|simulation.jacobian=\"fd\""
  "w6s4, difference J every step|-DCD_TRIAL_W6S4=1 -DCD_TRIAL_W6S4_EXACT=1|"
  "w6s4, model J every step|-DCD_TRIAL_W6S4=1 -DCD_ROSW_JAC_AGE=1|"
  "w6s4, model J every step + difference correction every 20|-DCD_TRIAL_W6S4=1 -DCD_ROSW_JAC_AGE=1 -DCD_TRIAL_CORR=20|"
  "w6s4, model J every step + difference correction every 50|-DCD_TRIAL_W6S4=1 -DCD_ROSW_JAC_AGE=1 -DCD_TRIAL_CORR=50|"
  "w6s4, model J kept 4 steps + difference correction every 50|-DCD_TRIAL_W6S4=1 -DCD_ROSW_JAC_AGE=4 -DCD_TRIAL_CORR=50|"
)
scenes=(
  "grasp twin setting, rtol 1e-6|scenarios/paper_fig5_envelope_grasp.toml|simulation.rtol=1e-6 simulation.duration=12 simulation.h_max=0.05"
  "grasp twin setting, rtol 1e-8|scenarios/paper_fig5_envelope_grasp.toml|simulation.rtol=1e-8 simulation.duration=12 simulation.h_max=0.05"
  "capture twin|bench/capture_twin.toml|simulation.h_max=0.05"
)
declare -A bin
for v in "${!variants[@]}"; do
  IFS='|' read -r name flags _ <<< "${variants[$v]}"
  b="$WT/build-v$v"
  echo "building $name" >&2
  make -C "$WT" -j2 BUILD="build-v$v" EXTRA_CFLAGS="$flags" "build-v$v/capdyn" > "$tmp/build$v.log" 2>&1 ||
    { tail -n 20 "$tmp/build$v.log" >&2; exit 1; }
  bin[$v]=$b/capdyn
done
for r in $(seq 1 "$REPS"); do
  echo "repetition $r of $REPS" >&2
  for s in "${!scenes[@]}"; do
    IFS='|' read -r _ file sets <<< "${scenes[$s]}"
    for v in "${!variants[@]}"; do
      IFS='|' read -r _ _ rsets <<< "${variants[$v]}"
      args=(--set 'simulation.integrator="ros34pw2"')
      for kv in $sets $rsets; do args+=(--set "$kv"); done
      /usr/bin/time -f '%U %S' -o "$tmp/t" "${bin[$v]}" run "$ROOT/$file" "${args[@]}" -o "$tmp/r.h5" > "$tmp/log" 2>&1 ||
        { echo "run failed: $v $s" >&2; tail -n 5 "$tmp/log" >&2; }
      grep '^integrator ' "$tmp/log" | sed 's/^integrator  *//' > "$tmp/line.$s.$v"
      awk '{print $1 + $2}' "$tmp/t" >> "$tmp/cpu.$s.$v"
    done
  done
done
{
  echo "# bash bench/trials/w6s4.sh, REPS=$REPS, HEAD $(git rev-parse --short HEAD), $(date -u +%Y-%m-%dT%H:%MZ)"
  echo "# load average at the end: $(cut -d' ' -f1-3 /proc/loadavg)"
  for s in "${!scenes[@]}"; do
    IFS='|' read -r sname _ _ <<< "${scenes[$s]}"
    echo
    echo "## $sname"
    for v in "${!variants[@]}"; do
      IFS='|' read -r name _ _ <<< "${variants[$v]}"
      cpu=$(sort -g "$tmp/cpu.$s.$v" | awk '{a[NR]=$1} END {printf "%.3f / %.3f", a[1], a[int((NR+1)/2)]}')
      printf '%-62s CPU min/median %s s | %s\n' "$name" "$cpu" "$(cat "$tmp/line.$s.$v")"
    done
  done
} | tee "$OUT"
