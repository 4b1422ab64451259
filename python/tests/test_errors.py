"""Bad input from Python: every kind gets an exception (CapdynError with
the engine's own message, or TypeError / ValueError / KeyError from the
binding's checks before C is called) and the interpreter goes on: nothing
crashes, the objects stay usable.

The scenario mistakes are tests/bad_inputs/ (one file per kind, each with
the one-line message capdyn check prints): loaded from Python, each raises
CapdynError whose message is that line without "capdyn: error: "."""
import glob
import math
import os

import numpy as np
import pytest

import capdyn
from capdyn import CapdynError
from conftest import ROOT, scenario
from test_views_state import pendulum

BAD = os.path.join(ROOT, "tests", "bad_inputs")


def _case_args(base):
    """--set overrides of NN_name.args (one argument per line)"""
    p = os.path.join(BAD, base + ".args")
    if not os.path.exists(p):
        return []
    args = [a for a in open(p).read().split("\n") if a]
    sets, i = [], 0
    while i < len(args):
        a = args[i]
        if a == "--set":
            sets.append(args[i + 1])
            i += 2
        elif a.startswith("--set="):
            sets.append(a[6:])
            i += 1
        else:
            raise AssertionError(f"{base}.args: unexpected argument {a}")
    return sets


CASES = sorted(os.path.basename(p)[:-5] for p in glob.glob(os.path.join(BAD, "[0-9][0-9]_*.toml")))


def test_bad_inputs_are_all_there():
    assert len(CASES) >= 40


@pytest.mark.parametrize("base", CASES)
def test_bad_scenario_raises_the_engines_message(base, monkeypatch):
    monkeypatch.chdir(BAD)
    want = open(os.path.join(BAD, base + ".expected")).read()
    assert want.startswith("capdyn: error: ") and want.endswith("\n")
    with pytest.raises(CapdynError) as e:
        capdyn.load(base + ".toml", set=_case_args(base))
    assert e.value.message == want[len("capdyn: error: "):-1]
    assert e.value.status in (capdyn.lib.CD_EINVAL, capdyn.lib.CD_EIO)


def test_bad_toml_string_names_the_string():
    text = open(os.path.join(BAD, "15_unknown_system_key.toml")).read()
    with pytest.raises(CapdynError) as e:
        capdyn.loads(text, name="<mine>")
    assert e.value.message == "<mine>:6:1: key 'system[0].mas': unknown key (did you mean 'mass'?)"


def test_load_arguments():
    with pytest.raises(CapdynError, match="cannot read scenario file '/no/such.toml'"):
        capdyn.load("/no/such.toml")
    with pytest.raises(TypeError):
        capdyn.load(42)
    with pytest.raises(ValueError, match="NUL"):
        capdyn.load("a\0b.toml")
    with pytest.raises(TypeError):
        capdyn.load(scenario("paper_fig3_impact.toml"), set=[1.5])
    with pytest.raises(ValueError, match="KEY=VALUE"):
        capdyn.load(scenario("paper_fig3_impact.toml"), set=["simulation.duration"])
    with pytest.raises(TypeError):
        capdyn.load(scenario("paper_fig3_impact.toml"), set={"simulation.duration": object()})
    with pytest.raises(CapdynError, match="unknown key"):
        capdyn.load(scenario("paper_fig3_impact.toml"), set={"simulation.durationx": 1.0})
    with pytest.raises(CapdynError, match="simulation.duration"):
        capdyn.load(scenario("paper_fig3_impact.toml"), set={"simulation.duration": "long"})
    with pytest.raises(TypeError):
        capdyn.loads(b"title = 'x'")
    # a dict override of every TOML type is written as TOML the loader accepts
    sc = capdyn.load(scenario("paper_fig3_impact.toml"),
                     set={"simulation.duration": 0.25, "title": 'a "quoted" title'})
    assert sc.duration == 0.25 and sc.title == 'a "quoted" title'


def test_model_arguments():
    m = capdyn.Model()
    with pytest.raises(CapdynError, match="base mass must be a positive finite number, got -1"):
        m.add_system(mass=-1.0)
    with pytest.raises(ValueError, match="finite"):
        m.add_system(mass=float("nan"))
    with pytest.raises(TypeError):
        m.add_system(mass="heavy")
    with pytest.raises(ValueError, match="expected 9 numbers"):
        m.add_system(inertia=[1, 2, 3])
    with pytest.raises(TypeError, match="unknown field 'mas'"):
        m.add_system(mas=1.0)
    with pytest.raises(ValueError, match="NUL"):
        m.add_system(name="a\0b")
    with pytest.raises(ValueError, match="expected one of"):
        m.add_system(type="floating")
    s = m.add_system(name="rig", type="fixed")
    with pytest.raises(ValueError, match="sys"):
        m.add_link(5, 0)
    with pytest.raises(ValueError, match="parent"):
        m.add_link(s, 99)
    with pytest.raises(KeyError):
        m.add_link(s, "nobody")
    with pytest.raises(TypeError):
        m.add_link(s, 0.5)
    with pytest.raises(ValueError, match="expected an integer in"):
        m.add_checkpoint(2**40, [0, 0, 0])
    with pytest.raises(ValueError, match="fit a C int"):
        m.add_law(pull=2**40)
    link = m.add_link(s, 0, axis=[1, 0, 0], com=[0, 0.5, 0])
    with pytest.raises(CapdynError):
        m.add_link(s, 0, axis=[0, 0, 0])
    with pytest.raises(ValueError, match="n x 3"):
        m.add_shape(link, "convex", verts=[1, 2])
    with pytest.raises(ValueError, match="shape"):
        m.add_pair(s, 0, 0)
    with pytest.raises(ValueError, match="at least one joint"):
        m.add_actuator([])
    with pytest.raises(ValueError, match="ratios"):
        m.add_actuator([link], ratios=[1, 2])
    with pytest.raises(ValueError, match="expected one of"):
        m.options.stepper = "euler"
    with pytest.raises(CapdynError, match="tolerances"):
        m.options.rtol = -1.0
    with pytest.raises(ValueError, match="not finalized"):
        capdyn.Simulation(m)
    with pytest.raises(TypeError):
        capdyn.Simulation("model")
    m.finalize()
    with pytest.raises(CapdynError):
        m.add_link(s, link)
    with pytest.raises(ValueError, match="finalized"):
        m.gravity = [0, 0, -1]
    assert capdyn.Simulation(m).t == 0.0  # still usable


def test_simulation_arguments():
    sim = capdyn.Simulation(pendulum())
    with pytest.raises(CapdynError, match="h must be positive and finite, got -1"):
        sim.step(-1.0)
    with pytest.raises(ValueError):
        sim.step(float("inf"))
    with pytest.raises(TypeError):
        sim.step("1ms")
    with pytest.raises(CapdynError, match="not before the current time"):
        sim.advance(-1.0)
    with pytest.raises(ValueError):
        sim.system(3)
    with pytest.raises(KeyError):
        sim.system("nope")
    with pytest.raises(ValueError, match="state of"):
        sim.state_set(np.zeros(3))
    with pytest.raises(ValueError):
        sim.state_set(["a"] * sim.state_size())
    with pytest.raises(CapdynError):  # the right size, not a state (its signature)
        sim.state_set(np.zeros(sim.state_size()))
    with pytest.raises(ValueError, match="another model"):
        sim.state_copy(capdyn.Simulation(pendulum()))
    with pytest.raises(TypeError):
        sim.state_copy(None)
    with pytest.raises(AttributeError, match="fixed when the simulation is created"):
        sim.options.stepper = "rk4"
    with pytest.raises(AttributeError):
        sim.options.no_such_option = 1
    with pytest.raises(ValueError, match="needs until"):
        sim.run()
    with pytest.raises(ValueError, match="positive"):
        sim.run(until=1.0, dt=0.0)
    with pytest.raises(ValueError, match="samples"):
        sim.run(until=1.0, dt=1e-12)
    with pytest.raises(TypeError):
        sim.run(until=1.0, dt=0.1, on_sample=3)
    with pytest.raises(ValueError, match="monitor"):
        sim.run(until=1.0, dt=0.1, until_verdict=True)
    # non-finite inputs written through the views: the engine's numerical error
    sim.ctrl[0] = float("nan")
    with pytest.raises(CapdynError) as e:
        sim.step(1e-3)
    assert e.value.status == capdyn.lib.CD_ENUMERIC and "non-finite" in e.value.message
    sim.ctrl[0] = 0.0
    sim.y[:] = np.nan
    with pytest.raises(CapdynError, match="non-finite"):
        sim.advance(sim.t + 0.1)
    sim.reset()  # and the simulation goes on
    sim.advance(0.01)
    assert math.isfinite(sim.q(0)[0])


def test_exceptions_in_callbacks_propagate():
    sim = capdyn.Simulation(capdyn.load(scenario("paper_fig3_impact.toml")))

    def boom(s):
        if s.t > 0.005:
            raise RuntimeError("stop here")
    with pytest.raises(RuntimeError, match="stop here"):
        sim.run(until=0.05, dt=1e-3, on_sample=boom, interpolate=True)
    t = sim.t
    assert 0.005 < t < 0.05
    with pytest.raises(RuntimeError, match="stop here"):
        sim.run(until=0.05, dt=1e-3, on_sample=boom)
    # a true return value stops the run cleanly
    res = sim.run(until=0.05, dt=1e-3, on_sample=lambda s: True)
    assert res.status == "ok" and res.nsamples == 1


def test_closed_simulation():
    sim = capdyn.Simulation(pendulum())
    sim.close()
    for f in (lambda: sim.step(1e-3), lambda: sim.t, lambda: sim.y, lambda: sim.state_get(),
              lambda: sim.options.rtol, lambda: sim.run(until=1, dt=0.1)):
        with pytest.raises(ValueError, match="closed"):
            f()
    sim.close()  # twice: nothing


def test_results_of_a_non_results_file(tmp_path):
    p = tmp_path / "x.h5"
    p.write_text("not hdf5")
    with pytest.raises(OSError):
        capdyn.Results(str(p))


BAD_VALUES = [None, "x", b"x", float("nan"), float("inf"), -1, 2**70, -2**70, [], [1.0] * 50, object(), {"a": 1},
              np.array([np.nan]), True]


def test_every_method_with_every_bad_value():
    """Each argument of each call, in turn, replaced by each bad value:
    only Python exceptions (or a normal return), never a crash; the
    simulation is still usable afterwards."""
    sc = capdyn.load(scenario("paper_fig3_impact.toml"))
    sim = capdyn.Simulation(sc)
    sim.options.max_steps = 20000  # a huge but valid end time stops with the step budget (CD_EMAXSTEPS)
    m = capdyn.Model()
    calls = [
        (sim.step, [1e-3]), (sim.advance, [0.01]), (sim.system, [0]), (sim.q, [0]), (sim.qd, [0]),
        (sim.state_set, [sim.state_get()]), (sim.state_copy, [sim]), (sim.mass_matrix, [0]), (sim.momentum, [0]),
        (lambda until, dt: sim.run(until=until, dt=dt), [sim.t + 0.002, 1e-3]),
        (lambda v: setattr(sim, "t", v), [0.0]), (lambda v: setattr(sim.options, "rtol", v), [1e-9]),
        (lambda v: setattr(sim.options, "max_evals", v), [0]),
        (lambda v: setattr(sim.options, "max_steps", v), [20000]),
        (capdyn.load, [scenario("paper_fig3_impact.toml")]), (capdyn.loads, ["title = 'x'"]),
        (m.add_system, []), (lambda **kw: m.add_system(**kw), []),
        (m.add_link, [0, 0]), (m.add_checkpoint, [0, [0, 0, 0], 0.01]), (m.add_shape, [0, "sphere", [0, 0, 0]]),
        (m.add_pair, [0, 0, 0]), (m.add_actuator, [[1]]), (m.set_joint, [1]), (m.prescribe_base, [0, [0] * 3, [0] * 3]),
        (m.add_finger, [[1], ([0, 1], [0, 1])]), (m.body_id, ["x"]), (m.system_id, ["x"]),
        (m.actuator_id, ["x"]), (capdyn.Simulation, [sc]), (capdyn.Results, ["/no/such.h5"]),
    ]
    m.add_system(name="rig", type="fixed")
    n = 0
    for fn, good in calls:
        for i in range(max(1, len(good))):
            for bad in BAD_VALUES:
                args = list(good)
                if args:
                    args[i] = bad
                else:
                    args = [bad]
                try:
                    fn(*args)
                except (CapdynError, TypeError, ValueError, KeyError, OSError, IndexError):
                    pass
                n += 1
    for bad in BAD_VALUES:
        for k in ("mass", "inertia", "pos", "quat", "name", "vel"):
            try:
                m.add_system(**{k: bad})
            except (CapdynError, TypeError, ValueError):
                pass
            n += 1
    assert n > 400
    sim.reset()
    sim.advance(0.01)
    assert sim.t == 0.01


def test_garbage_through_the_views():
    """Huge, infinite, NaN values written into the state and the inputs
    through the writable views: each later call returns or raises
    CapdynError (the engine checks what it integrates), never crashes; the
    state restored, the simulation runs on."""
    rng = np.random.default_rng(1)
    sim = capdyn.Simulation(capdyn.load(scenario("paper_fig5_envelope_grasp.toml")))
    sim.options.max_steps = 2000
    base = sim.state_get()
    outcomes = {"ok": 0, "error": 0}
    for trial in range(40):
        sim.state_set(base)
        k = trial % 4
        if k == 0:
            sim.y[:] = rng.normal(0, 1, sim.y.size) * 10.0 ** float(rng.integers(-3, 300))
        elif k == 1:
            sim.y[rng.integers(0, sim.y.size)] = rng.choice([0.0, 1e308, -1e308, np.nan, np.inf])
        elif k == 2:
            sim.qfrc_applied[:] = rng.choice([1e308, -1e308, np.nan, 0.0], sim.qfrc_applied.size)
        else:
            sim.xfrc_applied[:] = rng.normal(0, 1, sim.xfrc_applied.shape) * 1e200
        try:
            sim.advance(sim.t + 0.01)
            outcomes["ok"] += 1
        except CapdynError:
            outcomes["error"] += 1
    assert outcomes["error"] > 0 and sum(outcomes.values()) == 40
    sim.state_set(base)
    sim.advance(0.01)
    assert sim.t == 0.01
