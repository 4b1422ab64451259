"""The results reader against `capdyn export` (same column names, same
numbers to export's 10 significant digits), scenarios from TOML strings,
and a model built from Python checked against a closed-form answer."""

import numpy as np
import pytest

import capdyn
from conftest import run_cli, scenario


@pytest.fixture(scope="module")
def impact_h5(tmp_path_factory, capdyn_bin):
    out = str(tmp_path_factory.mktemp("res") / "impact.h5")
    run_cli("run", scenario("paper_fig3_impact.toml"), "-q", "-o", out, "--set", "simulation.duration=0.1")
    return out


def export_table(path, *what):
    text = run_cli("export", path, *what)
    lines = text.splitlines()
    names = lines[0][2:].split()
    rows = [ln.split() for ln in lines if ln and not ln.startswith("#")]
    return names, rows


def check_same(table, names, rows, strings=()):
    assert list(table) == names
    for j, k in enumerate(names):
        col = [r[j] for r in rows]
        if k in strings:
            assert [str(x) for x in table[k]] == col, k
        else:
            ref = np.array([float(x) for x in col])
            got = np.asarray(table[k], dtype=float)
            assert got.shape == ref.shape, k
            # export prints %.10g
            assert np.allclose(got, ref, rtol=1e-9, atol=0, equal_nan=True), k


def test_results_read_like_capdyn_export(impact_h5):
    with capdyn.Results(impact_h5) as r:
        assert r.n == 1001  # output_dt 1e-4 s, 0.1 s
        sysname = r.systems()[0]
        check_same(r.system(sysname), *export_table(impact_h5, "system", sysname))
        check_same(r.contacts(), *export_table(impact_h5, "contacts"))
        check_same(r.contacts(active=True), *export_table(impact_h5, "contacts", "--active"))
        check_same(r.slot(0), *export_table(impact_h5, "slot", "0"))
        check_same(r.time(), *export_table(impact_h5, "time"))
        ev = r.events()
        check_same(ev, *export_table(impact_h5, "events"), strings=("kind_name", "owner_kind", "body_a", "body_b"))
        assert len(ev["t"]) > 0
        with pytest.raises(IndexError):
            r.slot(5)
        with pytest.raises(KeyError):
            r.system("nope")


def test_loads_equals_load():
    path = scenario("paper_fig3_impact.toml")
    text = open(path).read()
    a = capdyn.Simulation(capdyn.loads(text, set={"simulation.duration": 0.05}))
    b = capdyn.Simulation(capdyn.load(path, set=["simulation.duration=0.05"]))
    ra, rb = a.run(), b.run()
    assert ra.t == rb.t == 0.05 and ra.nrhs == rb.nrhs
    assert np.array_equal(a.state_get(), b.state_get())


def test_ball_resting_on_a_plane_built_in_python():
    """A 2 kg sphere check point on a free body, gravity 9.81 down onto a
    plane, linear law K = 1e5 N/m with damping: it comes to rest where the
    contact carries its weight, x = m g / K = 0.1962 mm (to 1e-6 relative),
    and the normal force equals m g."""
    mass, g, K = 2.0, 9.81, 1e5
    m = capdyn.Model(gravity=[0, 0, -g])
    ground = m.add_system(name="ground", type="fixed")
    plane = m.add_shape(m.base_body(ground), "plane")
    ball = m.add_system(name="ball", type="free", mass=mass, inertia=[1e-3, 0, 0, 0, 1e-3, 0, 0, 0, 1e-3],
                        pos=[0, 0, 0.0])
    m.add_checkpoint(m.base_body(ball), [0, 0, 0], 0.0)
    law = m.add_law(K=K, D=400.0, mu_s=0.5, mu_k=0.5)
    m.add_pair(ball, plane, law)
    m.finalize()
    sim = capdyn.Simulation(m)
    sim.system(ball).pos[2] = 0.001  # 1 mm above the plane: it falls, bounces, settles
    sim.advance(2.0)
    x_expected = mass * g / K
    assert sim.slot_mode[0] != 0
    assert abs(sim.slot_x[0] - x_expected) < 1e-6 * x_expected
    assert abs(sim.slot_fn[0] - mass * g) < 1e-6 * mass * g
    assert abs(sim.system(ball).pos[2] + x_expected) < 1e-6 * x_expected
    ev = sim.events()
    assert ev and ev[0]["kind_name"] == "onset"
