"""Views on the engine's memory and the complete state.

- every state view (y, q, qd, the system's base parts) and the input views
  share memory with the engine's data (np.shares_memory, and a write
  through a view is what the engine integrates);
- save, continue, restore, continue again is bit-identical (sim.h), for a
  model built in Python, for a contact scenario with events, and for a
  scenario with the built-in capture controller, whose memory is part of
  state_get();
- a view outlives its simulation without dangling.
"""
import gc
import math

import numpy as np
import pytest

import capdyn
from conftest import scenario


def pendulum(q0=1.0, gravity=-9.81, stepper=None):
    """A 1 kg point-like bob at 0.5 m on a revolute joint about x, fixed base."""
    m = capdyn.Model(gravity=[0, 0, gravity])
    s = m.add_system(name="rig", type="fixed")
    inertia = [1e-4, 0, 0, 0, 1e-4, 0, 0, 0, 1e-4]
    m.add_link(s, m.base_body(s), name="arm", axis=[1, 0, 0], mass=1.0, com=[0, 0.5, 0], inertia=inertia, q0=q0)
    m.add_actuator(["rig/arm"], type="none", name="motor")
    if stepper:
        m.options.stepper = stepper
    return m.finalize()


def test_state_views_share_memory():
    sim = capdyn.Simulation(pendulum())
    y = sim.y
    st = sim.system(0)
    assert st.pos is None and st.quat is None  # a fixed base has no base state
    for v in (st.q, st.qd, sim.q(0), sim.qd(0)):
        assert np.shares_memory(v, y)
    assert sim.q(0) is sim.q(0)  # the same view every time, never a copy
    for v in (sim.ctrl, sim.qfrc_applied, sim.xfrc_applied, sim.udot, sim.tau, sim.body_x, sim.body_R):
        assert not v.flags.owndata
    # a step changes the values in place: the view read before is current
    q_before = float(st.q[0])
    sim.step(1e-3)
    assert st.q[0] != q_before and st.q[0] == y[0]
    # outputs are read-only, inputs writable
    with pytest.raises(ValueError):
        sim.udot[0] = 1.0
    with pytest.raises(ValueError):
        sim.slot_mode[:] = 0
    sim.ctrl[0] = 0.0


def test_ctrl_view_is_the_engines_input():
    """A torque written through the view drives the joint: with gravity off,
    a constant torque tau on inertia I (1 kg at 0.5 m, plus I_xx) gives
    q(t) = q0 + tau t^2 / (2 I) (rk8pd, rtol 1e-9: relative error < 1e-8)."""
    sim = capdyn.Simulation(pendulum(q0=0.0, gravity=0.0))
    sim.ctrl[0] = 0.3
    sim.advance(0.5)
    I = 1.0 * 0.5 ** 2 + 1e-4
    expected = 0.3 * 0.5 ** 2 / (2 * I)
    assert abs(sim.q(0)[0] - expected) < 1e-8 * expected
    assert np.shares_memory(sim.ctrl, sim.ctrl)


def test_writing_y_through_a_view_restarts_from_it():
    """q written through the view: the pendulum released from rest at q
    keeps its energy m g h (rk8pd: to 1e-9 relative) from that state."""
    sim = capdyn.Simulation(pendulum(q0=0.2))
    sim.q(0)[0] = 1.0
    sim.qd(0)[0] = 0.0
    sim.advance(0.3)
    ke, *_ = sim.momentum(0)
    g, r = 9.81, 0.5
    # the bob's height z = r sin(q) (com at +y rotated about x); energy drop = kinetic energy
    pe0 = 1.0 * g * r * math.sin(1.0)
    pe = 1.0 * g * r * math.sin(sim.q(0)[0])
    assert abs(ke - (pe0 - pe)) < 1e-9 * pe0 + 1e-10


def _continue_bits(sim, t1, t2):
    sim.advance(t1)
    saved = sim.state_get()
    sim.advance(t2)
    first = sim.state_get()
    sim.state_set(saved)
    assert sim.t == t1
    sim.advance(t2)
    second = sim.state_get()
    return first, second


def test_save_continue_restore_continue_model():
    first, second = _continue_bits(capdyn.Simulation(pendulum()), 0.25, 0.5)
    assert np.array_equal(first.view(np.uint64), second.view(np.uint64))


def test_save_continue_restore_continue_contacts():
    """The paper's Fig. 3 impact: contact onset and separation events
    between the save point (0.1 s) and the end (0.4 s)."""
    sc = capdyn.load(scenario("paper_fig3_impact.toml"))
    sim = capdyn.Simulation(sc)
    sim.advance(0.1)
    saved = sim.state_get()
    ev0 = sim.stats["nevents"]
    sim.advance(0.4)
    assert sim.stats["nevents"] > ev0  # events happened in between
    first = sim.state_get()
    sim.state_set(saved)
    sim.advance(0.4)
    assert np.array_equal(first.view(np.uint64), sim.state_get().view(np.uint64))
    # into another simulation of the same scenario, through state_copy
    other = capdyn.Simulation(sc)
    other.state_set(saved)
    sim2 = capdyn.Simulation(sc)
    sim2.state_copy(other)
    sim2.advance(0.4)
    assert np.array_equal(first.view(np.uint64), sim2.state_get().view(np.uint64))


def _advance_chunks(sim, t_end, chunk=0.1):
    """advance_to() of tests/test_capture.c: cd_sim_advance in 0.1 s calls."""
    while sim.t < t_end - 1e-12:
        sim.advance(min(sim.t + chunk, t_end))


def test_save_continue_restore_continue_controller():
    """A capture scenario with the built-in controller ([control]): its
    memory is saved with the data's state; restoring it into a new
    simulation (as after a restart) continues bit-identically. The run is
    advanced in 0.1 s calls, as tests/test_capture.c does."""
    sc = capdyn.load(scenario("capture_handrail_tumbling.toml"))
    sim = capdyn.Simulation(sc)
    assert sc.has_control and sim.state_size() > capdyn.lib.cd_state_size(sc._mp)
    _advance_chunks(sim, 0.2)
    saved = sim.state_get()
    _advance_chunks(sim, 0.4)
    first = sim.state_get()
    fresh = capdyn.Simulation(sc)
    fresh.state_set(saved)
    _advance_chunks(fresh, 0.4)
    assert np.array_equal(first.view(np.uint64), fresh.state_get().view(np.uint64))
    sim.state_set(saved)
    _advance_chunks(sim, 0.4)
    assert np.array_equal(first.view(np.uint64), sim.state_get().view(np.uint64))


@pytest.mark.xfail(strict=True, reason="engine: with the built-in controller installed, a checkpoint taken after "
                   "one cd_sim_advance call from 0 to 0.2 s does not rerun bit-identically (32 state entries differ "
                   "at 0.4 s; the same in C, without Python; without the controller it does): reported, not fixed here")
def test_save_after_one_long_call_with_controller():
    sc = capdyn.load(scenario("capture_handrail_tumbling.toml"))
    sim = capdyn.Simulation(sc)
    sim.advance(0.2)
    saved = sim.state_get()
    sim.advance(0.4)
    first = sim.state_get()
    sim.state_set(saved)
    sim.advance(0.4)
    assert np.array_equal(first.view(np.uint64), sim.state_get().view(np.uint64))


def test_views_outlive_the_simulation():
    sim = capdyn.Simulation(pendulum())
    sim.step(1e-3)
    y, q, fn = sim.y, sim.q(0), sim.slot_fn
    last = y.copy()
    sim.close()
    with pytest.raises(ValueError, match="closed"):
        sim.step(1e-3)
    del sim
    gc.collect()
    # the memory is still there (owned by the view), with the last values
    assert np.array_equal(y, last) and q[0] == last[0] and fn.size == 0
    y[0] = 2.0  # writing it harms nothing


def test_reset_reruns_bit_identically():
    """reset() (cd_data_reset, a fresh controller) and the same run again:
    the same state, bit for bit."""
    sim = capdyn.Simulation(capdyn.load(scenario("capture_handrail_tumbling.toml")))
    sim.advance(0.1)
    first = sim.state_get()
    sim.reset()
    assert sim.t == 0.0
    sim.advance(0.1)
    assert np.array_equal(first.view(np.uint64), sim.state_get().view(np.uint64))
