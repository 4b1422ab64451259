"""examples/control_loop.c's model and 1 kHz loop driven from Python: the
trajectory (t and the whole state y after every tick) is bit-identical to
the C example's own code (control_loop_trace.c includes the example and
prints it). Both compute the same IEEE-754 operations in the same order
(the library built with -ffp-contract=off, the harness too), so any
difference is a difference in what the binding passes or reads."""
import math
import os
import subprocess

import numpy as np
import pytest

import capdyn
from capdyn import lib
from conftest import BUILD, ROOT

NJ, RATE_HZ, T_MOVE, T_END, MAX_EVALS = 3, 1000, 2.0, 5.0, 20


def build_model(q0):
    """build_model() of examples/control_loop.c, through capdyn.Model."""
    m = capdyn.Model()
    base = lib.cd_system_desc_default()
    inertia = [0.0] * 9
    inertia[0], inertia[4], inertia[8] = 20.0, 25.0, 30.0
    sys = m.add_system(name="spacecraft", type="free", mass=150.0, inertia=inertia, vel=[0.02, -0.01, 0.005],
                       angvel=[0.01, 0.02, -0.015], pos=list(base.pos), quat=list(base.quat))
    mass, length = [6.0, 4.0, 2.0], [0.5, 0.5, 0.4]
    mount, elbow, z, y = [0.6, 0, 0], [0.5, 0, 0], [0, 0, 1], [0, 1, 0]
    links, acts = [], []
    for j in range(NJ):
        d = lib.cd_link_desc_default()
        com = list(d.com)
        com[0] = 0.5 * length[j]
        I = [0.0] * 9
        I[0] = 1e-3 * mass[j]
        I[4] = I[8] = mass[j] * length[j] * length[j] / 12.0
        parent = m.base_body(sys) if j == 0 else links[j - 1]
        links.append(m.add_link(sys, parent, type="revolute", pos=mount if j == 0 else elbow,
                                axis=z if j == 0 else y, mass=mass[j], com=com, inertia=I, q0=q0[j]))
        acts.append(m.add_actuator([links[j]], ratios=[1.0], type="none"))
    m.options.stepper = lib.CD_STEP_RK4_FIXED
    m.finalize()
    return m, links, acts


def reference(q0, qT, t):
    s = t / T_MOVE if t < T_MOVE else 1.0
    s3 = s * s * s
    p = s3 * (10 - 15 * s + 6 * s * s)
    dp = 30 * s * s * (1 - s) * (1 - s) / T_MOVE if t < T_MOVE else 0.0
    ddp = 60 * s * (1 - s) * (1 - 2 * s) / (T_MOVE * T_MOVE) if t < T_MOVE else 0.0
    q, qd, qdd = [], [], []
    for j in range(NJ):
        dq = qT[j] - q0[j]
        q.append(q0[j] + p * dq)
        qd.append(dp * dq)
        qdd.append(ddp * dq)
    return q, qd, qdd


def arm_inertia(H):
    """arm_inertia() of the example: Cholesky of the base block, Schur complement."""
    N = 6 + NJ
    L = [0.0] * 36
    X = [0.0] * (6 * NJ)
    for j in range(6):
        for i in range(j, 6):
            s = H[i * N + j]
            for k in range(j):
                s -= L[i * 6 + k] * L[j * 6 + k]
            if i == j:
                assert s > 0
                L[j * 6 + j] = math.sqrt(s)
            else:
                L[i * 6 + j] = s / L[j * 6 + j]
    for j in range(NJ):
        for i in range(6):
            s = H[i * N + 6 + j]
            for k in range(i):
                s -= L[i * 6 + k] * X[k * NJ + j]
            X[i * NJ + j] = s / L[i * 6 + i]
    Hs = [0.0] * (NJ * NJ)
    for i in range(NJ):
        for j in range(NJ):
            s = H[(6 + i) * N + 6 + j]
            for k in range(6):
                s -= X[k * NJ + i] * X[k * NJ + j]
            Hs[i * NJ + j] = s
    return Hs


def python_trajectory():
    q0, qT = [0.0, 0.3, -0.6], [0.8, -0.4, 1.0]
    wn = 2 * 3.14159265358979323846 * 1.5
    kp, kd = wn * wn, 2 * wn
    m, links, acts = build_model(q0)
    sim = capdyn.Simulation(m, event_capacity=64)
    sim.options.max_evals = MAX_EVALS
    q, qd, ctrl = sim.q(0), sim.qd(0), sim.ctrl
    rows = [np.concatenate(([sim.t], sim.y))]
    for _ in range(int(T_END * RATE_HZ + 0.5)):
        qr, qdr, qddr = reference(q0, qT, sim.t)
        Hs = arm_inertia(sim.mass_matrix(0).ravel().tolist())
        x, xd = q.tolist(), qd.tolist()
        acc = [qddr[j] + kp * (qr[j] - x[j]) + kd * (qdr[j] - xd[j]) for j in range(NJ)]
        for i in range(NJ):
            tau = 0.0
            for j in range(NJ):
                tau += Hs[i * NJ + j] * acc[j]
            ctrl[acts[i]] = tau
        sim.step(1.0 / RATE_HZ)
        rows.append(np.concatenate(([sim.t], sim.y)))
    return np.array(rows), m.ny


@pytest.fixture(scope="module")
def c_trajectory(tmp_path_factory):
    d = tmp_path_factory.mktemp("trace")
    exe = str(d / "control_loop_trace")
    cc = os.environ.get("CC", "cc")
    src = os.path.join(os.path.dirname(__file__), "control_loop_trace.c")
    subprocess.run([cc, "-std=c99", "-O2", "-ffp-contract=off", "-I" + os.path.join(ROOT, "include"), src, "-o", exe,
                    "-L" + BUILD, "-Wl,-rpath," + BUILD, "-lcapdyn", "-lm"], check=True)
    out = subprocess.run([exe], check=True, capture_output=True).stdout
    return np.frombuffer(out, dtype=np.float64)


def test_control_loop_trajectory_bit_identical(c_trajectory):
    py, ny = python_trajectory()
    c = c_trajectory.reshape(-1, 1 + ny)
    assert c.shape == py.shape == (5001, 1 + ny)
    assert c[-1, 0] == 5.0
    diff = np.nonzero(c.view(np.uint64) != py.view(np.uint64))
    assert diff[0].size == 0, f"first difference at tick {diff[0][0]}, entry {diff[1][0]}"
    # and the loop did what the example checks: the arm at the target posture
    sys_q = py[-1, 1 + 7:1 + 7 + NJ]
    assert np.max(np.abs(sys_q - [0.8, -0.4, 1.0])) < 1e-4
