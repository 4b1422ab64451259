# Force profile: normal and tangential force of every contact slot versus
# time, slip phases shaded, events marked (paper Fig. 3 / Fig. 5 style).
#
# usage: gnuplot -c plots/force_profile.gp CONTACTS.dat EVENTS.dat OUT.(png|svg) ["TITLE"] [T_MAX]
#   CONTACTS.dat  capdyn export RESULTS.h5 contacts --active
#   EVENTS.dat    capdyn export RESULTS.h5 events
#   T_MAX         optional upper limit of the time axis [s] (to zoom in)
# Events are marked in a strip at the top of each panel (onset and separation
# above the normal forces, stick -> slip and slip -> stick above the tangential).
# Columns of CONTACTS.dat: 1 t, 2 nopen, 3 nstick, 4 nslip, 5 fn_sum, then
# per slot j = 0..: fn at 6+3j, |ft| at 7+3j, mode at 8+3j (docs/cli.md).

if (ARGC < 3) { print "usage: gnuplot -c force_profile.gp CONTACTS.dat EVENTS.dat OUT.png|OUT.svg [TITLE] [T_MAX]"; exit status 2 }
contacts = ARG1
events = ARG2
out = ARG3
ttl = (ARGC >= 4) ? ARG4 : "contact forces"
tmax = (ARGC >= 5) ? ARG5 : ""

if (out[strlen(out)-3:] eq ".svg") {
    set terminal svg size 1000,760 dynamic enhanced font "sans,11" background rgb "white"
} else {
    set terminal pngcairo size 1000,760 enhanced font "sans,10"
}
set output out

hdr = system("grep -m1 '^#' '".contacts."'")
nslot = (words(hdr) - 6) / 3
slotname(j) = word(hdr, 7 + 3*j)[4:]
# "slot 19: hand/left2 cp 19" from the export's comment lines
slotlabel(j) = system(sprintf("grep -m1 '^# slot %s:' '%s' | sed 's/^# //; s/ check point / cp /; s/ -> .*//'", slotname(j), contacts))

# y ranges over every slot, and the sample spacing
stats contacts using 1 nooutput
tlo = STATS_min
thi = STATS_max
FN = 0.0
FT = 0.0
if (nslot > 0) {
    do for [j=0:nslot-1] {
        stats contacts using (column(6+3*j)) nooutput
        FN = (STATS_max > FN) ? STATS_max : FN
        stats contacts using (column(7+3*j)) nooutput
        FT = (STATS_max > FT) ? STATS_max : FT
    }
}
FN = (FN > 0) ? 1.12*FN : 1.0
# a frictionless run (|f_t| at round-off) is drawn on the normal-force scale
FT = (FT > 1e-9*FN) ? 1.12*FT : FN
if (tmax ne "") { thi = real(tmax) }

# events present? (stats fails on an empty file)
nev = int(system("grep -vc '^#' '".events."' || true"))

set xrange [tlo:thi]
set grid lc rgb "#dddddd"
set key outside right top vertical noenhanced font ",9" spacing 1.0
set style fill solid 0.18 noborder
set lmargin 10
set rmargin 28
set multiplot layout 2,1 title ttl noenhanced

set ylabel "normal force f_n at samples [N]"
set yrange [0:FN]
unset xlabel
set format x ""
plot contacts using 1:($4 > 0 ? FN : 0) with filledcurves y1=0 lc rgb "#e04040" title "slip phase", \
     for [j=0:nslot-1] contacts using 1:(column(6+3*j)) with lines lw 1.5 title slotlabel(j), \
     (nev > 0 ? events : NaN) using 1:($2 == 0 ? 0.975*FN : 1/0) with points pt 9 ps 0.8 lc rgb "#007000" title "onset", \
     (nev > 0 ? events : NaN) using 1:($2 == 1 ? 0.935*FN : 1/0) with points pt 11 ps 0.8 lc rgb "#000000" title "separation", \
     (nev > 0 ? events : NaN) using 1:($2 == 10 ? 0.895*FN : 1/0) with impulses lw 2 lc rgb "#8000a0" title "clutch"

set ylabel "tangential force |f_t| at samples [N]"
set yrange [0:FT]
set xlabel "time t [s]"
set format x "%g"
plot contacts using 1:($4 > 0 ? FT : 0) with filledcurves y1=0 lc rgb "#e04040" title "slip phase", \
     for [j=0:nslot-1] contacts using 1:(column(7+3*j)) with lines lw 1.5 title slotlabel(j), \
     (nev > 0 ? events : NaN) using 1:($2 == 2 ? 0.975*FT : 1/0) with points pt 7 ps 0.6 lc rgb "#d00000" title "stick -> slip", \
     (nev > 0 ? events : NaN) using 1:($2 == 3 ? 0.935*FT : 1/0) with points pt 6 ps 0.8 lc rgb "#0000d0" title "slip -> stick"

unset multiplot
