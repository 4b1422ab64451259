/* control_loop_model.h -- the plant and the controller of control_loop.c:
 * a free-floating spacecraft with a 3-joint arm (CD_ACT_NONE actuators) and
 * a PD + inertial feed-forward law toward a minimum-jerk reference. Kept in
 * a header so that bench/bench_ticks.c times the very same loop (`make
 * bench`, docs/performance.md); the example itself is control_loop.c. */
#ifndef CONTROL_LOOP_MODEL_H
#define CONTROL_LOOP_MODEL_H
#include <capdyn/capdyn.h>

#include <math.h>
#include <string.h>

#define NJ 3                 /* arm joints */
#define RATE_HZ 1000         /* control rate */
#define T_MOVE 2.0           /* duration of the reference motion [s] */
#define T_END 5.0            /* end of the run [s] */

/* ---- the model, built in code ---------------------------------------------- */
typedef struct {
    int link[NJ];            /* body id of each joint */
    int act[NJ];             /* actuator id (index into d->ctrl) of each joint */
} arm_ids;

/* A slender link of mass mass [kg] and length len [m] along its x axis. */
static cd_link_desc rod(int parent, const double pos[3], const double axis[3], double mass, double len, double q0)
{
    cd_link_desc l = cd_link_desc_default();
    l.parent = parent;
    l.type = CD_JOINT_REVOLUTE;
    memcpy(l.pos, pos, sizeof l.pos);
    memcpy(l.axis, axis, sizeof l.axis);
    l.mass = mass;
    l.com[0] = 0.5 * len;
    memset(l.inertia, 0, sizeof l.inertia);
    l.inertia[0] = 1e-3 * mass;                       /* about its own axis (thin rod) */
    l.inertia[4] = l.inertia[8] = mass * len * len / 12.0;
    l.q0 = q0;
    return l;
}

static cd_model *build_model(const double q0[NJ], arm_ids *ids, cd_error *err)
{
    static const double z[3] = {0, 0, 1}, y[3] = {0, 1, 0};
    const double mount[3] = {0.6, 0, 0}, elbow[3] = {0.5, 0, 0};
    const double mass[NJ] = {6.0, 4.0, 2.0}, len[NJ] = {0.5, 0.5, 0.4};
    cd_model *m = cd_model_create();
    cd_system_desc base = cd_system_desc_default();
    int j, sys;
    if (!m) {
        cd_error_set(err, CD_ENOMEM, "out of memory creating the model");
        return NULL;
    }
    /* m->gravity stays zero (orbit); m->opt keeps the defaults: the data's
     * runtime options are set on d->opt after creation (main). */
    base.name = "spacecraft";
    base.type = CD_BASE_FREE;
    base.mass = 150.0;
    memset(base.inertia, 0, sizeof base.inertia);
    base.inertia[0] = 20.0; base.inertia[4] = 25.0; base.inertia[8] = 30.0;
    /* residual drift and tumble before capture: the momenta are not zero,
     * so their relative drift is a meaningful number */
    base.vel[0] = 0.02; base.vel[1] = -0.01; base.vel[2] = 0.005;
    base.angvel[0] = 0.01; base.angvel[1] = 0.02; base.angvel[2] = -0.015;
    sys = cd_model_add_system(m, &base, err);
    if (sys < 0) goto fail;
    for (j = 0; j < NJ; j++) {
        /* joint 1 (shoulder yaw) about z on the base, joints 2-3 (pitch) about y */
        cd_link_desc l = rod(j == 0 ? m->sys_body_adr[sys] : ids->link[j - 1], j == 0 ? mount : elbow,
                             j == 0 ? z : y, mass[j], len[j], q0[j]);
        cd_actuator_desc a = cd_actuator_desc_default();
        double ratio = 1.0;
        ids->link[j] = cd_model_add_link(m, sys, &l, err);
        if (ids->link[j] < 0) goto fail;
        /* CD_ACT_NONE: the actuator's law is 0, its torque is d->ctrl[a];
         * transmission: ratio 1 to this joint; no motor envelope */
        a.type = CD_ACT_NONE;
        a.ntrn = 1;
        a.trn_body = &ids->link[j];
        a.trn_ratio = &ratio;
        ids->act[j] = cd_model_add_actuator(m, &a, err);
        if (ids->act[j] < 0) goto fail;
    }
    if (cd_model_finalize(m, err) != CD_OK) goto fail;
    return m;
fail:
    cd_model_free(m);
    return NULL;
}

/* ---- the controller ----------------------------------------------------------
 * tau = H* (qdd_ref + kp (q_ref - q) + kd (qd_ref - qd)): PD on the tracking
 * error plus the inertial feed-forward, scaled by the arm's generalized
 * inertia with the base floating, H* = H_qq - H_bq^T H_b^-1 H_bq (Umetani &
 * Yoshida 1989), from the system's mass matrix (cd_mass_matrix). The
 * Coriolis and centrifugal terms are left to the PD part. The controller has
 * no memory (no integral term): its output depends only on (t, state), so a
 * restored checkpoint replays it exactly. Flight software with controller
 * memory saves it next to the cd_state buffer. */
typedef struct {
    double q0[NJ], qT[NJ];   /* start and target postures [rad] */
    double kp, kd;           /* [1/s^2], [1/s]: natural frequency wn, critical damping */
    double H[(6 + NJ) * (6 + NJ)]; /* scratch: the system's mass matrix */
} controller;

/* minimum-jerk reference from q0 to qT over T_MOVE, held afterwards */
static void reference(const controller *c, double t, double *q, double *qd, double *qdd)
{
    double s = t < T_MOVE ? t / T_MOVE : 1.0, s3 = s * s * s;
    double p = s3 * (10 - 15 * s + 6 * s * s);
    double dp = t < T_MOVE ? 30 * s * s * (1 - s) * (1 - s) / T_MOVE : 0.0;
    double ddp = t < T_MOVE ? 60 * s * (1 - s) * (1 - 2 * s) / (T_MOVE * T_MOVE) : 0.0;
    int j;
    for (j = 0; j < NJ; j++) {
        double dq = c->qT[j] - c->q0[j];
        q[j] = c->q0[j] + p * dq;
        qd[j] = dp * dq;
        qdd[j] = ddp * dq;
    }
}

/* H* of the arm (NJ x NJ) from the free-floating system's mass matrix:
 * Cholesky of the 6 x 6 base block, then the Schur complement. Returns -1 if
 * the base block is not positive definite (cannot happen for a valid model). */
static int arm_inertia(const double *H, double Hs[NJ * NJ])
{
    enum { N = 6 + NJ };
    double L[36], X[6 * NJ];
    int i, j, k;
    for (j = 0; j < 6; j++) {
        for (i = j; i < 6; i++) {
            double s = H[i * N + j];
            for (k = 0; k < j; k++) s -= L[i * 6 + k] * L[j * 6 + k];
            if (i == j) {
                if (!(s > 0)) return -1;
                L[j * 6 + j] = sqrt(s);
            } else {
                L[i * 6 + j] = s / L[j * 6 + j];
            }
        }
    }
    /* X = L^-1 H_bq, so that H_bq^T H_b^-1 H_bq = X^T X */
    for (j = 0; j < NJ; j++)
        for (i = 0; i < 6; i++) {
            double s = H[i * N + 6 + j];
            for (k = 0; k < i; k++) s -= L[i * 6 + k] * X[k * NJ + j];
            X[i * NJ + j] = s / L[i * 6 + i];
        }
    for (i = 0; i < NJ; i++)
        for (j = 0; j < NJ; j++) {
            double s = H[(6 + i) * N + 6 + j];
            for (k = 0; k < 6; k++) s -= X[k * NJ + i] * X[k * NJ + j];
            Hs[i * NJ + j] = s;
        }
    return 0;
}

/* One control tick: reads the state at d->t, writes d->ctrl. Between two
 * cd_step calls the data holds the state and its kinematics, so the mass
 * matrix can be computed here (cd_kinematics recomputes the same poses from
 * d->y; it is called so that the tick does not depend on what the last call
 * evaluated). Returns -1 on a numerical failure. */
static int control_tick(const cd_model *m, cd_data *d, controller *c, const arm_ids *ids)
{
    cd_sys_state x = cd_state_of(m, d, 0);
    double qr[NJ], qdr[NJ], qddr[NJ], acc[NJ], Hs[NJ * NJ];
    int i, j;
    reference(c, d->t, qr, qdr, qddr);
    cd_kinematics(m, d);
    cd_mass_matrix(m, d, 0, c->H);
    if (arm_inertia(c->H, Hs) != 0) return -1;
    for (j = 0; j < NJ; j++) acc[j] = qddr[j] + c->kp * (qr[j] - x.q[j]) + c->kd * (qdr[j] - x.qd[j]);
    for (i = 0; i < NJ; i++) {
        double tau = 0;
        for (j = 0; j < NJ; j++) tau += Hs[i * NJ + j] * acc[j];
        d->ctrl[ids->act[i]] = tau; /* [N m]: takes effect exactly at the next call's start */
    }
    return 0;
}

#endif
