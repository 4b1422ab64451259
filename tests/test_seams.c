/* Core seams (issue 7): control inputs and the call boundary, fixed-rate
 * stepping, the complete state, the generic switch table (joint stops, user
 * switches), transmissions, joint elements, prescribed motion, equilibrium
 * start, the contact law's options, and the model/data split.
 * Every expected value is a closed form or a second, independent run. */
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include "scene_util.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

static const double G = 9.81;

static void fin(cd_model *m)
{
    cd_error e;
    cr_assert(cd_model_finalize(m, &e) == CD_OK, "finalize: %s", e.msg);
}

static cd_data *mk(const cd_model *m)
{
    cd_error e;
    cd_data *d = cd_data_create(m, 0, &e);
    cr_assert(d, "data_create: %s", e.msg);
    return d;
}

static void adv(const cd_model *m, cd_data *d, double t)
{
    cd_error e;
    cd_status st = cd_sim_advance(m, d, t, NULL, NULL, &e);
    cr_assert_eq(st, CD_OK, "advance to %g: %s", t, e.msg);
}

static int count_kind(const cd_data *d, int kind)
{
    long i;
    int n = 0;
    for (i = 0; i < d->ev_count && i < d->ev_cap; i++)
        if (cd_data_event(d, i)->kind == kind) n++;
    return n;
}

static const cd_event *first_kind(const cd_data *d, int kind)
{
    long i;
    for (i = 0; i < d->ev_count && i < d->ev_cap; i++)
        if (cd_data_event(d, i)->kind == kind) return cd_data_event(d, i);
    return NULL;
}

/* A fixed base with one revolute link about z, its CoM on the axis:
 * inertia about the joint = izz, no gravity. Returns the link body. */
static int one_link(cd_model *m, double izz, double q0)
{
    cd_error e;
    cd_link_desc l = cd_link_desc_default();
    int b;
    add_system(m, "base", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    l.name = "link";
    l.parent = 0;
    l.mass = 1.0;
    memset(l.inertia, 0, sizeof l.inertia);
    l.inertia[0] = l.inertia[4] = izz;
    l.inertia[8] = izz;
    l.q0 = q0;
    b = cd_model_add_link(m, 0, &l, &e);
    cr_assert(b >= 0, "%s", e.msg);
    return b;
}

/* ---- 1. schedules and control inputs ------------------------------------------ */

/* q(t) under a piecewise-constant torque (rows t_i, v_i; v_0 before t_0), from rest */
static void steps_closed_form(const double *tt, const double *vv, int n, double I, double t, double *q, double *qd)
{
    double x = 0, v = 0, tp = 0;
    int k;
    for (k = 0; k <= n; k++) {
        double tau = k == 0 ? vv[0] : vv[k - 1], tn = k < n ? tt[k] : HUGE_VAL, dt;
        if (tn > t) tn = t;
        dt = tn - tp;
        if (dt > 0) {
            x += v * dt + 0.5 * tau / I * dt * dt;
            v += tau / I * dt;
            tp = tn;
        }
        if (tn >= t) break;
    }
    *q = x;
    *qd = v;
}

static void steps_run(cd_stepper stp, double *q, double *qd, long *nsched)
{
    static const double tt[3] = {0.0, 0.1234567, 0.3}, vv[3] = {1.0, -2.0, 0.5};
    cd_model *m = cd_model_create();
    cd_actuator a;
    cd_error e;
    cd_data *d;
    int b = one_link(m, 0.5, 0.0);
    memset(&a, 0, sizeof a);
    a.type = CD_ACT_STEPS;
    a.tbl_t = tt;
    a.tbl_v = vv;
    a.ntbl = 3;
    cr_assert_eq(cd_model_set_actuator(m, b, &a, &e), CD_OK, "%s", e.msg);
    m->opt.stepper = stp;
    m->opt.rtol = 1e-13;
    m->opt.atol = 1e-15;
    m->opt.h_fixed = 2.5e-4; /* breakpoints off the grid */
    fin(m);
    d = mk(m);
    adv(m, d, 0.5);
    *q = cd_joint_q(m, d, b);
    *qd = cd_joint_qd(m, d, b);
    *nsched = count_kind(d, CD_EV_SCHEDULE);
    cd_data_free(d);
    cd_model_free(m);
}

Test(seams, piecewise_constant_torque_step_is_exact)
{
    /* A torque step at t = 0.1234567 s inside a fixed-step RK4 run and inside
     * an adaptive rk8pd run: steps end on the breakpoints, so both follow the
     * piecewise-quadratic closed form to 1e-12 (issue 7; before, the step was
     * smeared over a step: error 8.8e-5 at h = 2.5e-4). */
    static const double tt[3] = {0.0, 0.1234567, 0.3}, vv[3] = {1.0, -2.0, 0.5};
    double q, qd, qx, qdx;
    long ns;
    cd_stepper s[2] = {CD_STEP_RK4_FIXED, CD_STEP_RK8PD};
    int i;
    steps_closed_form(tt, vv, 3, 0.5, 0.5, &qx, &qdx);
    for (i = 0; i < 2; i++) {
        steps_run(s[i], &q, &qd, &ns);
        cr_log_info("%s: q err %.2e, qd err %.2e", cd_stepper_name(s[i]), q - qx, qd - qdx);
        cr_expect_lt(fabs(q - qx), 1e-12, "%s: q = %.17g, exact %.17g", cd_stepper_name(s[i]), q, qx);
        cr_expect_lt(fabs(qd - qdx), 1e-12, "%s: qd = %.17g, exact %.17g", cd_stepper_name(s[i]), qd, qdx);
        cr_expect_eq(ns, 2, "%s: two schedule steps after t = 0 (row 0 is in force from the start)", cd_stepper_name(s[i]));
    }
}

/* A free-floating base with a 2-link arm driven by ctrl (actuators of type NONE). */
typedef struct { cd_model *m; int j1, j2; } arm_t;

static arm_t arm_model(cd_stepper stp)
{
    arm_t r;
    cd_error e;
    cd_link_desc l = cd_link_desc_default();
    cd_actuator a;
    r.m = cd_model_create();
    add_system(r.m, "base", CD_BASE_FREE, 50.0, 5.0, NULL, NULL, NULL);
    l.parent = 0;
    l.pos[0] = 0.5;
    l.com[0] = 0.3;
    l.mass = 2.0;
    l.name = "j1";
    r.j1 = cd_model_add_link(r.m, 0, &l, &e);
    l.parent = r.j1;
    l.pos[0] = 0.6;
    l.axis[0] = 0; l.axis[1] = 1; l.axis[2] = 0;
    l.name = "j2";
    r.j2 = cd_model_add_link(r.m, 0, &l, &e);
    cr_assert(r.j2 > 0, "%s", e.msg);
    memset(&a, 0, sizeof a);
    a.type = CD_ACT_NONE;
    cr_assert_eq(cd_model_set_actuator(r.m, r.j1, &a, &e), CD_OK, "%s", e.msg);
    cr_assert_eq(cd_model_set_actuator(r.m, r.j2, &a, &e), CD_OK, "%s", e.msg);
    r.m->opt.stepper = stp;
    r.m->opt.h_fixed = 1e-3;
    fin(r.m);
    return r;
}

static double tau_k(int k, int j) { return 0.3 * sin(0.05 * k + j) + 0.1 * j; }

/* the SpaceDyn loop: set tau, take one classic RK4 step of h (the stages'
 * derivatives from cd_forward with the torque held) */
static void spacedyn_rk4(const cd_model *m, cd_data *d, double h, double *k1, double *k2, double *k3, double *k4,
                         double *y0)
{
    int i, n = m->ny;
    double t0 = d->t;
    memcpy(y0, d->y, (size_t)n * sizeof(double));
    cr_assert_eq(cd_forward(m, d), CD_OK);
    memcpy(k1, d->ydot, (size_t)n * sizeof(double));
    for (i = 0; i < n; i++) d->y[i] = y0[i] + 0.5 * h * k1[i];
    d->t = t0 + 0.5 * h;
    cr_assert_eq(cd_forward(m, d), CD_OK);
    memcpy(k2, d->ydot, (size_t)n * sizeof(double));
    for (i = 0; i < n; i++) d->y[i] = y0[i] + 0.5 * h * k2[i];
    cr_assert_eq(cd_forward(m, d), CD_OK);
    memcpy(k3, d->ydot, (size_t)n * sizeof(double));
    for (i = 0; i < n; i++) d->y[i] = y0[i] + h * k3[i];
    d->t = t0 + h;
    cr_assert_eq(cd_forward(m, d), CD_OK);
    memcpy(k4, d->ydot, (size_t)n * sizeof(double));
    for (i = 0; i < n; i++) d->y[i] = y0[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
}

Test(seams, ctrl_every_millisecond_reproduces_a_spacedyn_piecewise_torque_run)
{
    /* A controller writes new joint torques through d->ctrl before every
     * cd_step(h = 1 ms), 500 times. Reference: the SpaceDyn loop (set tau,
     * one RK4 step) written out here on the same derivatives. A third run
     * gives the same torques as a STEPS schedule to cd_sim_advance. All three
     * agree to 1e-12 (issue 7), and cd_step costs 4 evaluations per step. */
    arm_t A = arm_model(CD_STEP_RK4_FIXED), B = arm_model(CD_STEP_RK4_FIXED), C = arm_model(CD_STEP_RK4_FIXED);
    cd_data *da = mk(A.m), *db = mk(B.m), *dc;
    cd_error e;
    int n = A.m->ny, k, i, K = 500;
    double *w = calloc((size_t)(5 * n), sizeof(double)), err_ab = 0, err_ac = 0;
    double tt[501], v1[501], v2[501];
    long nrhs0;
    cd_actuator act;
    /* row 0: no torque during the warm-up step; row k + 1: tau_k from (k + 1) ms */
    tt[0] = 0; v1[0] = v2[0] = 0;
    for (k = 0; k < K; k++) { tt[k + 1] = (k + 1) * 1e-3; v1[k + 1] = tau_k(k, 0); v2[k + 1] = tau_k(k, 1); }
    /* the schedule model */
    cd_model_free(C.m);
    {
        cd_link_desc l = cd_link_desc_default();
        C.m = cd_model_create();
        add_system(C.m, "base", CD_BASE_FREE, 50.0, 5.0, NULL, NULL, NULL);
        l.parent = 0; l.pos[0] = 0.5; l.com[0] = 0.3; l.mass = 2.0; l.name = "j1";
        C.j1 = cd_model_add_link(C.m, 0, &l, &e);
        l.parent = C.j1; l.pos[0] = 0.6; l.axis[0] = 0; l.axis[1] = 1; l.axis[2] = 0; l.name = "j2";
        C.j2 = cd_model_add_link(C.m, 0, &l, &e);
        memset(&act, 0, sizeof act);
        act.type = CD_ACT_STEPS; act.tbl_t = tt; act.ntbl = K + 1;
        act.tbl_v = v1;
        cr_assert_eq(cd_model_set_actuator(C.m, C.j1, &act, &e), CD_OK, "%s", e.msg);
        act.tbl_v = v2;
        cr_assert_eq(cd_model_set_actuator(C.m, C.j2, &act, &e), CD_OK, "%s", e.msg);
        C.m->opt.stepper = CD_STEP_RK4_FIXED;
        C.m->opt.h_fixed = 1e-3;
        fin(C.m);
    }
    dc = mk(C.m);
    cr_assert_eq(cd_step(A.m, da, 1e-3, &e), CD_OK, "%s", e.msg); /* warm-up: the torque stays 0 */
    spacedyn_rk4(B.m, db, 1e-3, w, w + n, w + 2 * n, w + 3 * n, w + 4 * n);
    nrhs0 = da->stats.nrhs;
    for (k = 0; k < K; k++) {
        da->ctrl[0] = db->ctrl[0] = tau_k(k, 0);
        da->ctrl[1] = db->ctrl[1] = tau_k(k, 1);
        cr_assert_eq(cd_step(A.m, da, 1e-3, &e), CD_OK, "%s", e.msg);
        spacedyn_rk4(B.m, db, 1e-3, w, w + n, w + 2 * n, w + 3 * n, w + 4 * n);
    }
    cr_log_info("cd_step: %ld evaluations for %d steps whose input changed", da->stats.nrhs - nrhs0, K);
    /* the schedule run starts its torques at t = 1 ms (after the warm-up step) */
    cr_assert_eq(cd_sim_advance(C.m, dc, 1e-3, NULL, NULL, &e), CD_OK);
    (void)e;
    adv(C.m, dc, (K + 1) * 1e-3);
    for (i = 0; i < n; i++) {
        double ab = fabs(da->y[i] - db->y[i]), ac = fabs(da->y[i] - dc->y[i]);
        if (ab > err_ab) err_ab = ab;
        if (ac > err_ac) err_ac = ac;
    }
    cr_log_info("ctrl loop vs SpaceDyn loop %.2e, vs schedule %.2e", err_ab, err_ac);
    cr_expect_lt(err_ab, 1e-12, "ctrl loop vs SpaceDyn loop: %.3e", err_ab);
    cr_expect_lt(err_ac, 1e-12, "ctrl loop vs STEPS schedule: %.3e", err_ac);
    cr_expect_eq(da->t, (K + 1) * 1e-3, "t = t0 + k h exactly: %.17g", da->t);
    /* a changed input costs a fresh first stage: 4 stages + the end evaluation + the re-check */
    cr_expect_leq(da->stats.nrhs - nrhs0, (long)K * 6, "evaluations: %ld", da->stats.nrhs - nrhs0);
    free(w);
    cd_data_free(da); cd_data_free(db); cd_data_free(dc);
    cd_model_free(A.m); cd_model_free(B.m); cd_model_free(C.m);
}

Test(seams, cd_step_reuses_the_end_evaluation_and_keeps_time_on_the_grid)
{
    /* Unchanged inputs: 4 evaluations per RK4 step. Time after 1000 steps of
     * 0.1 s is 1000 x 0.1 (the grid), not the drifting running sum. */
    arm_t A = arm_model(CD_STEP_RK4_FIXED);
    cd_data *d = mk(A.m);
    cd_error e;
    double sum = 0;
    long nrhs0;
    int k;
    d->ctrl[0] = 0.1;
    cr_assert_eq(cd_step(A.m, d, 0.1, &e), CD_OK, "%s", e.msg);
    sum = 0.1;
    nrhs0 = d->stats.nrhs;
    for (k = 1; k < 1000; k++) {
        cr_assert_eq(cd_step(A.m, d, 0.1, &e), CD_OK, "%s", e.msg);
        sum += 0.1;
    }
    cr_expect_eq(d->stats.nrhs - nrhs0, 999 * 4, "evaluations for 999 quiet steps: %ld", d->stats.nrhs - nrhs0);
    cr_expect_eq(d->t, 1000 * 0.1, "t = %.17g", d->t);
    cr_expect_neq(sum, 1000 * 0.1, "the running sum drifts (%.17g): the grid is what keeps t exact", sum);
    cd_data_free(d);
    cd_model_free(A.m);
}

static void pd_cb(const cd_model *m, cd_data *d, void *user)
{
    const int *b = (const int *)user;
    d->ctrl[0] = 0.2 + 3.0 * (0.7 - cd_joint_q(m, d, b[0])) - 0.5 * cd_joint_qd(m, d, b[0]);
}

Test(seams, control_callback_equals_the_built_in_pd_law)
{
    /* A continuous control law through the callback (called at every
     * evaluation) gives the PD actuator's trajectory bit for bit. */
    cd_model *m1 = cd_model_create(), *m2 = cd_model_create();
    cd_actuator a;
    cd_error e;
    cd_data *d1, *d2;
    int b1 = one_link(m1, 0.2, 0.0), b2 = one_link(m2, 0.2, 0.0);
    memset(&a, 0, sizeof a);
    a.type = CD_ACT_PD; a.tau0 = 0.2; a.kp = 3.0; a.kd = 0.5; a.qref = 0.7;
    cr_assert_eq(cd_model_set_actuator(m1, b1, &a, &e), CD_OK);
    memset(&a, 0, sizeof a);
    a.type = CD_ACT_NONE;
    cr_assert_eq(cd_model_set_actuator(m2, b2, &a, &e), CD_OK);
    fin(m1); fin(m2);
    d1 = mk(m1); d2 = mk(m2);
    cd_data_set_control(d2, pd_cb, &b2);
    adv(m1, d1, 2.0);
    adv(m2, d2, 2.0);
    cr_expect_eq(memcmp(d1->y, d2->y, (size_t)m1->ny * sizeof(double)), 0, "q %.17g vs %.17g", d1->y[0], d2->y[0]);
    cd_data_free(d1); cd_data_free(d2);
    cd_model_free(m1); cd_model_free(m2);
}

Test(seams, applied_forces_and_body_frame_wrenches)
{
    /* qfrc_applied on a free base: x = F t^2 / 2m; xfrc_body on a body turned
     * 90 deg about z: a body-x force moves it along world y. 1e-12. */
    cd_model *m = cd_model_create();
    cd_data *d;
    double F = 3.0, M = 2.0, t = 1.5;
    int s;
    s = add_system(m, "free", CD_BASE_FREE, M, 1.0, NULL, NULL, NULL);
    {
        cd_system_desc sd = cd_system_desc_default();
        cd_error e;
        sd.name = "turned";
        sd.mass = M;
        sd.quat[0] = cos(M_PI / 4); sd.quat[3] = sin(M_PI / 4);
        cr_assert(cd_model_add_system(m, &sd, &e) >= 0);
    }
    fin(m);
    d = mk(m);
    d->qfrc_applied[m->sys_v_adr[s] + 0] = F;
    d->xfrc_body[6 * m->sys_body_adr[1] + 3] = F;
    adv(m, d, t);
    {
        cd_sys_state a = cd_state_of(m, d, 0), b = cd_state_of(m, d, 1);
        cr_expect_lt(fabs(a.pos[0] - F * t * t / (2 * M)), 1e-12, "x = %.17g", a.pos[0]);
        cr_expect_lt(fabs(b.pos[1] - F * t * t / (2 * M)), 1e-12, "y = %.17g", b.pos[1]);
        cr_expect_lt(fabs(b.pos[0]), 1e-12, "x = %.3e", b.pos[0]);
    }
    cd_data_free(d);
    cd_model_free(m);
}

/* ---- 2. the complete state --------------------------------------------------- */

/* a block dropped onto a slope it slides on: onset, stick -> slip events */
static cd_model *slide_scene(cd_stepper stp)
{
    cd_model *m = cd_model_create();
    cd_error e;
    cd_contact_law law = cd_contact_law_default();
    double pos[3] = {0, 0, 0.002}, th = atan(0.55);
    int g, pl, bl, lid;
    g = add_system(m, "slope", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    pl = add_plane(m, m->sys_body_adr[g]);
    bl = add_system(m, "block", CD_BASE_FREE, 1.0, 1e3, pos, NULL, NULL);
    add_point(m, m->sys_body_adr[bl]);
    law.K = 1e4; law.D = 2 * sqrt(1e4); law.Kt = 1e4; law.Dt = 2 * sqrt(1e4);
    law.mu_s = 0.5; law.mu_k = 0.4;
    lid = cd_model_add_law(m, &law, &e);
    cr_assert(cd_model_add_pair(m, bl, -1, pl, lid, &e) >= 0, "%s", e.msg);
    m->gravity[0] = G * sin(th);
    m->gravity[2] = -G * cos(th);
    m->opt.stepper = stp;
    m->opt.rtol = 1e-8;
    m->opt.atol = 1e-10;
    m->opt.h_fixed = 1e-4;
    m->opt.h_max = 1e-3;
    fin(m);
    return m;
}

Test(seams, restored_state_continues_bit_identically)
{
    /* Save at t1 (after the drop's onset), run on to t2; restore into a new
     * data, run to t2: bit-identical y, modes and events, for every stepper
     * (issue 7 names rkf45, rk8pd, rk4 and msbdf; auto, the default, keeps
     * its stepper, check interval and measured cost window in the state). */
    cd_stepper s[8] = {CD_STEP_RKF45, CD_STEP_RKCK,   CD_STEP_RK8PD,    CD_STEP_RK4_FIXED,
                       CD_STEP_MSBDF, CD_STEP_RK4IMP, CD_STEP_ROS34PW2, CD_STEP_AUTO};
    int i;
    for (i = 0; i < 8; i++) {
        cd_model *m = slide_scene(s[i]);
        cd_data *a = mk(m), *b = mk(m);
        cd_error e;
        size_t n = cd_state_size(m);
        double *buf = malloc(n * sizeof(double));
        long ev_a, ev_b;
        adv(m, a, 0.03);
        cr_assert_gt(count_kind(a, CD_EV_ONSET), 0, "%s: the drop has landed by t1", cd_stepper_name(s[i]));
        cd_state_get(m, a, buf);
        ev_a = a->ev_count;
        adv(m, a, 0.25);
        ev_a = a->ev_count - ev_a;
        cr_assert_eq(cd_state_set(m, b, buf, &e), CD_OK, "%s", e.msg);
        ev_b = b->ev_count;
        adv(m, b, 0.25);
        ev_b = b->ev_count - ev_b;
        cr_expect_eq(a->t, b->t);
        cr_expect_eq(memcmp(a->y, b->y, (size_t)m->ny * sizeof(double)), 0, "%s: y differs (x %.17g vs %.17g)",
                     cd_stepper_name(s[i]), a->y[0], b->y[0]);
        cr_expect_eq(a->slot_mode[0], b->slot_mode[0]);
        cr_expect_eq(ev_a, ev_b, "%s: events after t1 %ld vs %ld", cd_stepper_name(s[i]), ev_a, ev_b);
        cr_expect_gt(count_kind(a, CD_EV_STICK_SLIP), 0, "%s: the block slides (tan 0.55 > mu 0.5)", cd_stepper_name(s[i]));
        /* and back into a itself */
        cr_assert_eq(cd_state_set(m, a, buf, &e), CD_OK);
        adv(m, a, 0.25);
        cr_expect_eq(memcmp(a->y, b->y, (size_t)m->ny * sizeof(double)), 0, "%s: rerun in place differs", cd_stepper_name(s[i]));
        free(buf);
        cd_data_free(a); cd_data_free(b);
        cd_model_free(m);
    }
}

Test(seams, state_of_another_model_is_refused)
{
    cd_model *m1 = slide_scene(CD_STEP_RK8PD), *m2 = cd_model_create();
    cd_data *d1 = mk(m1), *d2;
    cd_error e;
    double *buf = malloc(cd_state_size(m1) * sizeof(double));
    one_link(m2, 1.0, 0.0);
    fin(m2);
    d2 = mk(m2);
    cd_state_get(m1, d1, buf);
    cr_expect_eq(cd_state_set(m2, d2, buf, &e), CD_EINVAL);
    cr_expect(strstr(e.msg, "not a state of this model") != NULL, "%s", e.msg);
    free(buf);
    cd_data_free(d1); cd_data_free(d2);
    cd_model_free(m1); cd_model_free(m2);
}

/* ---- 3. equilibrium start ------------------------------------------------------- */

/* a flat 1 kg block (0.1 x 0.1 x 0.01 m) on its four bottom corners, on a
 * slope: flat, so that the tipping moment of the friction shifts the corner
 * loads by 2 tan(th) h / L = 4.5 % only, and every corner can stick */
static cd_model *box_on_slope(double tan_th, double mu_s, int eq, double pt)
{
    cd_model *m = cd_model_create();
    cd_error e;
    cd_contact_law law = cd_contact_law_default();
    double pos[3] = {0, 0, 0.005}, th = atan(tan_th), c[3];
    int g, pl, bl, lid, i;
    g = add_system(m, "slope", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    pl = add_plane(m, m->sys_body_adr[g]);
    bl = add_system(m, "block", CD_BASE_FREE, 1.0, 1.0 * 0.01 / 12.0, pos, NULL, NULL);
    for (i = 0; i < 4; i++) {
        c[0] = (i & 1) ? 0.05 : -0.05;
        c[1] = (i & 2) ? 0.05 : -0.05;
        c[2] = -0.005;
        cr_assert(cd_model_add_checkpoint(m, m->sys_body_adr[bl], c, 0.0, &e) >= 0);
    }
    law.K = 1e5; law.D = 2 * sqrt(1e5 * 0.25);
    law.Kt = 1e5; law.Dt = 2 * sqrt(1e5 * 0.25);
    law.mu_s = mu_s; law.mu_k = 0.8 * mu_s;
    law.pt = pt;
    lid = cd_model_add_law(m, &law, &e);
    cr_assert(cd_model_add_pair(m, bl, -1, pl, lid, &e) >= 0, "%s", e.msg);
    m->gravity[0] = G * sin(th);
    m->gravity[2] = -G * cos(th);
    m->opt.rtol = 1e-10;
    m->opt.atol = 1e-13;
    m->opt.h_max = 1e-2;
    m->opt.equilibrium_start = eq;
    fin(m);
    return m;
}

Test(seams, block_placed_at_rest_on_a_slope_stays_at_rest)
{
    /* tan th = 0.9 mu_s. With the equilibrium start the contacts open preloaded
     * (penetrations and stick anchors): no slip event and drift < 1e-9 m over
     * 10 s (issue 7). Without it, the corners start open (x = 0 exactly is not
     * inside) and the block first falls into its load and slides by micrometres. */
    cd_model *m = box_on_slope(0.45, 0.5, 1, 1.0), *m0 = box_on_slope(0.45, 0.5, 0, 1.0);
    cd_data *d = mk(m), *d0 = mk(m0);
    double x0[3], drift;
    int k;
    memcpy(x0, cd_state_of(m, d, 1).pos, sizeof x0);
    cr_log_info("equilibrium start: %d Newton iterations, residual %.2e m/s^2", d->stats.eq_iterations, d->stats.eq_residual);
    for (k = 0; k < 4; k++) cr_assert_eq(d->slot_mode[k], CD_MODE_STICK, "corner %d closed", k);
    adv(m, d, 10.0);
    {
        double *x = cd_state_of(m, d, 1).pos;
        drift = sqrt((x[0] - x0[0]) * (x[0] - x0[0]) + (x[1] - x0[1]) * (x[1] - x0[1]) + (x[2] - x0[2]) * (x[2] - x0[2]));
    }
    cr_log_info("drift over 10 s: %.3e m, events %ld", drift, d->ev_count);
    cr_expect_eq(count_kind(d, CD_EV_STICK_SLIP), 0, "no slip");
    cr_expect_lt(drift, 1e-9, "drift %.3e m over 10 s", drift);
    /* without it the block first sinks and slides into its load: m g cos th / 4K = 2.2e-5 m */
    memcpy(x0, cd_state_of(m0, d0, 1).pos, sizeof x0);
    adv(m0, d0, 0.05);
    {
        double *x = cd_state_of(m0, d0, 1).pos;
        drift = sqrt((x[0] - x0[0]) * (x[0] - x0[0]) + (x[1] - x0[1]) * (x[1] - x0[1]) + (x[2] - x0[2]) * (x[2] - x0[2]));
    }
    cr_log_info("without the equilibrium start: moved %.3e m in 0.05 s, %d slip events", drift, count_kind(d0, CD_EV_STICK_SLIP));
    cr_expect_gt(drift, 1e-6, "without the equilibrium start the block settles by micrometres: %.3e m", drift);
    cd_data_free(d); cd_data_free(d0);
    cd_model_free(m); cd_model_free(m0);
}

Test(seams, tangential_exponent_sets_the_held_deflection)
{
    /* eq. (4) with p_t = 2: a sticking contact holding f_t has |z| = (f_t /
     * K_t)^(1/2). Four corners share m g sin th; equilibrium start; 1e-8. */
    double th = atan(0.3);
    cd_model *m = box_on_slope(0.3, 0.5, 1, 2.0);
    cd_data *d = mk(m);
    double ftot = 0, zerr = 0;
    int k;
    for (k = 0; k < 4; k++) {
        double *ft = d->slot_ft + 3 * k, *z = d->y + m->ny_slot_adr + 3 * k;
        double f = sqrt(ft[0] * ft[0] + ft[1] * ft[1] + ft[2] * ft[2]), zn = sqrt(z[0] * z[0] + z[1] * z[1] + z[2] * z[2]);
        double rel = fabs(zn - sqrt(f / m->law[0].Kt)) / sqrt(f / m->law[0].Kt);
        if (rel > zerr) zerr = rel;
        ftot += f;
    }
    cr_expect_lt(zerr, 1e-8, "|z| vs (f_t/K_t)^(1/2): %.3e", zerr);
    cr_expect_lt(fabs(ftot - G * sin(th)) / (G * sin(th)), 1e-9, "friction carries m g sin th: %.12g", ftot);
    cd_data_free(d);
    cd_model_free(m);
}

/* ---- 4. joint stops, user switches, transmissions, joint elements ---------------- */

typedef struct { int lim; double max_depth; } lim_watch;
static int lim_cb(const cd_model *m, cd_data *d, void *user)
{
    lim_watch *w = (lim_watch *)user;
    (void)m;
    if (d->lim_depth[w->lim] > w->max_depth) w->max_depth = d->lim_depth[w->lim];
    return 0;
}

Test(seams, joint_driven_into_its_stop)
{
    /* From rest, tau = 0.5 N m on I = 0.2 kg m^2 reaches the stop at 0.3 rad at
     * t = sqrt(2 0.3 I / tau), located to 1e-9 s. The critically damped stop
     * (K = 1e3 N m/rad) then holds it: the depth never exceeds tau/K + v/(w e)
     * (static load plus the impulse response), and settles at tau/K. */
    cd_model *m = cd_model_create();
    cd_joint_props p = cd_joint_props_default();
    cd_actuator a;
    cd_error e;
    cd_data *d;
    double I = 0.2, tau = 0.5, K = 1e3, th = 0.3, t_hit = sqrt(2 * th * I / tau), v = tau / I * t_hit, w = sqrt(K / I);
    lim_watch lw = {0, 0};
    const cd_event *ev;
    int b = one_link(m, I, 0.0);
    memset(&a, 0, sizeof a);
    a.type = CD_ACT_CONSTANT; a.tau0 = tau;
    cr_assert_eq(cd_model_set_actuator(m, b, &a, &e), CD_OK);
    p.limited = 1; p.lower = -1.0; p.upper = th; p.stop_K = K;
    cr_assert_eq(cd_model_set_joint(m, b, &p, &e), CD_OK, "%s", e.msg);
    m->opt.rtol = 1e-11; m->opt.atol = 1e-13; m->opt.h_max = 1e-3;
    fin(m);
    cr_expect_lt(fabs(m->body_limit[6 * b + 3] - 2 * sqrt(K * I)), 1e-12, "default damping is critical: %g", m->body_limit[6 * b + 3]);
    d = mk(m);
    cr_assert_eq(cd_sim_advance(m, d, 3.0, lim_cb, &lw, &e), CD_OK, "%s", e.msg);
    ev = first_kind(d, CD_EV_LIMIT_ENGAGE);
    cr_assert(ev, "no engagement event");
    cr_expect_lt(fabs(ev->t - t_hit), 1e-9, "engaged at %.12g, exact %.12g", ev->t, t_hit);
    cr_expect_eq(ev->owner_kind, CD_OWNER_JOINT);
    cr_expect_eq(ev->owner, b);
    cr_expect_eq(ev->mode_to, CD_LIM_UPPER);
    cr_expect_leq(lw.max_depth, tau / K + v / (w * exp(1.0)) * (1 + 1e-6), "max depth %.6g", lw.max_depth);
    cr_expect_lt(fabs(d->lim_depth[0] - tau / K), 1e-9, "static depth %.12g, tau/K %.12g", d->lim_depth[0], tau / K);
    /* (K d + D ddot may pull during the rebound: the no-pull stop then lets go and re-engages) */
    cr_expect_eq(d->lim_mode[0], CD_LIM_UPPER, "held by the stop at the end");
    cd_data_free(d);
    cd_model_free(m);
}

static double clutch_g(const cd_model *m, const cd_data *d, int i, void *user)
{
    (void)m; (void)i;
    /* engaged (mode 0): switches when the load reaches the plunger threshold */
    return d->user_mode[0] == 0 ? *(const double *)user - d->act_force[0] : 1.0;
}
static int clutch_tr(const cd_model *m, cd_data *d, int i, void *user)
{
    (void)m; (void)d; (void)i; (void)user;
    return 1;
}

Test(seams, clutch_user_switch_fires_once_at_its_threshold)
{
    /* The load ramps as 2 t N m; a clutch-type user switch with threshold
     * 0.7 N m fires once, at t = 0.35 s to 1e-9 s, logged with its owner. */
    cd_model *m = cd_model_create();
    cd_actuator a;
    cd_error e;
    cd_data *d;
    double tt[2] = {0, 10}, vv[2] = {0, 20}, thr = 0.7;
    const cd_event *ev;
    int b = one_link(m, 0.5, 0.0);
    memset(&a, 0, sizeof a);
    a.type = CD_ACT_TABLE; a.tbl_t = tt; a.tbl_v = vv; a.ntbl = 2;
    cr_assert_eq(cd_model_set_actuator(m, b, &a, &e), CD_OK);
    cr_assert_eq(cd_model_set_user_switches(m, 1, &e), CD_OK);
    m->opt.rtol = 1e-10;
    fin(m);
    d = mk(m);
    cd_data_set_user_switches(d, clutch_g, clutch_tr, &thr);
    adv(m, d, 1.0);
    cr_expect_eq(count_kind(d, CD_EV_USER), 1, "fires once");
    ev = first_kind(d, CD_EV_USER);
    cr_assert(ev);
    cr_expect_lt(fabs(ev->t - 0.35), 1e-9, "fired at %.12g", ev->t);
    cr_expect_eq(ev->owner_kind, CD_OWNER_USER);
    cr_expect_eq(ev->owner, 0);
    cr_expect_eq(ev->mode_to, 1);
    cr_expect_eq(d->user_mode[0], 1);
    cd_data_free(d);
    cd_model_free(m);
}

Test(seams, transmission_splits_one_motor_over_its_joints)
{
    /* One actuator drives three joints of a finger with ratios 3:2:1: each
     * joint's torque is ratio x actuator torque to 1e-14; with a motor model
     * the torque stays on the DC line T_s (1 - w/w_0). */
    cd_model *m = cd_model_create();
    cd_actuator_desc a = cd_actuator_desc_default();
    cd_link_desc l = cd_link_desc_default();
    cd_error e;
    cd_data *d;
    int b[3], j, id;
    double r[3] = {3, 2, 1}, Ts = 0.4, w0 = 10.0, w;
    add_system(m, "palm", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    for (j = 0; j < 3; j++) {
        l.parent = j == 0 ? 0 : b[j - 1];
        l.pos[1] = j == 0 ? 0 : 0.04;
        l.com[1] = 0.02;
        l.mass = 0.05;
        b[j] = cd_model_add_link(m, 0, &l, &e);
    }
    a.name = "grasp";
    a.type = CD_ACT_CONSTANT;
    a.tau0 = 0.3;
    a.ntrn = 3; a.trn_body = b; a.trn_ratio = r;
    id = cd_model_add_actuator(m, &a, &e);
    cr_assert(id >= 0, "%s", e.msg);
    a.name = "motor";
    a.tau0 = 5.0;  /* asks more than the motor can give */
    a.stall_torque = Ts; a.noload_speed = w0;
    cr_assert(cd_model_add_actuator(m, &a, &e) == 1, "%s", e.msg);
    fin(m);
    cr_expect_eq(cd_model_actuator_id(m, "motor"), 1);
    d = mk(m);
    cd_state_of(m, d, 0).qd[0] = 1.0; /* transmission rate 3 rad/s */
    cr_assert_eq(cd_forward(m, d), CD_OK);
    w = 3.0;
    cr_expect_eq(d->act_velocity[1], w);
    cr_expect_lt(fabs(d->act_force[1] - Ts * (1 - w / w0)), 1e-15, "motor torque %.17g", d->act_force[1]);
    for (j = 0; j < 3; j++) {
        double want = r[j] * (d->act_force[0] + d->act_force[1]);
        cr_expect_lt(fabs(d->qfrc_actuator[m->body_dof[b[j]]] - want), 1e-14, "joint %d: %.17g vs %.17g", j,
                     d->qfrc_actuator[m->body_dof[b[j]]], want);
    }
    cd_data_free(d);
    cd_model_free(m);
}

Test(seams, joint_spring_and_damper_give_the_damped_oscillation)
{
    /* q'' = -(k q + c q')/I from q0 = 0.1: the closed form, 1e-9 rad at t = 1 s. */
    cd_model *m = cd_model_create();
    cd_joint_props p = cd_joint_props_default();
    cd_error e;
    cd_data *d;
    double I = 0.5, k = 20.0, c = 0.6, q0 = 0.1, wn = sqrt(k / I), z = c / (2 * sqrt(k * I)), wd = wn * sqrt(1 - z * z), t = 1.0;
    double qx = q0 * exp(-z * wn * t) * (cos(wd * t) + z * wn / wd * sin(wd * t));
    int b = one_link(m, I, q0);
    p.stiffness = k; p.damping = c;
    cr_assert_eq(cd_model_set_joint(m, b, &p, &e), CD_OK, "%s", e.msg);
    m->opt.rtol = 1e-12; m->opt.atol = 1e-14;
    fin(m);
    d = mk(m);
    adv(m, d, t);
    cr_expect_lt(fabs(cd_joint_q(m, d, b) - qx), 1e-9, "q = %.12g, exact %.12g", cd_joint_q(m, d, b), qx);
    cd_data_free(d);
    cd_model_free(m);
}

static cd_model *slider(double F, double Tc, int *b)
{
    cd_model *m = cd_model_create();
    cd_joint_props p = cd_joint_props_default();
    cd_link_desc l = cd_link_desc_default();
    cd_actuator a;
    cd_error e;
    add_system(m, "rail", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    l.parent = 0; l.type = CD_JOINT_PRISMATIC; l.axis[0] = 1; l.axis[2] = 0; l.mass = 2.0;
    *b = cd_model_add_link(m, 0, &l, &e);
    memset(&a, 0, sizeof a);
    a.type = CD_ACT_CONSTANT; a.tau0 = F;
    cr_assert_eq(cd_model_set_actuator(m, *b, &a, &e), CD_OK);
    p.friction = Tc;
    cr_assert_eq(cd_model_set_joint(m, *b, &p, &e), CD_OK, "%s", e.msg);
    m->opt.rtol = 1e-11; m->opt.atol = 1e-14; m->opt.h_max = 1e-3;
    fin(m);
    return m;
}

Test(seams, coulomb_joint_friction_sticks_below_and_slides_above)
{
    /* A 2 kg slider with Coulomb friction 2 N. Pushed with 1.5 N it sticks:
     * no slip event, displacement = F / k_s (the stick spring), held. Pushed
     * with 3 N it slides with a = (F - T_c)/m (1e-6 rel). */
    int b, b2;
    cd_model *m = slider(1.5, 2.0, &b), *m2 = slider(3.0, 2.0, &b2);
    cd_data *d = mk(m), *d2 = mk(m2);
    double v1, v2;
    adv(m, d, 1.0);
    cr_expect_eq(count_kind(d, CD_EV_STICK_SLIP), 0, "sticks below the Coulomb force");
    cr_expect_lt(fabs(cd_joint_q(m, d, b) - 1.5 / m->body_fric[3 * b + 1]), 1e-9, "held at F/k_s: %.6g",
                 cd_joint_q(m, d, b));
    adv(m2, d2, 0.5);
    cr_expect_eq(count_kind(d2, CD_EV_STICK_SLIP), 1, "one stick -> slip");
    v1 = cd_joint_qd(m2, d2, b2);
    adv(m2, d2, 1.0);
    v2 = cd_joint_qd(m2, d2, b2);
    cr_expect_lt(fabs((v2 - v1) / 0.5 - 0.5) / 0.5, 1e-6, "a = %.12g, exact 0.5", (v2 - v1) / 0.5);
    cd_data_free(d); cd_data_free(d2);
    cd_model_free(m); cd_model_free(m2);
}

Test(seams, coulomb_joint_stops_at_the_coulomb_distance_without_spring_back)
{
    /* A 2 kg slider launched at v0 = 0.1 m/s against Coulomb friction
     * T_c = 2 N and nothing else decelerates at T_c/m = 1 m/s^2 and stops
     * after v0^2 m / (2 T_c) = 5 mm (closed form). At rest Coulomb friction
     * carries no load, so the joint stays there: within 1e-8 m at t = 1 s
     * (the old re-stick anchor preloaded the stick spring with T_c and sprang
     * it back by T_c / k_s = 1e-4 m), and the held friction torque is 0.
     * The joint re-sticks at the rate -v_reg, which the stick spring-damper
     * then stops within about v_reg / sqrt(k_s / m) = 1e-8 m at the default
     * v_reg = 1e-6 m/s (measured 2.0e-8 m); v_reg = 1e-8 m/s here keeps that
     * residue far below the tolerance. */
    int b;
    cd_model *m = cd_model_create();
    cd_joint_props p = cd_joint_props_default();
    cd_link_desc l = cd_link_desc_default();
    cd_error e;
    cd_data *d;
    double v0 = 0.1, Tc = 2.0, M = 2.0, xs = v0 * v0 * M / (2.0 * Tc);
    add_system(m, "rail", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    l.parent = 0; l.type = CD_JOINT_PRISMATIC; l.axis[0] = 1; l.axis[2] = 0; l.mass = M; l.qd0 = v0;
    b = cd_model_add_link(m, 0, &l, &e);
    cr_assert(b > 0, "%s", e.msg);
    p.friction = Tc;
    cr_assert_eq(cd_model_set_joint(m, b, &p, &e), CD_OK, "%s", e.msg);
    m->opt.rtol = 1e-11; m->opt.atol = 1e-14; m->opt.h_max = 1e-3; m->opt.v_reg = 1e-8;
    fin(m);
    d = mk(m);
    adv(m, d, 1.0);
    cr_expect_eq(count_kind(d, CD_EV_SLIP_STICK), 1, "one slip -> stick (the stop)");
    cr_expect_lt(fabs(cd_joint_q(m, d, b) - xs), 1e-8, "q = %.12g m, Coulomb distance %.12g m", cd_joint_q(m, d, b), xs);
    cr_expect_lt(fabs(cd_joint_qd(m, d, b)), 1e-8, "at rest: %.3g m/s", cd_joint_qd(m, d, b));
    cr_expect_lt(fabs(d->fric_force[0]), 1e-6, "no load, no friction at rest: %.3g N", d->fric_force[0]);
    cd_data_free(d);
    cd_model_free(m);
}

Test(seams, a_joint_moving_at_t0_reports_the_applied_friction_at_t0)
{
    /* The slider of the test above, launched at 0.1 m/s: its friction starts
     * in stick with the stick damper's -c_s v0 = -400 x 0.1 = -40 N, beyond
     * T_c = 2 N, so it slips at t = 0. The data right after creation (what a
     * t = 0 sample reads) holds the applied force, -T_c, in slip mode, with
     * the t = 0 event logged once; the first advance adds no second one. */
    int b;
    cd_model *m = cd_model_create();
    cd_joint_props p = cd_joint_props_default();
    cd_link_desc l = cd_link_desc_default();
    cd_error e;
    cd_data *d;
    add_system(m, "rail", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    l.parent = 0; l.type = CD_JOINT_PRISMATIC; l.axis[0] = 1; l.axis[2] = 0; l.mass = 2.0; l.qd0 = 0.1;
    b = cd_model_add_link(m, 0, &l, &e);
    cr_assert(b > 0, "%s", e.msg);
    p.friction = 2.0;
    cr_assert_eq(cd_model_set_joint(m, b, &p, &e), CD_OK, "%s", e.msg);
    fin(m);
    d = mk(m);
    cr_expect_eq(d->fric_mode[0], CD_MODE_SLIP, "slipping at t = 0");
    cr_expect_eq(d->fric_force[0], -2.0, "applied friction at t = 0: %.9g N, expected -T_c = -2 N", d->fric_force[0]);
    cr_expect_eq(d->qfrc_passive[m->body_dof[b]], -2.0, "the same in the generalized forces");
    cr_expect_eq(count_kind(d, CD_EV_STICK_SLIP), 1, "the t = 0 slip logged");
    adv(m, d, 1e-3);
    cr_expect_eq(count_kind(d, CD_EV_STICK_SLIP), 1, "logged once");
    cd_data_free(d);
    cd_model_free(m);
}

/* ---- 5. prescribed motion --------------------------------------------------------- */

Test(seams, prescribed_joint_follows_its_profile_and_reports_the_torque)
{
    /* Waypoints (0.5 s, 1 rad), (1 s, 0): q(t) is the minimum-jerk profile to
     * 1e-12, and the torque it takes is I q''(t) (1e-9). */
    cd_model *m = cd_model_create();
    cd_joint_props p = cd_joint_props_default();
    cd_error e;
    cd_data *d;
    double tt[2] = {0.5, 1.0}, qq[2] = {1.0, 0.0}, I = 0.3, t = 0.3, x = t / 0.5;
    double s = x * x * x * (10 - 15 * x + 6 * x * x), dds = 60 * x * (1 - 3 * x + 2 * x * x) / 0.25;
    int b = one_link(m, I, 0.0);
    p.prescribe = CD_PRESCRIBE_WAYPOINTS; p.presc_t = tt; p.presc_q = qq; p.npresc = 2;
    cr_assert_eq(cd_model_set_joint(m, b, &p, &e), CD_OK, "%s", e.msg);
    fin(m);
    d = mk(m);
    adv(m, d, t);
    cr_expect_lt(fabs(cd_joint_q(m, d, b) - s), 1e-12, "q = %.17g, profile %.17g", cd_joint_q(m, d, b), s);
    cr_expect_lt(fabs(d->qfrc_constraint[0] - I * dds), 1e-9, "torque %.12g, I q'' %.12g", d->qfrc_constraint[0], I * dds);
    adv(m, d, 1.5);
    cr_expect_eq(cd_joint_q(m, d, b), 0.0, "held at the last waypoint");
    cd_data_free(d);
    cd_model_free(m);
}

Test(seams, prescribed_base_moves_at_constant_velocity)
{
    /* A base prescribed at v = (0.1, 0, 0), w = (0, 0, 0.2) carries a free
     * joint whose reaction does not disturb it: position v t (1e-12). */
    cd_model *m = cd_model_create();
    cd_link_desc l = cd_link_desc_default();
    cd_error e;
    cd_data *d;
    double v[3] = {0.1, 0, 0}, w[3] = {0, 0, 0.2};
    int s = add_system(m, "probe", CD_BASE_FREE, 10.0, 1.0, NULL, NULL, NULL);
    l.parent = 0; l.pos[0] = 0.3; l.com[0] = 0.2; l.qd0 = 1.0; l.axis[1] = 1; l.axis[2] = 0;
    cr_assert(cd_model_add_link(m, s, &l, &e) > 0);
    cr_assert_eq(cd_model_prescribe_base(m, s, v, w, &e), CD_OK, "%s", e.msg);
    fin(m);
    d = mk(m);
    adv(m, d, 2.0);
    {
        cd_sys_state x = cd_state_of(m, d, s);
        double ang = 2 * atan2(x.quat[3], x.quat[0]);
        cr_expect_lt(fabs(x.pos[0] - 0.2), 1e-12, "x = %.17g", x.pos[0]);
        cr_expect_lt(fabs(ang - 0.4), 1e-12, "yaw = %.17g", ang);
        cr_expect_gt(fabs(d->qfrc_constraint[1]) + fabs(d->qfrc_constraint[2]) + fabs(d->qfrc_constraint[0]), 0.0,
                     "the swinging link loads the probe");
    }
    cd_data_free(d);
    cd_model_free(m);
}

/* ---- 6. the contact law's options --------------------------------------------------- */

Test(seams, kelvin_voigt_pull_option_keeps_contact_until_x_returns_to_zero)
{
    /* A 1 kg point mass hits a plane at 1 m/s, linear K = 1e4, D = 40 (zeta
     * 0.2). With `pull` (plain Kelvin-Voigt) the contact lasts pi/w_d and ends
     * at x = 0 with a pulling force -D xdot; without it the contact ends
     * earlier, where the force reaches zero at x > 0. */
    double K = 1e4, D = 40, M = 1, wn = sqrt(K / M), z = D / (2 * sqrt(K * M)), wd = wn * sqrt(1 - z * z);
    double T = M_PI / wd, dur[2];
    int pull;
    for (pull = 0; pull < 2; pull++) {
        cd_model *m = cd_model_create();
        cd_contact_law law = cd_contact_law_default();
        cd_error e;
        cd_data *d;
        double pos[3] = {0, 0, 1e-3}, vel[3] = {0, 0, -1};
        const cd_event *on, *off;
        int g = add_system(m, "wall", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL), pl, s, lid;
        pl = add_plane(m, m->sys_body_adr[g]);
        s = add_system(m, "ball", CD_BASE_FREE, M, 1.0, pos, vel, NULL);
        add_point(m, m->sys_body_adr[s]);
        law.K = K; law.D = D; law.mu_s = law.mu_k = 0; law.pull = pull;
        lid = cd_model_add_law(m, &law, &e);
        cr_assert(cd_model_add_pair(m, s, -1, pl, lid, &e) >= 0);
        m->opt.rtol = 1e-12; m->opt.atol = 1e-14; m->opt.h_max = 1e-4;
        fin(m);
        d = mk(m);
        adv(m, d, 0.1);
        on = first_kind(d, CD_EV_ONSET);
        off = first_kind(d, CD_EV_SEPARATION);
        cr_assert(on && off, "onset and separation");
        dur[pull] = off->t - on->t;
        if (pull) {
            cr_expect_lt(fabs(dur[1] - T) / T, 1e-8, "duration %.12g, pi/w_d %.12g", dur[1], T);
            cr_expect_lt(fabs(off->x), 1e-9, "ends at x = 0: %.3e", off->x);
            cr_expect_lt(off->fn, 0.0, "pulls at the end: %.6g N", off->fn);
        } else {
            cr_expect_gt(off->x, 0.0, "no pull: ends before x returns to 0 (x %.3e)", off->x);
        }
        cd_data_free(d);
        cd_model_free(m);
    }
    cr_expect_lt(dur[0], dur[1], "no-pull contact ends first (%.6g < %.6g)", dur[0], dur[1]);
}

/* ---- 7. model / data split -------------------------------------------------------- */

static unsigned long long fnv(unsigned long long h, const void *p, size_t n)
{
    const unsigned char *c = (const unsigned char *)p;
    size_t i;
    for (i = 0; i < n; i++) h = (h ^ c[i]) * 1099511628211ULL;
    return h;
}

static unsigned long long model_hash(const cd_model *m)
{
    unsigned long long h = 1469598103934665603ULL;
    size_t nb = (size_t)m->nbody, D = sizeof(double), I = sizeof(int);
    h = fnv(h, m, sizeof *m);
    h = fnv(h, m->body_jnt_pos, 3 * nb * D); h = fnv(h, m->body_jnt_rot, 9 * nb * D);
    h = fnv(h, m->body_axis, 3 * nb * D); h = fnv(h, m->body_mass, nb * D); h = fnv(h, m->body_com, 3 * nb * D);
    h = fnv(h, m->body_inertia, 9 * nb * D); h = fnv(h, m->body_q0, nb * D); h = fnv(h, m->body_qd0, nb * D);
    h = fnv(h, m->body_limit, 6 * nb * D); h = fnv(h, m->body_fric, 3 * nb * D); h = fnv(h, m->body_spring, 2 * nb * D);
    h = fnv(h, m->cp_pos, 3 * (size_t)m->ncp * D); h = fnv(h, m->shape_size, 3 * (size_t)m->nshape * D);
    h = fnv(h, m->law, (size_t)m->nlaw * sizeof *m->law);
    h = fnv(h, m->slot_cp, (size_t)m->nslot * I); h = fnv(h, m->slot_shape, (size_t)m->nslot * I);
    h = fnv(h, m->act_prm, 4 * (size_t)m->nu * D); h = fnv(h, m->tbl_t, (size_t)m->ntbl * D);
    h = fnv(h, m->sys_pos0, 3 * (size_t)m->nsys * D); h = fnv(h, m->sys_quat0, 4 * (size_t)m->nsys * D);
    return h;
}

Test(seams, a_run_leaves_the_model_bytes_unchanged_and_the_data_holds_no_model_pointer)
{
    /* The model is read-only after finalize: its struct and arrays hash the
     * same after a run with events. The data keeps no pointer to it: a run
     * continued with an identical model built anew, the first one freed, is
     * bit-identical to a run on one model (ASan would flag a stale pointer). */
    cd_model *m = slide_scene(CD_STEP_RK8PD), *m2, *m3;
    cd_data *d = mk(m), *d3;
    unsigned long long h0 = model_hash(m);
    adv(m, d, 0.1);
    cr_expect_eq(model_hash(m), h0, "the run wrote into the model");
    cd_model_free(m);
    m2 = slide_scene(CD_STEP_RK8PD);
    adv(m2, d, 0.2);
    m3 = slide_scene(CD_STEP_RK8PD);
    d3 = mk(m3);
    adv(m3, d3, 0.1);
    adv(m3, d3, 0.2);
    cr_expect_eq(memcmp(d->y, d3->y, (size_t)m3->ny * sizeof(double)), 0, "continued on a new model copy");
    cd_data_free(d); cd_data_free(d3);
    cd_model_free(m2); cd_model_free(m3);
}

Test(seams, model_without_degrees_of_freedom_is_a_clean_error)
{
    cd_model *m = cd_model_create();
    cd_error e;
    add_system(m, "rock", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    fin(m);
    cr_expect_null(cd_data_create(m, 0, &e));
    cr_expect_eq(e.status, CD_EINVAL);
    cr_expect(strstr(e.msg, "no degree of freedom") != NULL, "%s", e.msg);
    cd_model_free(m);
}

typedef struct { char buf[1 << 20]; size_t used; int nalloc, nfree; } arena;
static void *arena_alloc(size_t n, void *ctx)
{
    arena *a = (arena *)ctx;
    void *p;
    a->used = (a->used + 15) & ~(size_t)15;
    if (a->used + n > sizeof a->buf) return NULL;
    p = a->buf + a->used;
    a->used += n;
    a->nalloc++;
    return p;
}
static void arena_free(void *p, void *ctx) { (void)p; ((arena *)ctx)->nfree++; }

Test(seams, data_comes_from_the_callers_allocator_in_one_block)
{
    /* The data's arrays and its integrator's buffers are one block from the
     * caller's allocator; a run takes nothing more; free returns it. */
    static arena A;
    cd_allocator al = {arena_alloc, arena_free, &A};
    cd_model *m = slide_scene(CD_STEP_RK8PD);
    cd_error e;
    cd_data *d = cd_data_create_ex(m, 64, &al, &e);
    cr_assert(d, "%s", e.msg);
    cr_expect_eq(A.nalloc, 1, "blocks: %d", A.nalloc);
    adv(m, d, 0.1);
    cr_expect_eq(A.nalloc, 1, "a run allocated %d more", A.nalloc - 1);
    cd_data_free(d);
    cr_expect_eq(A.nfree, 1);
    cd_model_free(m);
}

Test(seams, evaluation_budget_bounds_a_fixed_rate_step)
{
    /* cd_step onto an impact with max_evals = 20: the step's evaluations stay
     * within the budget, the event is landed early (counted). Unlimited, the
     * same step locates the onset to event_tol. */
    long used[2];
    int lim;
    for (lim = 0; lim < 2; lim++) {
        cd_model *m = cd_model_create();
        cd_contact_law law = cd_contact_law_default();
        cd_error e;
        cd_data *d;
        double pos[3] = {0, 0, 0.5e-3}, vel[3] = {0, 0, -1};
        int g = add_system(m, "wall", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL), pl, s, lid;
        long n0;
        pl = add_plane(m, m->sys_body_adr[g]);
        s = add_system(m, "ball", CD_BASE_FREE, 1.0, 1.0, pos, vel, NULL);
        add_point(m, m->sys_body_adr[s]);
        lid = cd_model_add_law(m, &law, &e);
        cr_assert(cd_model_add_pair(m, s, -1, pl, lid, &e) >= 0);
        m->opt.stepper = CD_STEP_RK4_FIXED;
        fin(m);
        d = mk(m);
        d->opt.max_evals = lim ? 20 : 0;
        n0 = d->stats.nrhs;
        cr_assert_eq(cd_step(m, d, 1e-3, &e), CD_OK, "%s", e.msg);
        used[lim] = d->stats.nrhs - n0;
        cr_expect_eq(count_kind(d, CD_EV_ONSET), 1);
        if (lim) {
            cr_expect_leq(used[1], 20, "evaluations %ld > budget", used[1]);
            cr_expect_gt(d->stats.nwarn_budget, 0);
        }
        cd_data_free(d);
        cd_model_free(m);
    }
    cr_log_info("evaluations for the impact step: %ld unlimited, %ld with max_evals 20", used[0], used[1]);
    cr_expect_gt(used[0], 20, "unlimited location costs more than the budget");
}
