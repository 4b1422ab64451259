#!/usr/bin/env bash
# Where a run spends its steps: one `capdyn run` of a scenario (with any
# --set overrides), then per simulated second the accepted and rejected
# steps, the right-hand-side evaluations, the events, the median step size
# and the closed slots (stick / slip) at the second's end, from the results
# file's diagnostics (sampled every output_dt). For finding which phase of a
# run caps its real-time factor (docs/performance.md section 12).
#
# Usage: bash bench/steps_per_second.sh SCENARIO.toml [--set KEY=VALUE]...
#        BIN=build/capdyn PY=build/venv/bin/python (h5py)
#        DT=0.1 (the bins' width in simulated seconds, default 1; set the
#        scenario's simulation.output_dt finer than DT to see inside them)
set -u
cd "$(dirname "$0")/.."
BIN=${BIN:-build/capdyn}
PY=${PY:-build/venv/bin/python}
[ $# -ge 1 ] || { echo "usage: bash bench/steps_per_second.sh SCENARIO.toml [--set KEY=VALUE]..." >&2; exit 2; }
[ -x "$BIN" ] || { echo "build $BIN first (make)" >&2; exit 2; }
"$PY" -c 'import h5py' 2>/dev/null || { echo "$PY has no h5py (make python-test sets up build/venv)" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$BIN" run "$@" -o "$tmp/run.h5" > "$tmp/log" 2>&1 || { cat "$tmp/log" >&2; exit 1; }
grep -E '^(integrator|capture|wall time)' "$tmp/log"
"$PY" - "$tmp/run.h5" "${DT:-1}" <<'EOF'
import sys
import h5py
import numpy as np
f = h5py.File(sys.argv[1], "r")
t = f["/time"][:]
g = f["/diagnostics"]
steps, rej, rhs, ev, h = (g[k][:] for k in ("nsteps", "nrejected", "nrhs", "nevents", "step_size"))
mode = f["/contacts/mode"][:] if "/contacts/mode" in f else None
w = float(sys.argv[2])
if not w > 0:
    sys.exit("DT must be a positive number of seconds")
print("%11s %8s %8s %10s %7s %11s %6s %5s" % ("t [s]", "steps", "rejected", "evals", "events", "median h", "stick", "slip"))
for b in range(int(np.floor(t[0] / w + 1e-9)), int(np.ceil(t[-1] / w - 1e-9))):
    t0, t1 = b * w, (b + 1) * w
    i0 = int(np.searchsorted(t, t0 - 1e-12))
    i1 = int(np.searchsorted(t, t1 + 1e-12, side="right")) - 1
    if i1 <= i0:
        continue
    st = sl = 0
    if mode is not None:
        st, sl = int((mode[i1] == 1).sum()), int((mode[i1] == 2).sum())
    print("%5g-%-5g %8d %8d %10d %7d %11.3g %6d %5d" % (t0, t1, steps[i1] - steps[i0], rej[i1] - rej[i0],
          rhs[i1] - rhs[i0], ev[i1] - ev[i0], float(np.median(h[i0 + 1:i1 + 1])), st, sl))
EOF
