#!/usr/bin/env bash
# Force profile of any run (docs/figures.md): the contact forces on the
# target apart from the forces between bodies of one system (finger on
# finger), slots classified by the body pair the results file names, summed
# per finger link; the y-scale set by the grasp (transients above it drawn
# as clipped marks with their peak in the legend); thin grey vertical lines
# at the events the run has (clutch, schedule); slip phases shaded.
#
#   plots/force_profile.sh RESULTS.h5 OUT.png|OUT.svg [TITLE] [T_MAX]
#     TITLE  default: the file's title; T_MAX: end of the time axis [s]
#            (a zoom: then the y-scale covers every force in the window)
# Environment: CAPDYN (default build/capdyn); DATA_DIR: where the exported
# columns go (default: next to OUT), as OUTSTEM_*.dat.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
CAPDYN=${CAPDYN:-$ROOT/build/capdyn}
[ $# -ge 2 ] || { echo "usage: plots/force_profile.sh RESULTS.h5 OUT.png|OUT.svg [TITLE] [T_MAX]" >&2; exit 2; }
h5=$1; out=$2; tmax=${4:-}
title=${3:-$("$CAPDYN" info "$h5" | sed -n 's/^title  *//p' | head -1)}
stem=$(basename "${out%.*}")
p="${DATA_DIR:-$(dirname "$out")}/$stem"
"$CAPDYN" export "$h5" contacts --active > "${p}_contacts.dat"
"$CAPDYN" export "$h5" slots > "${p}_slots.dat"
"$CAPDYN" export "$h5" events > "${p}_events.dat"
# groups: on another system's body (the target) per check-point body
# (finger link); within one system per body pair
: > "${p}_groups.txt"
awk -v S="${p}_slots.dat" -v G="${p}_groups.txt" '
    function sys(b) { sub(/\/.*/, "", b); return b }
    BEGIN { while ((getline l < S) > 0) if (l !~ /^#/) { split(l, f, " "); A[f[1]] = f[3]; B[f[1]] = f[4] } }
    /^# t / { for (k = 7; k <= NF; k += 3) { s = $k; sub(/^fn\./, "", s); c = k - 1
                  if (sys(A[s]) != sys(B[s])) { g = "on " B[s] ": " A[s]; cls = "t" } else { g = A[s] < B[s] ? A[s] " - " B[s] : B[s] " - " A[s]; cls = "s" }
                  if (!(g in gi)) { gi[g] = ++ng; gname[ng] = g; gcls[ng] = cls }
                  grp[c] = gi[g] }
              for (i = 1; i <= ng; i++) if (gcls[i] == "t") order[++no] = i
              nt = no
              for (i = 1; i <= ng; i++) if (gcls[i] == "s") order[++no] = i
              for (i = 1; i <= no; i++) print gcls[order[i]], gname[order[i]] > G
              next }
    /^#/ { next }
    { for (i = 1; i <= ng; i++) { fn[i] = 0; ft[i] = 0 }; slip = 0
      for (k = 6; k + 2 <= NF; k += 3) { i = grp[k]; fn[i] += $k; ft[i] += $(k + 1); if ($(k + 2) == 2 && gcls[i] == "t") slip = 1 }
      printf "%s %d", $1, slip
      for (j = 1; j <= nt; j++) printf " %.6g %.6g", fn[order[j]], ft[order[j]]
      for (j = nt + 1; j <= no; j++) printf " %.6g", fn[order[j]]
      printf "\n" }' "${p}_contacts.dat" > "${p}_groups.dat"
nt=$(grep -c '^t ' "${p}_groups.txt" || true)
ns=$(grep -c '^s ' "${p}_groups.txt" || true)
# the y-scale: 1.3 x the 98th percentile of the largest group force over the
# samples with contact (with T_MAX: the maximum up to T_MAX), per panel
scale() { # first column, stride, count
    awk -v o="$1" -v st="$2" -v n="$3" -v tmax="$tmax" '
        tmax != "" && $1 > tmax + 0 { next }
        { m = 0; for (j = 0; j < n; j++) if ($(o + st * j) > m) m = $(o + st * j)
          if (m > 0) print m, $1 }' "${p}_groups.dat" | sort -g | awk -v tmax="$tmax" '
        { v[++nv] = $1; tp = $2 }
        END { if (nv == 0) { print 1, 0, 0; exit }
              y = tmax != "" ? 1.05 * v[nv] : 1.3 * v[int(0.98 * (nv - 1)) + 1]; if (y <= 0) y = 1
              print y, v[nv], tp }'
}
read -r yn pkn tpn <<< "$(scale 3 2 "$nt")"
read -r yt pkt tpt <<< "$(scale 4 2 "$nt")"
read -r ys pks tps <<< "$(scale $((3 + 2 * nt)) 1 "$ns")"
gnuplot -c "$ROOT/plots/force_profile.gp" "$p" "$out" "$title" "${tmax:--}" "$nt" "$ns" "$yn $pkn $tpn" "$yt $pkt $tpt" "$ys $pks $tps"
