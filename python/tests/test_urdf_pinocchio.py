"""URDF import (issue 25, docs/urdf.md) against Pinocchio: the same URDF
file loaded by capdyn ([[system]] urdf = ..., base = "free") and by
Pinocchio (buildModelFromUrdf with a JointModelFreeFlyer root) gives the
same mass matrix, centre of mass, spatial momentum and forward dynamics on
random states, to 1e-10 relative, for the three models of tests/urdf/
(a 7-DoF arm on a free base, the ETS-VII-like chaser, a hand with fixed
joints).

Frames (docs/urdf.md, "Frames"). Pinocchio's free-flyer configuration is
the root LINK frame: q = [p (world), quaternion (x, y, z, w)], velocity
nu = [v_l, w_l], the linear velocity of the root frame origin and the
angular velocity, both in the root frame (LOCAL). capdyn's base state is
the base CoM c = p + R c_l (c_l: the root's CoM in its frame, fixed links
merged), quaternion (w, x, y, z), CoM velocity and angular velocity both
in WORLD axes. So u = T nu with
    v0 = R (v_l + w_l x c_l),  w0 = R w_l,  qd = P qd_pin,
    T = [[R, -R [c_l x], 0], [0, R, 0], [0, 0, P]],
and the kinetic energy u^T H u = nu^T M nu gives M = T^T H T; a
generalized force maps as tau_pin = T^T tau_capdyn; accelerations map as
    v0dot = R (a_v + a_w x c_l + w_l x (v_l + w_l x c_l)),  w0dot = R a_w
(Pinocchio's free-flyer acceleration is d/dt of the LOCAL components).
Tolerances: relative in the max norm of each compared quantity (entries
near zero are compared against the largest one)."""
import os
import xml.etree.ElementTree as ET

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")
import capdyn  # noqa: E402

from conftest import ROOT  # noqa: E402

URDF_DIR = os.path.join(ROOT, "tests", "urdf")
MODELS = ["arm7.urdf", "chaser.urdf", "hand.urdf"]
RTOL = 1e-10
NSTATE = 5


def skew(a):
    return np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])


def rel(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300)


def load_both(tmp_path, name):
    path = os.path.join(URDF_DIR, name)
    sc = tmp_path / "urdf.toml"
    sc.write_text('[simulation]\nduration = 0.1\ngravity = [0.0, 0.0, 0.0]\n\n'
                  f'[[system]]\nname = "robot"\nurdf = "{path}"\nbase = "free"\n')
    scen = capdyn.load(str(sc))
    sim = capdyn.Simulation(scen)
    sim.scenario = scen
    model = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer())
    model.gravity.linear[:] = 0.0
    child = {j.get("name"): j.find("child").get("link") for j in ET.parse(path).getroot().iter("joint")}
    return sim, model, child


def random_state(rng, sim, model, child):
    """A random state for both: (q_pin, v_pin, R, c_l, perm) with the
    capdyn state written into sim; perm[k_pin] = capdyn joint index."""
    m = sim._m
    b0 = m.sys_body_adr[0]
    c_l = model.inertias[1].lever.copy()  # root CoM in the root frame, fixed links merged (Pinocchio's own merge)
    quat = rng.normal(size=4)
    quat /= np.linalg.norm(quat)
    R = pin.Quaternion(quat[0], quat[1], quat[2], quat[3]).toRotationMatrix()  # (w, x, y, z)
    p = rng.uniform(-1, 1, 3)
    v_l, w_l = rng.uniform(-0.5, 0.5, 3), rng.uniform(-0.5, 0.5, 3)
    q = pin.neutral(model)
    v = np.zeros(model.nv)
    q[0:3] = p
    q[3:7] = [quat[1], quat[2], quat[3], quat[0]]  # Pinocchio: (x, y, z, w)
    v[0:3], v[3:6] = v_l, w_l
    st = sim.system(0)
    perm = []
    for j in range(2, model.njoints):
        jm = model.joints[j]
        body = sim.scenario.body_id("robot/" + child[model.names[j]])
        k = m.body_dof[body] - m.sys_v_adr[0] - 6
        perm.append(k)
        lo, hi = model.lowerPositionLimit[jm.idx_q], model.upperPositionLimit[jm.idx_q]
        if jm.nq == 2:  # continuous: (cos, sin)
            th = rng.uniform(-np.pi, np.pi)
            q[jm.idx_q:jm.idx_q + 2] = [np.cos(th), np.sin(th)]
        else:
            lo, hi = max(lo, -3.0), min(hi, 3.0)
            th = rng.uniform(lo + 0.1 * (hi - lo), hi - 0.1 * (hi - lo))  # inside the stops
            q[jm.idx_q] = th
        v[jm.idx_v] = rng.uniform(-0.5, 0.5)
        st.q[k] = th
        st.qd[k] = v[jm.idx_v]
    assert sorted(perm) == list(range(len(perm))), "every capdyn joint is a Pinocchio joint"
    assert b0 == 0
    st.pos[:] = p + R @ c_l
    st.quat[:] = quat
    st.vel[:] = R @ (v_l + np.cross(w_l, c_l))
    st.angvel[:] = R @ w_l
    return q, v, R, c_l, perm


def T_of(R, c_l, perm, n):
    T = np.zeros((n, n))
    T[0:3, 0:3] = R
    T[0:3, 3:6] = -R @ skew(c_l)
    T[3:6, 3:6] = R
    for kp, kc in enumerate(perm):
        T[6 + kc, 6 + kp] = 1.0
    return T


@pytest.mark.parametrize("name", MODELS)
def test_urdf_matches_pinocchio(tmp_path, name):
    sim, model, child = load_both(tmp_path, name)
    data = model.createData()
    rng = np.random.default_rng(25)
    worst = {"M": 0.0, "com": 0.0, "momentum": 0.0, "fd": 0.0}
    for _ in range(NSTATE):
        q, v, R, c_l, perm = random_state(rng, sim, model, child)
        n = model.nv
        assert sim._m.sys_ndof[0] == n
        T = T_of(R, c_l, perm, n)
        # mass matrix
        H = sim.mass_matrix(0)
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        worst["M"] = max(worst["M"], rel(T.T @ H @ T, M))
        # centre of mass and spatial momentum (P; L about the CoM, world axes)
        ke, P, Lc, Lo, com = sim.momentum(0)
        c_pin = pin.centerOfMass(model, data, q)
        hg = pin.computeCentroidalMomentum(model, data, q, v)
        worst["com"] = max(worst["com"], rel(com, c_pin))
        worst["momentum"] = max(worst["momentum"], rel(np.concatenate([P, Lc]), np.concatenate([hg.linear, hg.angular])))
        assert abs(ke - 0.5 * v @ M @ v) <= RTOL * abs(ke)
        # forward dynamics with random generalized forces (plus the URDF's joint damping, as capdyn applies it)
        sim.qfrc_applied[:] = rng.uniform(-5, 5, n)
        sim.forward()
        tau = np.array(sim.tau)
        a = pin.aba(model, data, q, v, T.T @ tau)
        a_v, a_w, v_l, w_l = a[0:3], a[3:6], v[0:3], v[3:6]
        u_pin = np.zeros(n)
        u_pin[0:3] = R @ (a_v + np.cross(a_w, c_l) + np.cross(w_l, v_l + np.cross(w_l, c_l)))
        u_pin[3:6] = R @ a_w
        for kp, kc in enumerate(perm):
            u_pin[6 + kc] = a[6 + kp]
        worst["fd"] = max(worst["fd"], rel(sim.udot, u_pin))
    for k, e in worst.items():
        assert e <= RTOL, f"{name}: {k} differs from Pinocchio by {e:.3g} relative (tolerance {RTOL:g})"
    print(f"{name}: worst relative differences from Pinocchio over {NSTATE} random states: "
          + ", ".join(f"{k} {e:.2e}" for k, e in worst.items()))
