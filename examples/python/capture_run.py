#!/usr/bin/env python3
"""capture_run.py -- a capture scenario run from Python: its verdict, its
figures of merit and a matplotlib plot of the contact force profile.

    build/venv/bin/python examples/python/capture_run.py \
        [SCENARIO.toml] [--set KEY=VALUE ...] [--until-verdict] [-o force.png]

Default scenario: scenarios/space_gripper_handrail.toml (a Space Gripper
closing on a handrail, paper Fig. 11; captured at 0.83 s). The run is the
one `capdyn run` makes (same samples, same verdict and numbers); at every
sample the normal forces of the contact slots are read from the engine's
memory (sim.slot_fn, a numpy view) and summed over the slots touching the
object and over the fingers' other contacts. Exit status 1 if the run
fails, 0 otherwise (whatever the verdict: it is printed).
"""
import argparse
import os
import sys

import numpy as np

import capdyn

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenario", nargs="?", default=os.path.join(ROOT, "scenarios", "space_gripper_handrail.toml"))
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override (capdyn run --set)")
    ap.add_argument("--until-verdict", action="store_true", help="stop at the capture verdict")
    ap.add_argument("-o", "--output", default="capture_force.png", help="the force profile (PNG)")
    a = ap.parse_args()

    sc = capdyn.load(a.scenario, set=a.set)
    if not sc.has_capture:
        sys.exit(f"{a.scenario}: no capture verdict (the scenario needs a [gripper] and an object)")
    sim = capdyn.Simulation(sc)
    # the slots touching the object: check point or shape on a body of the object's system
    body_sys = sc.body_systems()[sc.slot_bodies()]
    on_object = np.any(body_sys == sc.capture_object, axis=1)

    t, f_obj, f_other, n_closed = [], [], [], []
    fn = sim.slot_fn            # a view: its values are the engine's at every sample
    mode = sim.slot_mode

    def sample(s):
        # interpolated samples (sampling = "interpolate") come as copies, the others as the simulation itself
        f = s.slot_fn if s is not sim else fn
        t.append(s.t)
        f_obj.append(float(f[on_object].sum()))
        f_other.append(float(f[~on_object].sum()))
        n_closed.append(int(np.count_nonzero((s.slot_mode if s is not sim else mode)[on_object])))

    try:
        res = sim.run(until_verdict=a.until_verdict, on_sample=sample)
    except capdyn.CapdynError as e:
        print(f"capture_run: run failed: {e}", file=sys.stderr)
        return 1
    c = res.capture
    print(f"{sc.title}")
    print(f"  {res.message}; {res.nsteps} steps, {res.nrhs} evaluations, {res.nevents} events")
    print(f"  verdict     {c.verdict}" + (f" at t = {c.t:.4g} s" if c.verdict != "unresolved" else ""))
    print(f"  peak force  {c.peak_fn:.4g} N on the object (largest over every step: {res.fn_step_max:.4g} N)")
    print(f"  peak torque {c.peak_tau:.4g} N m; contacts at the end: {c.n_stick} stick, {c.n_slip} slip; "
          f"epsilon {c.epsilon:.3g}")
    print(f"  offset      {np.array2string(c.offset, precision=4)} m (object - palm centre, palm frame)")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 3.6))
    ax.plot(t, f_obj, label="on the object (sum of normal forces)")
    ax.plot(t, f_other, label="other contacts", alpha=0.7)
    if c.verdict != "unresolved":
        ax.axvline(c.t, color="k", ls="--", lw=0.8, label=f"{c.verdict} at {c.t:.3g} s")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("normal force [N]")
    ax.set_title(sc.title, fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(a.output, dpi=120)
    print(f"  force profile: {a.output} ({len(t)} samples, at most {max(n_closed)} object contacts closed)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
