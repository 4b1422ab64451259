#!/usr/bin/env bash
# Variants per second of `capdyn sweep` (docs/sweep.md, issue 9): one sweep
# run with -j 1, with -j $(nproc), and, where build-mpi/capdyn exists
# (make MPI=1), under `mpirun -n 2` and `mpirun -n $(nproc)+1` (rank 0 only
# hands out work). Each prints its summary line (variants/s); the summaries
# are checked identical (wall times apart) with h5diff.
#
#   bash bench/sweep_speed.sh [GRID_X GRID_Y]      (default 5x5 of 0.2 s runs)
#
# The machine may be shared: rates are wall-clock rates of this machine now.
set -euo pipefail
cd "$(dirname "$0")/.."
B=${CAPDYN:-build/capdyn}
MB=build-mpi/capdyn
NX=${1:-5}
NY=${2:-5}
NP=$(nproc)
T=$(mktemp -d /tmp/capdyn_sweep_bench.XXXXXX)
trap 'rm -rf "$T"' EXIT
ARGS=(scenarios/tako_centred.toml --set simulation.duration=0.2 --set simulation.output_dt=0.01
      --vary "target.object.position[0]=-0.004:0.004:$NX" --vary "target.object.position[1]=0.07:0.09:$NY")
echo "sweep: ${NX}x${NY} variants of scenarios/tako_centred.toml, 0.2 s each; $NP cores online"
echo "-j 1:";      "$B" sweep "${ARGS[@]}" -j 1 -o "$T/j1.h5" | head -1
echo "-j $NP:";    "$B" sweep "${ARGS[@]}" -j "$NP" -o "$T/jn.h5" | head -1
h5diff --exclude-path /timing "$T/j1.h5" "$T/jn.h5" && echo "summaries identical (-j 1, -j $NP)"
if [ -x "$MB" ] && command -v mpirun > /dev/null; then
    export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
    for n in 2 $((NP + 1)); do
        echo "mpirun -n $n:"
        mpirun -n "$n" --oversubscribe "$MB" sweep "${ARGS[@]}" -o "$T/mpi$n.h5" | head -1
        h5diff --exclude-path /timing "$T/j1.h5" "$T/mpi$n.h5" && echo "summary identical to -j 1"
    done
else
    echo "(no MPI build: make MPI=1 for the mpirun rows)"
fi
