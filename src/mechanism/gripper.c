/* Clutched fingers: the Space Gripper and the Barrett TorqueSwitch (paper
 * sec. 4; model.h, cd_finger_desc).
 *
 * Engaged, joint j of a finger follows the closing schedule through the
 * synchronising coupling, a stiff wire modelled as a spring-damper:
 *     tau_j = sat( K_w (q0_j + sync_j theta_s(t) - q_j) - D_w qdot_j ),  |tau_j| <= torque_limit
 * (q0_j the joint's initial angle: the wires are rigged at the initial pose,
 * so a hand that starts open, q0 != 0, is held there until the schedule runs)
 * The cross-routed wires of the Space Gripper make every joint turn with the
 * pulley; a kinematic constraint would need loop closure, which capdyn's
 * open-chain algorithm avoids on purpose (paper sec. 1): a stiff coupling is
 * the compliant version, and its K_w is the wire's real stiffness (the joints
 * then follow the schedule within tau / K_w, tested). The clutch's load is the
 * largest closing coupling torque, max_j tau_j (positive closes); the plunger
 * disengages when it reaches the threshold (a located event, logged per
 * finger). Released:
 *     SPACE          tau_j = ratio_j grasp_torque  (equal-pressure wires, the
 *                    Soft Gripper's split: quadratic from the tip by default)
 *     TORQUE_SWITCH  tau_0 = K_w (q_brake - q_0) - D_w qdot_0 (inner joint
 *                    braked where it was), outer joints still coupled.
 * Opening: after open_at, once the schedule (turning back) has come back to
 * the finger, i.e. the coupling would pull it open (load <= 0), the clutch
 * re-engages (a located event) and the schedule opens the finger; only a
 * closing load disengages it, so opening does not chatter. */
#include "capdyn/sim.h"
#include "../math/cd_math.h"
#include "actuation.h"

static double schedule(const cd_model *m, int f, double t)
{
    const double *tt = m->tbl_t + m->finger_tbl_adr[f], *qq = m->tbl_v + m->finger_tbl_adr[f];
    int n = m->finger_tbl_n[f], lo;
    if (t <= tt[0]) return qq[0];
    if (t >= tt[n - 1]) return qq[n - 1];
    lo = cd_count_le(tt, n, t); /* the first row after t: 1 .. n-1 here */
    return qq[lo - 1] + (qq[lo] - qq[lo - 1]) * (t - tt[lo - 1]) / (tt[lo] - tt[lo - 1]);
}

void cd_gripper_torques(const cd_model *m, cd_data *d)
{
    int f, j;
    for (f = 0; f < m->nfinger; f++) {
        const double *P = m->finger_prm + 6 * f;
        int adr = m->finger_jnt_adr[f], n = m->finger_jnt_n[f], released = d->finger_mode[f] == CD_CLUTCH_RELEASED;
        double th = schedule(m, f, d->t - d->finger_t0[f]), load = -HUGE_VAL; /* t0: data.h */
        d->finger_theta[f] = th;
        for (j = 0; j < n; j++) {
            int b = m->fjnt_body[adr + j];
            double q = cd_joint_q(m, d, b), qd = cd_joint_qd(m, d, b), tau;
            /* the coupling's torque, applied or (clutch out) only sensed */
            double tc = P[0] * (m->body_q0[b] + m->fjnt_sync[adr + j] * th - q) - P[1] * qd;
            if (P[4] > 0 && tc > P[4]) tc = P[4];
            if (P[4] > 0 && tc < -P[4]) tc = -P[4];
            if (tc > load) load = tc;
            if (released && m->finger_type[f] == CD_FINGER_SPACE) tau = m->fjnt_ratio[adr + j] * P[3];
            else if (released && j == 0) tau = P[0] * (d->finger_brake[f] - q) - P[1] * qd; /* the TorqueSwitch's brake */
            else tau = tc;
            d->qfrc_actuator[m->body_dof[b]] += tau;
        }
        d->finger_load[f] = load;
    }
}

/* engaged: threshold - load (disengage under a closing load); released:
 * re-engage once open_at has passed and the schedule has come back to the
 * finger (its coupling would pull open: load <= 0), max(open_at - t, load). */
void cd_finger_functions(const cd_model *m, const cd_data *d, int i, double g[2])
{
    const double *P = m->finger_prm + 6 * i;
    if (d->finger_mode[i] == CD_CLUTCH_ENGAGED) g[0] = P[2] - d->finger_load[i];
    else if (P[5] > 0) g[0] = P[5] - d->t > d->finger_load[i] ? P[5] - d->t : d->finger_load[i];
    else g[0] = 1.0;
    g[1] = 1.0;
}

int cd_finger_transition(const cd_model *m, cd_data *d, int i, cd_event *ev)
{
    double g[2];
    int from = d->finger_mode[i];
    cd_finger_functions(m, d, i, g);
    if (!(g[0] < 0)) return 0;
    if (from == CD_CLUTCH_ENGAGED) {
        d->finger_mode[i] = CD_CLUTCH_RELEASED;
        d->finger_brake[i] = cd_joint_q(m, d, m->fjnt_body[m->finger_jnt_adr[i]]);
    } else {
        d->finger_mode[i] = CD_CLUTCH_ENGAGED;
    }
    ev->kind = CD_EV_CLUTCH;
    ev->owner_kind = CD_OWNER_FINGER;
    ev->owner = i;
    ev->body_a = m->fjnt_body[m->finger_jnt_adr[i]];
    ev->mode_from = from;
    ev->mode_to = d->finger_mode[i];
    ev->fn = d->finger_load[i];
    return 1;
}
