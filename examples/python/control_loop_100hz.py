#!/usr/bin/env python3
"""control_loop_100hz.py -- a 100 Hz joint-space control loop in Python.

The plant of examples/control_loop.c, built from Python (capdyn.Model): a
free-floating 150 kg spacecraft, drifting and tumbling slowly, with a
3-joint arm whose joints are driven by actuators of type "none" (the
joint torque is exactly the command written into sim.ctrl, a numpy view
on the engine's input).

Every 10 ms: read the joint angles and rates (views into the state), compute
a PD + feed-forward law toward a minimum-jerk reference, scaled by the
arm's inertia with the base floating, H* = H_qq - H_bq^T H_b^-1 H_bq (from
sim.mass_matrix), write sim.ctrl, and call sim.step(0.01): with the default
adaptive stepper (rk8pd) that integrates exactly to the next tick with the
command held (a zero-order hold).

What running it checks (exit status 1 if any fails, so it is a test):
  - the arm reaches the target posture: every joint within 1e-4 rad and
    1e-4 rad/s of it at the end (5 s);
  - no external force acts, so the linear momentum and the angular momentum
    about the system's CoM are conserved to 1e-9 relative (sim.momentum).
"""
import sys

import numpy as np

import capdyn

RATE_HZ, T_MOVE, T_END = 100, 2.0, 5.0
Q0, QT = np.array([0.0, 0.3, -0.6]), np.array([0.8, -0.4, 1.0])


def build_model():
    m = capdyn.Model()                       # gravity zero: orbit
    sys_ = m.add_system(name="spacecraft", type="free", mass=150.0,
                        inertia=np.diag([20.0, 25.0, 30.0]).ravel(),
                        vel=[0.02, -0.01, 0.005], angvel=[0.01, 0.02, -0.015])
    parent, acts = m.base_body(sys_), []
    for j, (mass, length) in enumerate(zip([6.0, 4.0, 2.0], [0.5, 0.5, 0.4])):
        inertia = np.diag([1e-3 * mass, mass * length ** 2 / 12, mass * length ** 2 / 12]).ravel()
        parent = m.add_link(sys_, parent, name=f"j{j + 1}", pos=[0.6, 0, 0] if j == 0 else [0.5, 0, 0],
                            axis=[0, 0, 1] if j == 0 else [0, 1, 0], mass=mass, com=[0.5 * length, 0, 0],
                            inertia=inertia, q0=Q0[j])
        acts.append(m.add_actuator([parent], type="none", name=f"motor{j + 1}"))
    return m.finalize(), acts


def reference(t):
    """minimum-jerk from Q0 to QT over T_MOVE, held afterwards"""
    s = min(t / T_MOVE, 1.0)
    p = s ** 3 * (10 - 15 * s + 6 * s * s)
    dp = 30 * s * s * (1 - s) ** 2 / T_MOVE if t < T_MOVE else 0.0
    ddp = 60 * s * (1 - s) * (1 - 2 * s) / T_MOVE ** 2 if t < T_MOVE else 0.0
    return Q0 + p * (QT - Q0), dp * (QT - Q0), ddp * (QT - Q0)


def main():
    model, acts = build_model()
    sim = capdyn.Simulation(model)
    q, qd, ctrl = sim.q(0), sim.qd(0), sim.ctrl        # views: always the engine's current values
    wn = 2 * np.pi * 1.5
    kp, kd = wn * wn, 2 * wn
    _, P0, L0, _, _ = sim.momentum(0)
    for _ in range(int(T_END * RATE_HZ + 0.5)):
        qr, qdr, qddr = reference(sim.t)
        H = sim.mass_matrix(0)
        Hb, Hbq, Hqq = H[:6, :6], H[:6, 6:], H[6:, 6:]
        Hstar = Hqq - Hbq.T @ np.linalg.solve(Hb, Hbq)
        ctrl[acts] = Hstar @ (qddr + kp * (qr - q) + kd * (qdr - qd))
        sim.step(1.0 / RATE_HZ)
    _, P1, L1, _, _ = sim.momentum(0)
    err, rate = np.max(np.abs(q - QT)), np.max(np.abs(qd))
    dP = np.linalg.norm(P1 - P0) / np.linalg.norm(P0)
    dL = np.linalg.norm(L1 - L0) / np.linalg.norm(L0)
    st = sim.stats
    print(f"capdyn {capdyn.version()}: 3-joint arm on a free-floating base, {RATE_HZ} Hz loop in Python, "
          f"{sim.options.stepper}")
    print(f"  t = {sim.t:.3f} s: {st['nsteps']} integrator steps, {st['nrhs']} evaluations")
    print(f"  final joint error {err:.2e} rad, rate {rate:.2e} rad/s (tolerance 1e-4)")
    print(f"  momentum drift: linear {dP:.2e}, angular about the CoM {dL:.2e} (tolerance 1e-9)")
    ok = err <= 1e-4 and rate <= 1e-4 and dP <= 1e-9 and dL <= 1e-9
    print("PASS" if ok else "FAIL")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
