# Energy and momentum diagnostics of a run, and the integrator's step size.
#
# usage: gnuplot -c plots/diagnostics.gp DIAGNOSTICS.dat OUT.(png|svg) ["TITLE"]
#   DIAGNOSTICS.dat  capdyn export RESULTS.h5 diagnostics [SYSTEM]
# Columns: 1 t, 2 ke, 3 pe, 4 e, 5 de, 6-8 p, 9 dp, 10-12 l (about the CoM),
# 13 dl, 14-16 CoM, 17 h, 18 nrhs, 19 nsteps, 20 nrejected, 21 nevents, 22 wall.
# Energy is kinetic + gravitational (contact springs and actuator work are not
# in it); dp and dl are |P - P(0)| and |L - L(0)|, zero when conserved
# exactly, plotted on a log scale (points that are exactly 0 are omitted).

if (ARGC < 2) { print "usage: gnuplot -c diagnostics.gp DIAGNOSTICS.dat OUT.png|OUT.svg [TITLE]"; exit status 2 }
diag = ARG1
out = ARG2
ttl = (ARGC >= 3) ? ARG3 : "diagnostics"

if (out[strlen(out)-3:] eq ".svg") {
    set terminal svg size 900,900 dynamic enhanced font "sans,11" background rgb "white"
} else {
    set terminal pngcairo size 900,900 enhanced font "sans,10"
}
set output out
set grid lc rgb "#dddddd"
set key top right noenhanced font ",9"
set lmargin 12
set multiplot layout 3,1 title ttl noenhanced

set ylabel "energy [J]"
unset xlabel
set format x ""
plot diag using 1:2 with lines lw 1.5 title "kinetic", \
     diag using 1:3 with lines lw 1.5 title "potential (gravity)", \
     diag using 1:4 with lines lw 1.5 dt 2 title "total"

set ylabel "momentum drift"
set logscale y
set format y "10^{%L}"
plot diag using 1:($9 > 0 ? $9 : 1/0) with lines lw 1.5 title "|P - P(0)| [kg m/s]", \
     diag using 1:($13 > 0 ? $13 : 1/0) with lines lw 1.5 title "|L - L(0)| about the CoM [kg m^2/s]"

# mean step over each sample interval: (t_i - t_(i-1)) / (nsteps_i - nsteps_(i-1));
# the last accepted step before a sample is often a sliver that lands on it
set ylabel "step size h [s]"
set xlabel "time t [s]"
set format x "%g"
t0 = 0; n0 = 0
set key bottom right
plot diag using 1:(dn = $19 - n0, dt = $1 - t0, n0 = $19, t0 = $1, (dn > 0 && dt > 0) ? dt/dn : 1/0) \
          with steps lw 1.5 title "mean step over the sample interval", \
     diag using 1:($17 > 0 ? $17 : 1/0) with points pt 7 ps 0.3 lc rgb "#a0a0a0" title "last step before the sample"
unset multiplot
