"""Hands and targets built from Python with the builders (include/capdyn/
build.h), when this capdyn has them: examples/space_gripper_capture.c
built through capdyn.Model gives the same model (every state entry and size)
as the C calls, and the same outcome: after 4 s both fingers are clutched
and the cylinder is held (speed below 1e-3 m/s, centred within half the
finger spacing)."""

import numpy as np
import pytest

import capdyn
from capdyn import lib

needs = pytest.mark.skipif(not capdyn.HAVE_BUILDERS, reason="this capdyn has no include/capdyn/build.h")


def test_without_builders_the_calls_say_so():
    if capdyn.HAVE_BUILDERS:
        assert callable(capdyn.Model().add_hand)
        return
    with pytest.raises(NotImplementedError, match="no builders"):
        capdyn.Model().add_hand()


def space_gripper_capture():
    """examples/space_gripper_capture.c, through capdyn.Model."""
    pi = 3.14159265358979
    m = capdyn.Model()
    m.options.rtol, m.options.atol, m.options.h_max = 1e-8, 1e-10, 1e-3
    obj = m.add_target(name="object", mass=0.3,
                       inertia=[1.81875e-4, 0, 0, 0, 1.81875e-4, 0, 0, 0, 1.8375e-4],
                       pos=[0.005, 0.105, 0], vel=[0, -0.03, 0],
                       shapes=[dict(type="cylinder", radius=0.035, length=0.06)])
    d = lib.cd_hand_desc_default()
    hand = m.add_hand(type="space", link_length=[d.link_length[0], 0.07], link_mass=[0.05, 0.04], joint_limited=1,
                      joint_upper=[pi, pi], close_angle=110.0 * pi / 180.0, close_start=0.6, torque=0.05,
                      clutch_threshold=0.25, torque_limit=0.3)
    m.add_hand_drive(hand, law=("rule", 1e3, 10, 0.3, 1.0, 0.5), targets=[obj])
    return m.finalize(), obj, hand


@needs
def test_space_gripper_capture_from_python():
    m, obj, hand = space_gripper_capture()
    assert hand.nfinger == 2 and hand.nclutch == 2 and len(hand.finger_body[0]) == 2
    sim = capdyn.Simulation(m, event_capacity=1024)
    sim.advance(4.0)
    clutched = sum(sim.finger_mode[f] != 0 for f in hand.clutch)
    b = m.base_body(obj)
    v = sim.body_v[b]
    spacing = lib.cd_hand_desc_default().spacing
    assert clutched == 2
    assert np.linalg.norm(v) < 1e-3
    assert abs(sim.body_x[b, 0]) < spacing / 2


@needs
def test_finger_stop_law_per_link_reaches_the_description():
    """joint_stop_K / joint_stop_D (cd_hand_desc, one per finger link) are
    per-link arrays like joint_lower: the given links set, the rest 0 (the
    default law); the hand builds with them."""
    pi = 3.14159265358979
    m = capdyn.Model()
    hand = m.add_hand(type="soft", link_length=[0.08, 0.07], link_mass=[0.15, 0.1], joint_limited=1,
                      joint_lower=[0.0, 0.0], joint_upper=[pi, pi], joint_stop_D=[2.6, 0.41], joint_stop_K=[500.0])
    d = hand._desc
    assert list(d.joint_stop_D[0:3]) == [2.6, 0.41, 0.0]
    assert list(d.joint_stop_K[0:2]) == [500.0, 0.0]
    assert hand.nfinger == 2 and hand.nlink == 2


@needs
def test_builder_errors_are_the_engines():
    m = capdyn.Model()
    with pytest.raises(capdyn.CapdynError):
        m.add_target(mass=-1.0)
    with pytest.raises(ValueError, match="expected one of"):
        m.add_hand(type="claw")
    with pytest.raises(ValueError, match="at most"):
        m.add_hand(link_length=[0.05] * 100)
    with pytest.raises(TypeError):
        m.add_target(shapes=[3])
    with pytest.raises(TypeError):
        m.add_hand_drive("hand")
