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
# Environment: CAPDYN (default build/capdyn); the exported columns go next to
# OUT (OUT without its extension, _*.dat).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
CAPDYN=${CAPDYN:-$ROOT/build/capdyn}
[ $# -ge 2 ] || { echo "usage: plots/force_profile.sh RESULTS.h5 OUT.png|OUT.svg [TITLE] [T_MAX]" >&2; exit 2; }
h5=$1; out=$2; tmax=${4:-}
title=${3:-$("$CAPDYN" info "$h5" | sed -n 's/^title  *//p' | head -1)}
p="${out%.*}"
"$CAPDYN" export "$h5" contacts --active > "${p}_contacts.dat"
"$CAPDYN" export "$h5" slots > "${p}_slots.dat"
"$CAPDYN" export "$h5" events > "${p}_events.dat"
# groups: on another system's body (the target) per check-point body
# (finger link); within one system per body pair
awk -v S="${p}_slots.dat" -v G="${p}_groups.txt" -v tmax="$tmax" '
    function sys(b) { sub(/\/.*/, "", b); return b }
    BEGIN { while ((getline l < S) > 0) if (l !~ /^#/) { split(l, f, " "); A[f[1]] = f[3]; B[f[1]] = f[4] } }
    /^# t / { for (k = 7; k <= NF; k += 3) { s = $k; sub(/^fn\./, "", s); c = k - 1
                  if (sys(A[s]) != sys(B[s])) { g = "on " B[s] ": " A[s]; cls = "t" } else { g = A[s] " - " B[s]; cls = "s" }
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
[ -f "${p}_groups.txt" ] || : > "${p}_groups.txt"
nt=$(grep -c '^t ' "${p}_groups.txt" || true)
ns=$(grep -c '^s ' "${p}_groups.txt" || true)
# the y-scale: 1.3 x the 98th percentile of the largest group force over the
# samples with contact (t <= T_MAX; with T_MAX: the maximum), per panel
scale() { # first-column offset, stride, count
    awk -v o="$1" -v st="$2" -v n="$3" -v tmax="$tmax" '
        tmax != "" && $1 > tmax + 0 { next }
        { m = 0; for (j = 0; j < n; j++) if ($(o + st * j) > m) m = $(o + st * j)
          if (m > 0) v[++nv] = m; if (m > pk) { pk = m; tp = $1 } }
        END { if (nv == 0) { print 1, 0, 0; exit }
              asort_n = nv; for (i = 2; i <= nv; i++) { x = v[i]; for (j = i - 1; j >= 1 && v[j] > x; j--) v[j + 1] = v[j]; v[j + 1] = x }
              y = tmax != "" ? pk : 1.3 * v[int(0.98 * (nv - 1)) + 1]; if (y <= 0) y = 1
              print y, pk, tp }' "${p}_groups.dat"
}
read -r yn pkn tpn <<< "$(scale 3 2 "$nt")"
read -r yt pkt tpt <<< "$(scale 4 2 "$nt")"
read -r ys pks tps <<< "$(scale $((3 + 2 * nt)) 1 "$ns")"
gnuplot -c "$ROOT/plots/force_profile.gp" "$p" "$out" "$title" "${tmax:--}" "$nt" "$ns" "$yn $pkn $tpn" "$yt $pkt $tpt" "$ys $pks $tps"
