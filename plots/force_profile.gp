# Force profile (plots/force_profile.sh writes the inputs):
#   gnuplot -c plots/force_profile.gp PREFIX OUT.(png|svg) TITLE T_MAX NT NS "YN PKN TPN" "YT PKT TPT" "YS PKS TPS"
# PREFIX_groups.dat: t, slip (1 if a contact on the target slips), then per
# target group (a finger link touching another system's body) fn ft, then
# per within-system group (a body pair of one system) fn; PREFIX_groups.txt
# names them ("t NAME" / "s NAME"); PREFIX_events.dat: capdyn export events.
# T_MAX: end of the time axis ("-": the run's end). Y* the panel's y maximum,
# PK* the largest value and TP* its time (drawn as clipped marks if above Y*).
p = ARG1; out = ARG2; ttl = ARG3; tmax = ARG4
nt = int(ARG5); ns = int(ARG6)
yn = real(word(ARG7,1)); pkn = real(word(ARG7,2)); tpn = real(word(ARG7,3))
yt = real(word(ARG8,1)); pkt = real(word(ARG8,2)); tpt = real(word(ARG8,3))
ys = real(word(ARG9,1)); pks = real(word(ARG9,2)); tps = real(word(ARG9,3))
gname(k) = system(sprintf("awk 'NR == %d { sub(/^[ts] /, \"\"); print }' '%s_groups.txt'", k, p))
link(k) = (g = gname(k), strstrt(g, ": ") > 0 ? g[strstrt(g, ": ") + 2:] : g)
target = (nt > 0) ? (g = gname(1), g[4:strstrt(g, ": ") - 1]) : "the target"

if (out[strlen(out)-3:] eq ".svg") {
    set terminal svg size 1100,820 dynamic enhanced font "sans,11" background rgb "white"
} else {
    set terminal pngcairo size 1100,820 enhanced font "sans,10"
}
set output out
stats p."_groups.dat" using 1 nooutput
tlo = STATS_min; thi = STATS_max
stats p."_groups.dat" using 2 nooutput
anyslip = STATS_max > 0
# a frictionless run (|f_t| at round-off) is drawn on the normal-force scale
if (pkt <= 1e-9 * pkn) { yt = yn }
if (tmax ne "-") { thi = real(tmax) }
set xrange [tlo:thi]

# events the run has: clutch (10) and schedule (9) as thin grey lines
ev = p."_events.dat"
nclutch = int(system(sprintf("awk '!/^#/ && $2 == 10' '%s' | wc -l", ev)))
nsched = int(system(sprintf("awk '!/^#/ && $2 == 9' '%s' | wc -l", ev)))
evt = system(sprintf("awk '!/^#/ && ($2 == 10 || $2 == 9) { print $1 \":\" $2 }' '%s'", ev))
do for [w in evt] {
    et = real(w[1:strstrt(w, ":") - 1]); ek = int(w[strstrt(w, ":") + 1:])
    if (et >= tlo && et <= thi) {
        if (ek == 10) { set arrow from et, graph 0 to et, graph 1 nohead lw 0.8 lc rgb "grey45" back }
        if (ek == 9) { set arrow from et, graph 0 to et, graph 1 nohead lw 0.8 lc rgb "grey45" dt 2 back }
    }
}
set grid lc rgb "#e4e4e4"
set key outside right top vertical noenhanced font ",9" spacing 1.0 samplen 2
set style fill solid 0.15 noborder
set lmargin 10
set rmargin 30
np = (ns > 0) ? 3 : 2
set multiplot layout np,1 title ttl noenhanced font ",12"

set title sprintf("normal force on %s, per check-point body, e.g. finger link (sum over its check points)", target) noenhanced
set ylabel "f_n [N]"
set yrange [0:yn]
unset xlabel
if (nt > 0) {
    plot p."_groups.dat" using 1:($2 > 0 ? yn : 0) with filledcurves y1=0 lc rgb "#e04040" title (anyslip ? "a contact on the target slips" : ""), \
         for [j=1:nt] "" using 1:(column(1+2*j)) with lines lw 1.5 title link(j), \
         for [j=1:nt] "" using 1:(column(1+2*j) > yn ? yn : NaN) with points pt 9 ps 0.9 lc rgb "black" \
             title (j == 1 && pkn > yn ? sprintf("above the scale (peak at samples %.3g N at %.3g s)", pkn, tpn) : ""), \
         NaN with lines lw 0.8 lc rgb "grey45" title (nclutch > 0 ? sprintf("clutch event (%d)", nclutch) : ""), \
         NaN with lines lw 0.8 dt 2 lc rgb "grey45" title (nsched > 0 ? sprintf("schedule row change (%d)", nsched) : "")
} else {
    set label 1 "no contact with another system's body" at graph 0.5, 0.5 center
    plot NaN notitle
    unset label 1
}

set title sprintf("tangential force magnitude on %s, per check-point body (sum of |f_t|)", target) noenhanced
set ylabel "|f_t| [N]"
set yrange [0:yt]
if (ns == 0) { set xlabel "time t [s]" }
if (nt > 0) {
    plot p."_groups.dat" using 1:($2 > 0 ? yt : 0) with filledcurves y1=0 lc rgb "#e04040" notitle, \
         for [j=1:nt] "" using 1:(column(2+2*j)) with lines lw 1.5 title link(j), \
         for [j=1:nt] "" using 1:(column(2+2*j) > yt ? yt : NaN) with points pt 9 ps 0.9 lc rgb "black" \
             title (j == 1 && pkt > yt ? sprintf("above the scale (peak at samples %.3g N at %.3g s)", pkt, tpt) : "")
} else {
    plot NaN notitle
}

if (ns > 0) {
    set title "normal force between bodies of one system (finger on finger), per body pair"
    set ylabel "f_n [N]"
    set yrange [0:ys]
    set xlabel "time t [s]"
    plot for [j=1:ns] p."_groups.dat" using 1:(column(2+2*nt+j)) with lines lw 1.2 title gname(nt + j), \
         for [j=1:ns] "" using 1:(column(2+2*nt+j) > ys ? ys : NaN) with points pt 9 ps 0.9 lc rgb "black" \
             title (j == 1 && pks > ys ? sprintf("above the scale (peak at samples %.3g N at %.3g s)", pks, tps) : "")
}
unset multiplot
