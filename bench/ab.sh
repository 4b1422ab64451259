#!/usr/bin/env bash
# Interleaved A/B of two builds of bench_scenarios (e.g. before and after a
# change, or two compiler settings): ROUNDS rounds; in each, every scenario
# runs once (-r 1, its own settings) with A and with B, the order of A and B
# alternating between rounds so that neither always runs first. Prints the
# CPU seconds of every run, then per scenario the minimum and median of
# each binary and the speed-ups A/B of the minima and of the medians, and
# whether the two binaries took the same steps and evaluations (a change
# meant to be exact must not move them).
#
# Usage: ROUNDS=5 bash bench/ab.sh BIN_A BIN_B SCENARIO.toml... [-- --set KEY=VALUE ...]
# The machine is shared and noisy: read the minima first, and several rounds.
set -u
cd "$(dirname "$0")/.."
[ $# -ge 3 ] || { echo "usage: ROUNDS=5 bash bench/ab.sh BIN_A BIN_B SCENARIO.toml... [-- --set K=V ...]" >&2; exit 2; }
A=$1; B=$2; shift 2
scen=(); extra=()
while [ $# -gt 0 ]; do
    if [ "$1" = "--" ]; then shift; extra=("$@"); break; fi
    scen+=("$1"); shift
done
for b in "$A" "$B"; do [ -x "$b" ] || { echo "bench/ab.sh: '$b' is not an executable" >&2; exit 2; }; done
ROUNDS=${ROUNDS:-5}
tmp=$(mktemp)
trap 'rm -f "$tmp"' EXIT
echo "A = $A"
echo "B = $B"
echo "$ROUNDS rounds, $(date -u '+%Y-%m-%d %H:%M UTC'), load average at start: $(cut -d' ' -f1-3 /proc/loadavg)"
printf '%-6s %-4s %-36s %10s %10s %12s\n' round bin scenario "cpu [s]" steps evaluations
for ((r = 1; r <= ROUNDS; r++)); do
    if ((r % 2)); then order=(A B); else order=(B A); fi
    for s in "${scen[@]}"; do
        for which in "${order[@]}"; do
            bin=$A; [ "$which" = B ] && bin=$B
            line=$("$bin" -r 1 "${extra[@]}" "$s" | grep -F "$(basename "$s")") || { echo "bench/ab.sh: $bin failed on $s" >&2; exit 1; }
            # scenario stepper dur wall min cpu RTF RTFcpu steps rhs jac events status
            read -r name _ _ _ _ cpu _ _ steps rhs _ <<<"$line"
            printf '%-6s %-4s %-36s %10s %10s %12s\n' "$r" "$which" "$name" "$cpu" "$steps" "$rhs"
            echo "$which $name $cpu $steps $rhs" >>"$tmp"
        done
    done
done
echo
printf '%-36s %10s %10s %10s %10s %9s %9s %s\n' scenario "A min" "A median" "B min" "B median" "min A/B" "med A/B" "same steps"
awk '
function median(arr, n,   i, j, t) {
    for (i = 2; i <= n; i++) { t = arr[i]; for (j = i - 1; j >= 1 && arr[j] > t; j--) arr[j + 1] = arr[j]; arr[j + 1] = t }
    return n % 2 ? arr[(n + 1) / 2] : (arr[n / 2] + arr[n / 2 + 1]) / 2
}
{
    k = $1 SUBSEP $2; n[k]++; v[k, n[k]] = $3
    if (!($2 in seen)) { seen[$2] = 1; order[++ns] = $2 }
    sig = $4 " " $5
    if (($2, "sig") in first) { if (first[$2, "sig"] != sig) differ[$2] = 1 } else first[$2, "sig"] = sig
}
END {
    for (i = 1; i <= ns; i++) {
        s = order[i]
        for (w = 0; w < 2; w++) {
            b = w ? "B" : "A"; k = b SUBSEP s; m = 1e300
            for (j = 1; j <= n[k]; j++) { x[j] = v[k, j]; if (x[j] < m) m = x[j] }
            mn[b] = m; md[b] = median(x, n[k])
        }
        printf "%-36s %10.3f %10.3f %10.3f %10.3f %9.3f %9.3f %s\n", s, mn["A"], md["A"], mn["B"], md["B"],
               mn["A"] / mn["B"], md["A"] / md["B"], (s in differ) ? "no" : "yes"
    }
}' "$tmp"
