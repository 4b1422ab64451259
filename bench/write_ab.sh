#!/usr/bin/env bash
# Interleaved A/B of two capdyn binaries on `capdyn run` as a user runs it,
# results file included (bench/ab.sh times the library without writing):
# ROUNDS rounds; in each, every scenario runs once with A and once with B,
# the order alternating between rounds. Prints every run's wall and CPU
# seconds (user + system, /usr/bin/time) and file size, then per scenario
# the minimum and median of each binary, the speed-ups A/B of the CPU-time
# minima and medians, and the real-time factor duration / median wall time
# of each (RTF as `capdyn run` delivers it).
#
# Usage: ROUNDS=5 bash bench/write_ab.sh CAPDYN_A CAPDYN_B SCENARIO.toml... [-- --set KEY=VALUE ...]
# The machine is shared and noisy: read the minima first, and several rounds.
set -u
cd "$(dirname "$0")/.."
[ $# -ge 3 ] || { echo "usage: ROUNDS=5 bash bench/write_ab.sh CAPDYN_A CAPDYN_B SCENARIO.toml... [-- --set K=V ...]" >&2; exit 2; }
A=$1; B=$2; shift 2
scen=(); extra=()
while [ $# -gt 0 ]; do
    if [ "$1" = "--" ]; then shift; extra=("$@"); break; fi
    scen+=("$1"); shift
done
for b in "$A" "$B"; do [ -x "$b" ] || { echo "bench/write_ab.sh: '$b' is not an executable" >&2; exit 2; }; done
[ -x /usr/bin/time ] || { echo "bench/write_ab.sh: needs /usr/bin/time (Debian package time)" >&2; exit 2; }
ROUNDS=${ROUNDS:-5}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
echo "A = $A"
echo "B = $B"
echo "${extra[*]:+overrides: ${extra[*]}}"
echo "$ROUNDS rounds, $(date -u '+%Y-%m-%d %H:%M UTC'), load average at start: $(cut -d' ' -f1-3 /proc/loadavg)"
printf '%-6s %-4s %-36s %9s %9s %12s\n' round bin scenario "wall [s]" "cpu [s]" "file [B]"
for ((r = 1; r <= ROUNDS; r++)); do
    if ((r % 2)); then order=(A B); else order=(B A); fi
    for s in "${scen[@]}"; do
        name=$(basename "$s" .toml)
        for which in "${order[@]}"; do
            bin=$A; [ "$which" = B ] && bin=$B
            rm -f "$dir/o.h5"
            /usr/bin/time -f '%e %U %S' -o "$dir/t" "$bin" run "$s" -o "$dir/o.h5" --quiet "${extra[@]}" ||
                { echo "bench/write_ab.sh: $bin failed on $s" >&2; exit 1; }
            read -r wall us sy <"$dir/t"
            cpu=$(awk -v u="$us" -v s="$sy" 'BEGIN { printf "%.3f", u + s }')
            size=$(stat -c %s "$dir/o.h5")
            printf '%-6s %-4s %-36s %9s %9s %12s\n' "$r" "$which" "$name" "$wall" "$cpu" "$size"
            echo "$which $name $wall $cpu $size" >>"$dir/all"
        done
    done
done
echo
printf '%-36s %23s %23s %13s %13s %9s %9s\n' scenario "A cpu min/median [s]" "B cpu min/median [s]" "A/B min" "A/B median" "RTF A" "RTF B"
for s in "${scen[@]}"; do
    name=$(basename "$s" .toml)
    # the simulated duration: an override, else the scenario's [simulation] duration
    dur=$(printf '%s\n' "${extra[@]}" | sed -n 's/^simulation\.duration=//p' | tail -1)
    [ -n "$dur" ] || dur=$(awk '/^\[/ { sim = ($0 ~ /^\[simulation\]/) } sim && /^duration *=/ { sub(/#.*/, ""); split($0, a, "="); print a[2] + 0; exit }' "$s")
    awk -v n="$name" -v dur="${dur:-0}" '
        function med(a, k,   i, j, t) { for (i = 1; i <= k; i++) for (j = i + 1; j <= k; j++) if (a[j] < a[i]) { t = a[i]; a[i] = a[j]; a[j] = t }
                                        return k % 2 ? a[(k + 1) / 2] : 0.5 * (a[k / 2] + a[k / 2 + 1]) }
        $2 == n && $1 == "A" { ka++; ca[ka] = $4; wa[ka] = $3; sa = $5 }
        $2 == n && $1 == "B" { kb++; cb[kb] = $4; wb[kb] = $3; sb = $5 }
        END {
            mina = ca[1]; for (i = 2; i <= ka; i++) if (ca[i] < mina) mina = ca[i]
            minb = cb[1]; for (i = 2; i <= kb; i++) if (cb[i] < minb) minb = cb[i]
            ma = med(ca, ka); mb = med(cb, kb); mwa = med(wa, ka); mwb = med(wb, kb)
            ra = "-"; rb = "-"
            if (dur > 0) { ra = sprintf("%.2f", dur / mwa); rb = sprintf("%.2f", dur / mwb) }
            printf "%-36s %11.3f/%-11.3f %11.3f/%-11.3f %13.2f %13.2f %9s %9s   file A %d B %d bytes\n", n, mina, ma, minb, mb, mina / minb, ma / mb, ra, rb, sa, sb
        }' "$dir/all"
done
