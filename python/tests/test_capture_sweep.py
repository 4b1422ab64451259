"""A shipped capture scenario run from Python gives what `capdyn run`
gives (verdict, its time, peak force, the other figures of merit: the same
numbers, exactly: the same library code and the same run loop), and a
sweep of a few variants run from Python with multiprocessing equals
`capdyn sweep` variant by variant.

The scenario is the Space Gripper on a handrail (paper Fig. 11), cut at
0.9 s (it is captured at 0.83 s) so that the test stays short; the same
--set override goes to both sides."""
import math
import multiprocessing
import subprocess

import h5py
import numpy as np

import capdyn
from conftest import BIN, scenario

HANDRAIL = scenario("space_gripper_handrail.toml")


def same(a, b):
    """equal numbers, NaN equal to NaN"""
    return (math.isnan(a) and math.isnan(b)) or a == b


def test_capture_run_equals_capdyn_run(tmp_path, capdyn_bin):
    sets = ["simulation.duration=0.9"]
    out = tmp_path / "handrail.h5"
    # the command in the background while Python runs the same scenario
    cli = subprocess.Popen([BIN, "run", HANDRAIL, "-q", "-o", str(out), *sum((["--set", s] for s in sets), [])],
                           stderr=subprocess.PIPE, text=True)
    sim = capdyn.Simulation(capdyn.load(HANDRAIL, set=sets))
    res = sim.run()
    assert cli.wait() == 0, cli.stderr.read()
    with capdyn.Results(str(out)) as r:
        ref = r.capture
        assert r.attrs["t_final"] == res.t == 0.9
        assert r.attrs["stats_nrhs"] == res.nrhs and r.attrs["stats_nevents"] == res.nevents
    cap = res.capture
    assert cap.verdict == ref["verdict"] == "captured"
    assert cap.t == ref["t"]
    assert cap.peak_fn == ref["peak_fn"] > 0
    for k in ("peak_tau", "epsilon", "n_stick", "n_slip"):
        assert same(getattr(cap, k), ref[k]), k
    assert np.array_equal(cap.offset, ref["offset"])


SWEEP_KEY = "gripper.torque"
SWEEP_SPEC = "0.04:0.06:3"
SWEEP_SETS = ["simulation.duration=1.2"]


def run_variant(value):
    """One variant as capdyn sweep runs it: the overrides, then the swept key."""
    sim = capdyn.Simulation(capdyn.load(HANDRAIL, set=SWEEP_SETS + [f"{SWEEP_KEY}={value}"]))
    r = sim.run(until_verdict=True)
    c = r.capture
    return dict(verdict=c.verdict, t_capture=c.t_capture, t_escape=c.t_escape, t_cage=c.t_cage, peak_fn=c.peak_fn,
                peak_tau=c.peak_tau, epsilon=c.epsilon, n_stick=c.n_stick, n_slip=c.n_slip,
                fn_step_max=r.fn_step_max, t_final=r.t, stats_rhs=r.nrhs, stats_steps=r.nsteps, events=r.nevents)


def test_sweep_with_multiprocessing_equals_capdyn_sweep(tmp_path, capdyn_bin):
    out = tmp_path / "sweep.h5"
    cli = subprocess.Popen([BIN, "sweep", HANDRAIL, "--vary", f"{SWEEP_KEY}={SWEEP_SPEC}", "--until-verdict",
                            "-j", "1", "-q", "-o", str(out), *sum((["--set", s] for s in SWEEP_SETS), [])],
                           stderr=subprocess.PIPE, text=True)
    values = ["0.04", "0.05", "0.06"]
    with multiprocessing.get_context("fork").Pool(2) as pool:
        mine = pool.map(run_variant, values)
    assert cli.wait() == 0, cli.stderr.read()
    names = {0: "unresolved", 1: "captured", 2: "escaped"}
    with h5py.File(out, "r") as f:
        got = [v.decode() if isinstance(v, bytes) else v for v in f["param_values"][:, 0]]
        assert [float(v) for v in got] == [float(v) for v in values]
        assert list(f["status"][:]) == [0, 0, 0]
        for i, m in enumerate(mine):
            assert names[int(f["verdict"][i])] == m["verdict"], f"variant {i}"
            for k in ("t_capture", "t_escape", "t_cage", "peak_fn", "peak_tau", "epsilon", "fn_step_max", "t_final"):
                assert same(float(f[k][i]), m[k]), f"variant {i}: {k} {f[k][i]} vs {m[k]}"
            for k in ("n_stick", "n_slip", "stats_rhs", "stats_steps", "events"):
                assert int(f[k][i]) == m[k], f"variant {i}: {k}"
    # the variants are not all alike: the sweep did vary the physics
    assert len({m["peak_fn"] for m in mine}) == 3


def test_caged_maps_to_its_name_and_time(tmp_path, capdyn_bin):
    """verdict code 3 (verdict.h) is "caged" in Python as in the file: the
    Space Gripper wrap of its cylinder with frictionless contacts comes to
    rest without force closure (tests/test_verdict.c), caged at 0.672 s."""
    sets = ["simulation.duration=1.0", "contact.mu=0.0", "contact.mu_max=0.0"]
    out = tmp_path / "cage.h5"
    cyl = scenario("space_gripper_cylinder.toml")
    subprocess.run([BIN, "run", cyl, "-q", "-o", str(out), *sum((["--set", s] for s in sets), [])], check=True)
    res = capdyn.Simulation(capdyn.load(cyl, set=sets)).run()
    with capdyn.Results(str(out)) as r:
        ref = r.capture
        pk = r.step_peaks()
    cap = res.capture
    # the peaks over steps the run stored (capdyn info prints them): every
    # step's force is in the onset window or out of it, and the largest is
    # the one the Python loop keeps (the same steps)
    assert pk is not None and set(pk) == {"fn_step_max", "fn_step_body", "fn_step_onset", "ft_step_max",
                                          "t_fn_step_body", "t_fn_step_onset"}
    assert np.array_equal(pk["fn_step_max"], np.maximum(pk["fn_step_body"], pk["fn_step_onset"]))
    assert pk["fn_step_max"].max() == res.fn_step_max
    assert np.all(pk["ft_step_max"] == 0.0)  # frictionless
    assert cap.verdict == ref["verdict"] == "caged"
    assert not cap.captured
    assert cap.t == ref["t"] and abs(cap.t - 0.672) < 1.5e-3
    # the monitor's cage time, as capdyn sweep stores it (t_cage); never captured
    assert cap.t_cage == cap.t and math.isnan(cap.t_capture)
    assert cap.epsilon == ref["epsilon"] == 0.0
