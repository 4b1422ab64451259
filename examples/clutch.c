/* clutch.c -- a user switch: a torque clutch that opens at a grip force
 * (docs/embedding.md, "User switches").
 *
 * A one-joint finger (fixed base, revolute about z) closes on a fixed block
 * under a constant motor torque. Between the motor and the finger sits a
 * clutch, modelled as a user switch: engaged (mode 0) it passes the torque;
 * when the normal force at the fingertip's contact reaches F_OPEN it opens
 * (mode 1) and the finger is no longer driven -- the Space Gripper's torque
 * clutch, which limits the grip force whatever the motor does.
 *
 * The switching function is F_OPEN - f_n (negative: open now); the
 * integrator locates its zero like a contact event, calls the transition
 * once, and logs a CD_EV_USER event. The motor torque is applied by a
 * control callback that reads the clutch's mode.
 *
 * What running it checks (exit status 1 otherwise): the clutch opens exactly
 * once; the event log names the switch (CD_EV_USER, owner 0, mode 0 -> 1);
 * at the event the grip force is F_OPEN within FORCE_TOL (the crossing is
 * located to opt.event_tol in time); the motor torque is zero at the end and
 * the return spring has pulled the finger off the block.
 * Needs nothing but <capdyn/capdyn.h> and the C library. */
#include <capdyn/capdyn.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#define MOTOR_TORQUE 2.0     /* [N m] */
#define F_OPEN 3.0           /* [N] grip force at which the clutch opens */
#define JOINT_DAMPING 50.0   /* [N m s/rad] a geared drive: the finger closes slowly (0.04 rad/s) */
#define JOINT_SPRING 5.0     /* [N m/rad] return spring, at rest at the start posture */
#define Q0 0.45              /* [rad] start posture: the fingertip 3 cm from the block */
#define T_END 5.0            /* [s] */
#define NPRINT 12            /* events printed */
#define FORCE_TOL 1e-6       /* [N] */

typedef struct {
    int act, slot;           /* the motor's actuator, the fingertip's contact slot */
    double torque, f_open;
    long nopen;              /* transitions taken */
} clutch;

/* switching function of user switch i: continuous in (t, state) between events */
static double clutch_g(const cd_model *m, const cd_data *d, int i, void *user)
{
    const clutch *c = (const clutch *)user;
    (void)m;
    if (d->user_mode[i] == 1) return 1.0;      /* open: never switches back */
    return c->f_open - d->slot_fn[c->slot];    /* < 0 once the grip force passed f_open */
}

/* transition: called once at the located crossing; returns the new mode */
static int clutch_open(const cd_model *m, cd_data *d, int i, void *user)
{
    clutch *c = (clutch *)user;
    (void)m; (void)d; (void)i;
    c->nopen++;
    return 1;
}

/* control callback, called at every evaluation: the motor torque reaches the
 * finger only through the engaged clutch */
static void clutch_drive(const cd_model *m, cd_data *d, void *user)
{
    const clutch *c = (const clutch *)user;
    (void)m;
    d->ctrl[c->act] = d->user_mode[0] == 0 ? c->torque : 0.0;
}

/* step callback of cd_sim_advance (after every accepted step and every
 * located event): records the grip force at the first state with the clutch open */
typedef struct { double t, fn; int seen; int slot; } watch;
static int watch_open(const cd_model *m, cd_data *d, void *user)
{
    watch *w = (watch *)user;
    (void)m;
    if (!w->seen && d->user_mode[0] == 1) {
        w->seen = 1;
        w->t = d->t;
        w->fn = d->slot_fn[w->slot];
    }
    return 0;   /* go on */
}

static cd_model *build(clutch *c, cd_error *err)
{
    cd_model *m = cd_model_create();
    cd_system_desc hand = cd_system_desc_default(), wall = cd_system_desc_default();
    cd_link_desc finger = cd_link_desc_default();
    cd_actuator_desc motor = cd_actuator_desc_default();
    cd_joint_props jp = cd_joint_props_default();
    cd_contact_law law = cd_contact_law_from_rule(1e3, 10, 0.05, 1.0, 0.3);
    const double tip[3] = {0.5, 0, 0}, block_pos[3] = {0.45, 0.35, 0}, half[3] = {0.2, 0.1, 0.1};
    double ratio = 1.0;
    int hs, ws, fb, sh, lw, k;
    if (!m) { cd_error_set(err, CD_ENOMEM, "out of memory creating the model"); return NULL; }
    hand.type = CD_BASE_FIXED;
    hand.name = "hand";
    wall.type = CD_BASE_FIXED;
    wall.name = "wall";
    /* bodies of one system are contiguous: a system's links before the next system */
    if ((hs = cd_model_add_system(m, &hand, err)) < 0) goto fail;
    /* the finger: 0.5 m along x, turning about z toward the block's face y = 0.25 m */
    finger.name = "finger";
    finger.parent = m->sys_body_adr[hs];
    finger.mass = 0.1;
    finger.com[0] = 0.25;
    memset(finger.inertia, 0, sizeof finger.inertia);
    finger.inertia[0] = 1e-5; finger.inertia[4] = finger.inertia[8] = 0.1 * 0.25 / 12;
    finger.q0 = Q0;
    if ((fb = cd_model_add_link(m, hs, &finger, err)) < 0) goto fail;
    /* a damper on the joint: the finger touches the block at a few cm/s, so
     * the contact force starts below F_OPEN and grows to the motor's push
     * (2 N m against the spring's 0.35 N m: about 3.8 N); a return spring
     * pulls the finger back once the clutch has opened */
    jp.damping = JOINT_DAMPING;
    jp.stiffness = JOINT_SPRING;
    jp.rest = Q0;
    if (cd_model_set_joint(m, fb, &jp, err) != CD_OK) goto fail;
    if ((ws = cd_model_add_system(m, &wall, err)) < 0) goto fail;
    if (cd_model_add_checkpoint(m, fb, tip, 0.01, err) < 0) goto fail;
    sh = cd_model_add_shape(m, m->sys_body_adr[ws], CD_SHAPE_BOX, block_pos, NULL, half, NULL, 0, err);
    if (sh < 0 || (lw = cd_model_add_law(m, &law, err)) < 0 || cd_model_add_pair(m, hs, -1, sh, lw, err) < 0) goto fail;
    motor.name = "motor";
    motor.type = CD_ACT_NONE;            /* torque = d->ctrl[motor], written by the callback */
    motor.ntrn = 1;
    motor.trn_body = &fb;
    motor.trn_ratio = &ratio;
    if ((c->act = cd_model_add_actuator(m, &motor, err)) < 0) goto fail;
    if (cd_model_set_user_switches(m, 1, err) != CD_OK) goto fail;
    if (cd_model_finalize(m, err) != CD_OK) goto fail;
    /* the slot table is built at finalize: find the fingertip x block slot */
    c->slot = -1;
    for (k = 0; k < m->nslot; k++)
        if (m->cp_body[m->slot_cp[k]] == fb && m->slot_shape[k] == sh) c->slot = k;
    if (c->slot < 0) { cd_error_set(err, CD_EINVAL, "no contact slot between the fingertip and the block"); goto fail; }
    return m;
fail:
    cd_model_free(m);
    return NULL;
}

int main(void)
{
    clutch c = {0, 0, MOTOR_TORQUE, F_OPEN, 0};
    cd_error err;
    cd_model *m;
    cd_data *d;
    cd_status st;
    long i, nuser = 0;
    const cd_event *open_ev = NULL;
    watch w = {0, 0, 0, 0};
    int fails = 0;

    memset(&err, 0, sizeof err);
    m = build(&c, &err);
    if (!m) { fprintf(stderr, "clutch: model: %s\n", err.msg); return 1; }
    d = cd_data_create(m, 0, &err);           /* default stepper: adaptive rk8pd */
    if (!d) { fprintf(stderr, "clutch: data: %s\n", err.msg); cd_model_free(m); return 1; }
    /* set the callbacks before the first call */
    cd_data_set_user_switches(d, clutch_g, clutch_open, &c);
    cd_data_set_control(d, clutch_drive, &c);

    w.slot = c.slot;
    st = cd_sim_advance(m, d, T_END, watch_open, &w, &err);
    if (st != CD_OK) {
        fprintf(stderr, "clutch: %s: %s\n", cd_status_string(st), err.msg);
        cd_data_free(d); cd_model_free(m); return 1;
    }

    printf("capdyn clutch: finger closing on a block, clutch opening at %.3g N (%s)\n", F_OPEN,
           cd_stepper_name(d->opt.stepper));
    for (i = 0; i < (d->ev_count < d->ev_cap ? d->ev_count : d->ev_cap); i++) {
        const cd_event *ev = cd_data_event(d, i);
        if (i < NPRINT)
            printf("  event t = %.9f s  %-12s owner %s %d  mode %d -> %d  fn %.9g N\n", ev->t, cd_event_kind_name(ev->kind),
               cd_owner_kind_name(ev->owner_kind), ev->owner, ev->mode_from, ev->mode_to, ev->fn);
        if (ev->kind == CD_EV_USER) { nuser++; open_ev = ev; }
    }
    printf("  %ld events in all; the fingertip's contact at t = %.3f s: %s\n", d->ev_count, d->t,
           cd_slot_mode_name((cd_slot_mode)d->slot_mode[c.slot]));
    printf("  grip force at the opening (t = %.9f s): %.12f N, |error| %.2e N (tolerance %.0e)\n", w.t, w.fn,
           fabs(w.fn - F_OPEN), FORCE_TOL);
    printf("  transitions %ld, user events %ld, clutch mode at t = %.3f s: %d, motor torque %g N m\n", c.nopen, nuser,
           d->t, d->user_mode[0], d->act_force[c.act]);

    if (c.nopen != 1 || nuser != 1) { fprintf(stderr, "FAIL: the clutch must open exactly once\n"); fails++; }
    if (!open_ev || open_ev->owner_kind != CD_OWNER_USER || open_ev->owner != 0 || open_ev->mode_from != 0 ||
        open_ev->mode_to != 1) {
        fprintf(stderr, "FAIL: no event naming user switch 0, mode 0 -> 1\n");
        fails++;
    }
    if (!(fabs(w.fn - F_OPEN) <= FORCE_TOL) || !open_ev || w.t != open_ev->t) {
        fprintf(stderr, "FAIL: the clutch did not open at %g N (force there %.9g N)\n", F_OPEN, w.fn);
        fails++;
    }
    if (d->user_mode[0] != 1 || d->act_force[c.act] != 0.0) { fprintf(stderr, "FAIL: the clutch is not open at the end\n"); fails++; }
    if (d->slot_mode[c.slot] != CD_MODE_OPEN) { fprintf(stderr, "FAIL: the spring did not pull the finger off the block\n"); fails++; }

    cd_data_free(d);
    cd_model_free(m);
    printf("%s\n", fails ? "FAIL" : "PASS");
    return fails ? 1 : 0;
}
