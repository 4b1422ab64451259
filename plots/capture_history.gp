# Time histories of a run (plots/capture.sh writes the inputs):
#   gnuplot -c plots/capture_history.gp PREFIX OUT.png TITLE TARGET ARM "FREE SYSTEMS"
# PREFIX_fsplit.dat: t, sum of fn on TARGET's system from other systems'
# check points (slots classified by their body pair), sum of fn between
# bodies of one system (finger on finger), stick and slip contacts on the
# target; PREFIX_tau.dat: t then the joint torques of system ARM ("-": none);
# PREFIX_rot_NAME.dat (t, rotation from the attitude at t = 0 [deg]) and
# PREFIX_diag_NAME.dat (capdyn export diagnostics NAME)
# for every free-floating system; PREFIX_diag_all.dat: the whole.
p = ARG1; out = ARG2; title = ARG3; target = ARG4; arm = ARG5; free = ARG6
set terminal pngcairo size 1400,1000 font ",10"
set output out
set multiplot layout 3,2 title title noenhanced
set grid lc rgb "#dddddd"
set xlabel "t [s]"
set key outside right top vertical noenhanced font ",9"
set rmargin 26
set title "contact forces" noenhanced
set ylabel "N"; set y2tics; set y2label "contacts on the target"
plot p."_fsplit.dat" using 1:2 with lines lw 2 lc rgb "red" title sprintf("sum f_n on %s", target), \
     "" using 1:3 with lines lw 1 lc rgb "purple" title "sum f_n within one system", \
     "" using 1:4 axes x1y2 with steps lc rgb "forest-green" title "stick contacts (right)", \
     "" using 1:5 axes x1y2 with steps lc rgb "orange" title "slip contacts (right)"
unset y2tics; unset y2label
if (arm ne "-") {
    nj = int(system(sprintf("awk '{ print NF - 1; exit }' '%s_tau.dat'", p)))
    set title sprintf("joint torques of %s (all sources)", arm) noenhanced
    set ylabel "N m or N"
    plot for [j=2:nj+1] p."_tau.dat" using 1:j with lines title sprintf("joint %d", j-1)
} else {
    set title "no system with joints"; unset ylabel
    plot NaN notitle
}
nf = words(free)
set title "rotation of each free-floating system from its attitude at t = 0"
set ylabel "deg"
if (nf > 0) {
    plot for [k=1:nf] p."_rot_".word(free,k).".dat" using 1:2 with lines lw 2 title word(free,k)
} else { plot NaN notitle }
set title "linear momentum of each free-floating system and of the whole"
set ylabel "|p| [kg m/s]"
if (nf > 0) {
    plot for [k=1:nf] p."_diag_".word(free,k).".dat" using 1:(sqrt($6**2 + $7**2 + $8**2)) with lines lw 2 title word(free,k), \
         p."_diag_all.dat" using 1:(sqrt($6**2 + $7**2 + $8**2)) with lines lw 2 dt 2 lc rgb "black" title "whole"
} else { plot p."_diag_all.dat" using 1:(sqrt($6**2 + $7**2 + $8**2)) with lines lw 2 lc rgb "black" title "whole" }
set title "angular momentum about each one's own CoM"
set ylabel "|L| [kg m^2/s]"
if (nf > 0) {
    plot for [k=1:nf] p."_diag_".word(free,k).".dat" using 1:(sqrt($10**2 + $11**2 + $12**2)) with lines lw 2 title word(free,k), \
         p."_diag_all.dat" using 1:(sqrt($10**2 + $11**2 + $12**2)) with lines lw 2 dt 2 lc rgb "black" title "whole"
} else { plot p."_diag_all.dat" using 1:(sqrt($10**2 + $11**2 + $12**2)) with lines lw 2 lc rgb "black" title "whole" }
set title "momentum of the whole: change since t = 0 (conserved without fixed bases and external torques)"
set ylabel ""
set logscale y
plot p."_diag_all.dat" using 1:($9 > 0 ? $9 : 1e-18) with lines title "|P - P(0)| [kg m/s]", \
     "" using 1:($13 > 0 ? $13 : 1e-18) with lines title "|L - L(0)| [kg m^2/s]"
unset multiplot
