/* Stick-slip validation (issue 3, tests 3 and 4) and the chattering guard.
 *
 * The sliding "block" is a point contact: a check point of radius 0 at the
 * block's CoM, so friction exerts no moment and the motion is the textbook
 * particle-on-a-surface one. Loads that must act on the block only (a normal
 * load) are user wrenches (d->xfrc_applied); surfaces that move (a slowly
 * tilting slope, a belt) are free bodies of 1e15 kg, on which the contact
 * reactions produce accelerations below 1e-13 m/s^2. */
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include "scene_util.h"
#include <math.h>
#include <string.h>

static const double G = 9.81;

static double norm3(const double *a) { return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }




static cd_contact_law law_for(double mass, double K, double Kt, double mu_s, double mu_k)
{
    cd_contact_law law = cd_contact_law_default();
    law.K = K;
    law.D = 2.0 * sqrt(K * mass); /* critical damping (paper's rule, zeta = 1) */
    law.Kt = Kt;
    law.Dt = 2.0 * sqrt(Kt * mass);
    law.mu_s = mu_s;
    law.mu_k = mu_k;
    return law;
}

static void finalize(cd_model *m)
{
    cd_error e;
    cr_assert(cd_model_finalize(m, &e) == CD_OK, "%s", e.msg);
    m->opt.rtol = 1e-11;
    m->opt.atol = 1e-13;
    m->opt.h_max = 1e-3;
}

static int count_kind(const cd_data *d, int kind)
{
    long i;
    int n = 0;
    for (i = 0; i < d->ev_count; i++)
        if (cd_data_event(d, i)->kind == kind) n++;
    return n;
}

/* ---- test 3: block on an incline ----------------------------------------- */
/* The slope is the plane z = 0 of a fixed support; gravity makes angle th with
 * the slope normal: g = G (sin th, 0, -cos th). The block (1 kg) starts at rest
 * at the static penetration x0 = m G cos th / K, so no normal mode is excited. */
typedef struct { cd_model *m; cd_data *d; int block; } scene;

static scene incline(double th, double mu_s, double mu_k)
{
    scene r;
    cd_error e;
    double mass = 1.0, K = 1e6, pos[3] = {0, 0, 0};
    int ground, plane, lid;
    r.m = cd_model_create();
    ground = add_system(r.m, "slope", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    plane = add_plane(r.m, r.m->sys_body_adr[ground]);
    pos[2] = -mass * G * cos(th) / K;
    /* The contact point lies x/2 below the check point (middle of the overlap),
     * so friction has a lever of ~5 um about the CoM; with a single point
     * nothing resists the tipping it drives. A large rotational inertia keeps
     * this idealised point block from tipping (1e6 kg m^2: < 1e-14 rad in 10 s). */
    r.block = add_system(r.m, "block", CD_BASE_FREE, mass, 1e6, pos, NULL, NULL);
    add_point(r.m, r.m->sys_body_adr[r.block]);
    {
        cd_contact_law law = law_for(mass, K, 1e6, mu_s, mu_k);
        lid = cd_model_add_law(r.m, &law, &e);
    }
    cr_assert(cd_model_add_pair(r.m, r.block, -1, plane, lid, &e) >= 0, "%s", e.msg);
    r.m->gravity[0] = G * sin(th);
    r.m->gravity[2] = -G * cos(th);
    finalize(r.m);
    r.d = cd_data_create(r.m, 0, &e);
    cr_assert(r.d, "%s", e.msg);
    return r;
}

Test(friction, incline_sticks_without_creep)
{
    /* tan th = 0.45 < mu_s = 0.5: the block sticks; the stick spring holds a
     * constant deflection, so after settling there is no creep: drift over
     * 10 s < 1e-9 m (issue 3, test 3). */
    double th = atan(0.45), x1, x2, ft;
    scene r = incline(th, 0.5, 0.4);
    cd_error e;
    cr_assert_eq(r.d->slot_mode[0], CD_MODE_STICK, "a contact closed at t = 0 starts sticking");
    /* start settled: the stick spring preloaded to hold m G sin th (f_t = -K_t z).
     * From z = 0 the critically damped spring's force overshoots its final
     * value by e^-2 = 13.5 % (f = F - m zddot), which at tan th = 0.45 would
     * exceed mu_s = 0.5 and rightly break the block loose. */
    r.d->y[r.m->ny_slot_adr] = 1.0 * G * sin(th) / r.m->law[0].Kt;
    cr_assert_eq(cd_sim_advance(r.m, r.d, 1.0, NULL, NULL, &e), CD_OK, "%s", e.msg);
    x1 = cd_state_of(r.m, r.d, r.block).pos[0];
    cr_assert_eq(cd_sim_advance(r.m, r.d, 11.0, NULL, NULL, &e), CD_OK, "%s", e.msg);
    x2 = cd_state_of(r.m, r.d, r.block).pos[0];
    cr_log_info("incline stick: creep %.3e m over 10 s, nrhs %ld", x2 - x1, r.d->stats.nrhs);
    cr_expect_lt(fabs(x2 - x1), 1e-9, "creep %.3e m over 10 s", x2 - x1);
    cr_expect_eq(count_kind(r.d, CD_EV_STICK_SLIP), 0, "no slip below the static limit");
    cr_expect_eq(r.d->slot_mode[0], CD_MODE_STICK);
    /* the friction force balances the slope component of the weight, 1e-9 rel */
    ft = norm3(r.d->slot_ft);
    cr_expect_lt(fabs(ft - G * sin(th)) / (G * sin(th)), 1e-9, "f_t = %.12g N", ft);
    cd_data_free(r.d);
    cd_model_free(r.m);
}

/* The same hold with the linearly implicit stepper: a quiet stick is stiff
 * (the stick spring-damper on a 1 kg block), so explicit steps are capped by
 * stability while ros34pw2's are not: the same no-creep and force balance
 * (1e-9), with at least 5x fewer evaluations than rk8pd (measured: 678 vs
 * 37 247, 55x, h_max 0.1 s: rk8pd stays below 8e-3 s, ros34pw2 reaches 0.1 s). */
Test(friction, incline_holds_with_the_stiff_stepper_in_fewer_evaluations)
{
    double th = atan(0.45), x[2][2], ft[2];
    long nrhs[2];
    int k;
    for (k = 0; k < 2; k++) {
        scene r = incline(th, 0.5, 0.4);
        cd_error e;
        cd_data_free(r.d);
        r.m->opt.stepper = k ? CD_STEP_ROS34PW2 : CD_STEP_RK8PD;
        r.m->opt.h_max = 0.1; /* let the step grow as far as each method allows */
        r.d = cd_data_create(r.m, 0, &e);
        cr_assert(r.d, "%s", e.msg);
        r.d->y[r.m->ny_slot_adr] = 1.0 * G * sin(th) / r.m->law[0].Kt;
        cr_assert_eq(cd_sim_advance(r.m, r.d, 1.0, NULL, NULL, &e), CD_OK, "%s", e.msg);
        x[k][0] = cd_state_of(r.m, r.d, r.block).pos[0];
        cr_assert_eq(cd_sim_advance(r.m, r.d, 11.0, NULL, NULL, &e), CD_OK, "%s", e.msg);
        x[k][1] = cd_state_of(r.m, r.d, r.block).pos[0];
        ft[k] = norm3(r.d->slot_ft);
        nrhs[k] = r.d->stats.nrhs;
        cr_log_info("%s: %ld steps, %ld rejected, %ld Jacobians, h %.3g..%.3g", cd_stepper_name(r.m->opt.stepper),
                    r.d->stats.nsteps, r.d->stats.nrejected, r.d->stats.njac, r.d->stats.h_min_seen, r.d->stats.h_max_seen);
        cr_expect_eq(count_kind(r.d, CD_EV_STICK_SLIP), 0, "%s: no slip", cd_stepper_name(r.m->opt.stepper));
        cd_data_free(r.d);
        cd_model_free(r.m);
    }
    cr_log_info("incline hold: rk8pd %ld rhs, ros34pw2 %ld rhs (%.1fx); creep %.2e / %.2e m", nrhs[0], nrhs[1],
                (double)nrhs[0] / (double)nrhs[1], x[0][1] - x[0][0], x[1][1] - x[1][0]);
    cr_expect_lt(fabs(x[1][1] - x[1][0]), 1e-9, "ros34pw2 creep %.3e m over 10 s", x[1][1] - x[1][0]);
    cr_expect_lt(fabs(ft[1] - G * sin(th)) / (G * sin(th)), 1e-9, "ros34pw2 f_t = %.12g N", ft[1]);
    cr_expect_geq(nrhs[0], 5 * nrhs[1], "rk8pd %ld vs ros34pw2 %ld evaluations", nrhs[0], nrhs[1]);
}

Test(friction, incline_slides_with_coulomb_acceleration)
{
    /* tan th = 0.55 > mu_s = 0.5: the block breaks loose and slides with
     * a = G (sin th - mu_k cos th) (issue 3, test 3), within 1e-6 relative. */
    double th = atan(0.55), a_exact = G * (sin(th) - 0.4 * cos(th)), v1, v2, a;
    scene r = incline(th, 0.5, 0.4);
    cd_error e;
    cr_assert_eq(cd_sim_advance(r.m, r.d, 0.5, NULL, NULL, &e), CD_OK, "%s", e.msg);
    cr_assert_eq(count_kind(r.d, CD_EV_STICK_SLIP), 1, "one stick -> slip event");
    cr_assert_eq(r.d->slot_mode[0], CD_MODE_SLIP);
    v1 = cd_state_of(r.m, r.d, r.block).vel[0];
    cr_assert_eq(cd_sim_advance(r.m, r.d, 1.5, NULL, NULL, &e), CD_OK, "%s", e.msg);
    v2 = cd_state_of(r.m, r.d, r.block).vel[0];
    a = (v2 - v1) / 1.0;
    cr_log_info("incline slide: a = %.12g, exact %.12g, rel %.2e, nrhs %ld", a, a_exact, (a - a_exact) / a_exact, r.d->stats.nrhs);
    cr_expect_lt(fabs(a - a_exact) / a_exact, 1e-6, "a = %.12g, exact %.12g", a, a_exact);
    cr_expect_eq(count_kind(r.d, CD_EV_SLIP_STICK), 0, "it never sticks again");
    cd_data_free(r.d);
    cd_model_free(r.m);
}

Test(friction, slowly_tilted_slope_breaks_loose_on_time)
{
    /* The slope is a 1e15 kg free body rotating about the world y axis at
     * w = 0.002 rad/s from th0 = 20 deg; the block sits on the axis, loaded by
     * its weight m G (-z, world) as a user wrench (gravity would also act on
     * the slope). Quasi-statically f_t = m G sin th(t), f_n = m G cos th(t),
     * so the stick -> slip event is at tan th = mu_s: t* = (atan(mu_s) - th0) / w.
     * The block is x0 = 9 um off the axis and is carried by the surface at
     * v ~ w x0, turning at w: the neglected inertial force m w^2 x0 shifts
     * f_t / f_n by ~1e-10 at w = 0.01 (measured: 8e-9 s), scaling as w^2
     * while the event's sensitivity scales as 1/w: at w = 0.002 it is ~2e-9 s.
     * Issue 3 asks for 1e-8 s. */
    cd_model *m = cd_model_create();
    cd_data *d;
    cd_error e;
    double th0 = 20.0 * M_PI / 180.0, w = 0.002, mass = 1.0, K = 1e6, pos[3] = {0, 0, 0};
    double angvel[3] = {0, -w, 0}; /* rotation about -y raises the +x side: slope down toward -x */
    int slope, plane, block, lid;
    double tstar, t_ev = -1;
    long i;
    cd_system_desc s = cd_system_desc_default();
    s.name = "slope";
    s.mass = 1e15;
    memset(s.inertia, 0, sizeof s.inertia);
    s.inertia[0] = s.inertia[4] = s.inertia[8] = 1e15;
    /* orientation: rotated by -th0 about y so that the slope normal is (sin th0, 0, cos th0):
     * the downhill direction (along which gravity pulls) is -x' */
    s.quat[0] = cos(-th0 / 2); s.quat[2] = sin(-th0 / 2);
    memcpy(s.angvel, angvel, sizeof angvel);
    slope = cd_model_add_system(m, &s, &e);
    cr_assert(slope >= 0, "%s", e.msg);
    plane = add_plane(m, m->sys_body_adr[slope]);
    /* block at the static penetration along the slope normal */
    {
        double x0 = mass * G * cos(th0) / K;
        pos[0] = -x0 * sin(th0); pos[2] = -x0 * cos(th0);
    }
    block = add_system(m, "block", CD_BASE_FREE, mass, 1e6, pos, NULL, NULL); /* no tipping, see incline() */
    add_point(m, m->sys_body_adr[block]);
    {
        cd_contact_law law = law_for(mass, K, 1e6, 0.5, 0.4);
        lid = cd_model_add_law(m, &law, &e);
    }
    cr_assert(cd_model_add_pair(m, block, -1, plane, lid, &e) >= 0, "%s", e.msg);
    finalize(m);
    /* the stick anchor is ~4e-6 m: an absolute tolerance of 1e-13 m would be
     * a 2.5e-8 relative force error, i.e. ~1e-6 s on the event time */
    m->opt.atol = 1e-17;
    m->opt.h_max = 1e-2;
    d = cd_data_create(m, 0, &e);
    cr_assert(d, "%s", e.msg);
    /* block velocity must match the slope surface's at t = 0: the block sits on the axis, v = 0 */
    d->xfrc_applied[6 * m->sys_body_adr[block] + 5] = -mass * G;
    tstar = (atan(0.5) - th0) / w;
    cr_assert_eq(cd_sim_advance(m, d, tstar + 0.5, NULL, NULL, &e), CD_OK, "%s", e.msg);
    for (i = 0; i < d->ev_count; i++)
        if (cd_data_event(d, i)->kind == CD_EV_STICK_SLIP) { t_ev = cd_data_event(d, i)->t; break; }
    cr_assert(t_ev > 0, "no stick -> slip event");
    cr_log_info("tilted slope: stick->slip at %.12f s, exact %.12f s, diff %.2e s, nrhs %ld", t_ev, tstar, t_ev - tstar, d->stats.nrhs);
    cr_expect_lt(fabs(t_ev - tstar), 1e-8, "event at %.12f s, expected %.12f s (diff %.2e)", t_ev, tstar, t_ev - tstar);
    cd_data_free(d);
    cd_model_free(m);
}

/* ---- test 4: mass-spring on a moving belt --------------------------------- */
/* A block of mass m tied to a wall by a spring k sits on a belt moving at v_b
 * (+x) and is pressed on it by a load N. Rigid-stick analysis (Popp & Stelter
 * 1990; any vibrations text): with x_s = mu_s N / k (break-away) and
 * x_k = mu_k N / k (slip centre), X0 = x_s - x_k, w = sqrt(k/m):
 *   slip:  x = x_k + X0 cos(wt) + (v_b/w) sin(wt) until xdot = v_b again,
 *          T_slip = (pi + 2 atan2(v_b / w, X0)) / w, ending at x_k - X0;
 *   stick: carried at v_b from x_k - X0 back to x_s: T_stick = 2 X0 / v_b.
 * The block hangs on two prismatic joints (x, spring; z, free) of a fixed
 * base, so the spring is a PD actuator with kp = k. The belt is a 1e15 kg
 * free body moving at v_b. */
typedef struct { double t_stick, t_slip; long nrhs; } belt_result;

static belt_result run_belt(double kt_ratio)
{
    cd_model *m = cd_model_create();
    cd_data *d;
    cd_error e;
    double mass = 1.0, k = 100.0, N = 10.0, vb = 0.1, K = 1e6, pos[3] = {0, 0, 0}, vel[3] = {0, 0, 0};
    int wall, belt, plane, lid, bx, bz;
    long i;
    double last_stick = -1, last_slip = -1;
    belt_result r = {0, 0, 0};
    cd_link_desc l = cd_link_desc_default();
    cd_actuator spring;
    wall = add_system(m, "wall", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    l.name = "slider";
    l.parent = m->sys_body_adr[wall];
    l.type = CD_JOINT_PRISMATIC;
    l.axis[0] = 1; l.axis[1] = 0; l.axis[2] = 0;
    l.mass = 0.5 * mass;
    bx = cd_model_add_link(m, wall, &l, &e);
    cr_assert(bx >= 0, "%s", e.msg);
    l.name = "block";
    l.parent = bx;
    l.axis[0] = 0; l.axis[2] = 1;
    l.q0 = -N / K; /* static normal penetration */
    bz = cd_model_add_link(m, wall, &l, &e);
    cr_assert(bz >= 0, "%s", e.msg);
    memset(&spring, 0, sizeof spring);
    spring.type = CD_ACT_PD;
    spring.kp = k;
    cr_assert(cd_model_set_actuator(m, bx, &spring, &e) == CD_OK, "%s", e.msg);
    add_point(m, bz);
    vel[0] = vb;
    belt = add_system(m, "belt", CD_BASE_FREE, 1e15, 1e15, pos, vel, NULL);
    plane = add_plane(m, m->sys_body_adr[belt]);
    {
        cd_contact_law law = law_for(mass, K, kt_ratio * k, 0.5, 0.3);
        lid = cd_model_add_law(m, &law, &e);
    }
    cr_assert(cd_model_add_pair(m, wall, bz, plane, lid, &e) >= 0, "%s", e.msg);
    finalize(m);
    d = cd_data_create(m, 0, &e);
    cr_assert(d, "%s", e.msg);
    d->xfrc_applied[6 * bz + 5] = -N;
    /* the block starts at rest on the moving belt: it slips at once, then
     * falls into the limit cycle; measure the last full cycle after 5 s */
    cr_assert_eq(cd_sim_advance(m, d, 6.0, NULL, NULL, &e), CD_OK, "%s", e.msg);
    for (i = 0; i < d->ev_count; i++) {
        const cd_event *ev = cd_data_event(d, i);
        if (ev->t < 3.0) continue;
        if (ev->kind == CD_EV_STICK_SLIP) {
            if (last_stick >= 0) r.t_stick = ev->t - last_stick;
            last_slip = ev->t;
        } else if (ev->kind == CD_EV_SLIP_STICK) {
            if (last_slip >= 0) r.t_slip = ev->t - last_slip;
            last_stick = ev->t;
        }
    }
    r.nrhs = d->stats.nrhs;
    cd_data_free(d);
    cd_model_free(m);
    return r;
}

Test(friction, belt_stick_slip_limit_cycle, .timeout = 120)
{
    double k = 100.0, N = 10.0, vb = 0.1, w = sqrt(k / 1.0);
    double X0 = (0.5 - 0.3) * N / k;
    double T_stick = 2.0 * X0 / vb, T_slip = (M_PI + 2.0 * atan2(vb / w, X0)) / w;
    double ratios[3] = {1e2, 1e3, 1e4}, err_prev = HUGE_VAL;
    int i;
    for (i = 0; i < 3; i++) {
        belt_result r = run_belt(ratios[i]);
        double es = fabs(r.t_stick - T_stick) / T_stick, el = fabs(r.t_slip - T_slip) / T_slip;
        double err = es > el ? es : el;
        cr_log_info("K_t = %g k: stick %.9f (exact %.9f, rel %.2e), slip %.9f (exact %.9f, rel %.2e), nrhs %ld",
                    ratios[i], r.t_stick, T_stick, es, r.t_slip, T_slip, el, r.nrhs);
        cr_assert(r.t_stick > 0 && r.t_slip > 0, "no limit cycle found");
        /* the rigid-stick value is approached as K_t grows */
        cr_expect_lt(err, err_prev, "error must shrink as K_t grows (%.2e after %.2e)", err, err_prev);
        err_prev = err;
        if (ratios[i] >= 1e4) cr_expect_lt(err, 1e-4, "issue 3 test 4: 1e-4 relative at K_t = 1e4 k");
    }
}

/* ---- chattering guard ------------------------------------------------------ */
Test(friction, oblique_impact_cascades_onset_to_slip_in_zero_time)
{
    /* A point hits a plane obliquely with mu_s = mu_k: at onset the tangential
     * damper force D_t |v_t| exceeds mu_s D xdot, so the slot must go open ->
     * stick -> slip at the same instant (a bounded zero-time cascade), then
     * slide; the guard allows at most two switches of a slot at one instant. */
    cd_model *m = cd_model_create();
    cd_data *d;
    cd_error e;
    double pos[3] = {0, 0, 0.01}, vel[3] = {2.0, 0, -1.0};
    int ground, plane, ball, lid;
    const cd_event *e0, *e1;
    ground = add_system(m, "ground", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    plane = add_plane(m, m->sys_body_adr[ground]);
    ball = add_system(m, "ball", CD_BASE_FREE, 1.0, 1.0, pos, vel, NULL);
    add_point(m, m->sys_body_adr[ball]);
    {
        cd_contact_law law = law_for(1.0, 1e5, 1e5, 0.3, 0.3);
        lid = cd_model_add_law(m, &law, &e);
    }
    cr_assert(cd_model_add_pair(m, ball, -1, plane, lid, &e) >= 0);
    finalize(m);
    d = cd_data_create(m, 0, &e);
    cr_assert_eq(cd_sim_advance(m, d, 0.1, NULL, NULL, &e), CD_OK, "%s", e.msg);
    cr_assert_geq(d->ev_count, 3);
    e0 = cd_data_event(d, 0);
    e1 = cd_data_event(d, 1);
    cr_expect_eq(e0->kind, CD_EV_ONSET);
    cr_expect_eq(e1->kind, CD_EV_STICK_SLIP);
    cr_expect_eq(e0->t, e1->t, "the cascade takes zero time");
    cr_expect_lt(fabs(e0->t - 0.01), 1e-9, "onset when the point reaches the plane: t = 0.01 s");
    /* the ball leaves the plane sliding the whole time: separation is the last event */
    cr_expect_eq(cd_data_event(d, d->ev_count - 1)->kind, CD_EV_SEPARATION);
    cr_expect_lt(d->ev_count, 10, "no chattering: %ld events", d->ev_count);
    cd_data_free(d);
    cd_model_free(m);
}

Test(friction, shrinking_cone_slips_once_without_chatter)
{
    /* A block pressed on a table by a spring (1e3 N/m) and pulled along x by a
     * load F_t(t) = 4 - t N; the table recedes at 4 mm/s, so the normal load
     * falls as N(t) = 10 - 4t N. With mu = 0.5 the cone mu N = 5 - 2t shrinks
     * faster than the load: break-away at t = 1 s (quasi-static), then a
     * forward slide (net force t - 1 > 0) until the block leaves the table at
     * N = 0, t = 2.5 s. At break-away the tangential spring is still
     * unloading (the contact point moves against the slip direction): the
     * slip velocity must not be mistaken for a reversal (docs/contact.md),
     * so: one stick -> slip, no slip -> stick, one separation. */
    cd_model *m = cd_model_create();
    cd_data *d;
    cd_error e;
    cd_link_desc l = cd_link_desc_default();
    cd_actuator a;
    double tt[2] = {0.0, 4.0}, ft[2] = {4.0, 0.0}, K = 1e6, vel[3] = {0, 0, -4e-3};
    int rig, table, plane, lid, bx, bz, n_ss, n_ls, n_sep;
    long i;
    double t_ss = -1, t_sep = -1;
    rig = add_system(m, "rig", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    l.parent = m->sys_body_adr[rig];
    l.type = CD_JOINT_PRISMATIC;
    l.axis[0] = 1; l.axis[2] = 0;
    l.mass = 0.5;
    bx = cd_model_add_link(m, rig, &l, &e);
    l.parent = bx;
    l.axis[0] = 0; l.axis[2] = 1;
    l.q0 = -10.0 / K;
    l.qd0 = vel[2]; /* moving down with the table: no normal damper force at t = 0 */
    bz = cd_model_add_link(m, rig, &l, &e);
    cr_assert(bz >= 0, "%s", e.msg);
    memset(&a, 0, sizeof a);
    a.type = CD_ACT_TABLE;
    a.tbl_t = tt;
    a.tbl_v = ft;
    a.ntbl = 2;
    cr_assert(cd_model_set_actuator(m, bx, &a, &e) == CD_OK, "%s", e.msg);
    memset(&a, 0, sizeof a);
    a.type = CD_ACT_PD;
    a.kp = 1e3;
    a.qref = -10.0 / K - 0.01; /* 10 N pressing at t = 0 */
    cr_assert(cd_model_set_actuator(m, bz, &a, &e) == CD_OK, "%s", e.msg);
    add_point(m, bz);
    table = add_system(m, "table", CD_BASE_FREE, 1e15, 1e15, NULL, vel, NULL);
    plane = add_plane(m, m->sys_body_adr[table]);
    {
        cd_contact_law law = law_for(1.0, K, 1e6, 0.5, 0.5);
        lid = cd_model_add_law(m, &law, &e);
    }
    cr_assert(cd_model_add_pair(m, rig, bz, plane, lid, &e) >= 0, "%s", e.msg);
    finalize(m);
    d = cd_data_create(m, 0, &e);
    cr_assert(d, "%s", e.msg);
    d->y[m->ny_slot_adr] = 4.0 / m->law[0].Kt; /* stick spring preloaded to hold F_t(0) */
    cr_assert_eq(cd_sim_advance(m, d, 3.0, NULL, NULL, &e), CD_OK, "%s", e.msg);
    n_ss = count_kind(d, CD_EV_STICK_SLIP);
    n_ls = count_kind(d, CD_EV_SLIP_STICK);
    n_sep = count_kind(d, CD_EV_SEPARATION);
    for (i = 0; i < d->ev_count; i++) {
        const cd_event *ev = cd_data_event(d, i);
        if (ev->kind == CD_EV_STICK_SLIP && t_ss < 0) t_ss = ev->t;
        if (ev->kind == CD_EV_SEPARATION && t_sep < 0) t_sep = ev->t;
    }
    cr_log_info("shrinking cone: %ld events, stick->slip at %.6f s, separation at %.6f s, nrhs %ld",
                d->ev_count, t_ss, t_sep, d->stats.nrhs);
    cr_expect_eq(n_ss, 1, "one break-away (%d)", n_ss);
    cr_expect_eq(n_ls, 0, "no spurious re-stick (%d)", n_ls);
    cr_expect_eq(n_sep, 1);
    /* Exact times. The table is at -v t, the block rides on it, the check
     * point's penetration x obeys the contact law in series with the pressing
     * spring: K x + D xdot = kp (c0 - v t - x), c0 = -qref = 0.01 + 10/K, whose
     * ramp solution (the transient dies at (K + kp)/D = 500 /s) is x = a + b t,
     * b = -kp v / (K + kp), a = (kp c0 - D b) / (K + kp); the normal force is
     * N(t) = kp (c0 - a - (v + b) t). Break-away where 4 - t = mu N(t),
     * separation where N = 0. The block's x motion is uniform during stick and
     * its z motion uniform up to the ramp, so no inertia enters: 1e-7 s. */
    {
        double kp = 1e3, v = 4e-3, c0 = 0.01 + 10.0 / K, D = m->law[0].D;
        double b = -kp * v / (K + kp), a0 = (kp * c0 - D * b) / (K + kp);
        double t1 = (0.5 * kp * (c0 - a0) - 4.0) / (0.5 * kp * (v + b) - 1.0);
        double t2 = (c0 - a0) / (v + b);
        cr_expect_lt(fabs(t_ss - t1), 1e-7, "break-away at %.9f s, expected %.9f s", t_ss, t1);
        cr_expect_lt(fabs(t_sep - t2), 1e-7, "separation at %.9f s, expected %.9f s", t_sep, t2);
    }
    cd_data_free(d);
    cd_model_free(m);
}

Test(friction, sticking_pair_turning_together_keeps_its_force_in_the_body_frame)
{
    /* Two 1e15 kg bodies in stick contact spin together at 1 rad/s about the
     * contact normal (world z): no relative motion, so the held tangential
     * force must turn with them. The anchor is kept in the axes of the
     * shape's body: after a quarter turn the force, seen from that body, is
     * still -1 N along its x (it was -1 N along world x = body x at t = 0),
     * within 1e-9 N; in world axes it has turned to -1 N along y. */
    cd_model *m = cd_model_create();
    cd_data *d;
    cd_error e;
    double pA[3] = {0, 0, -1e-6}, w[3] = {0, 0, 1.0}, fb[3];
    int A, B, sh, lid;
    const double *R, *f;
    B = add_system(m, "plate", CD_BASE_FREE, 1e15, 1e15, NULL, NULL, w);
    A = add_system(m, "pin", CD_BASE_FREE, 1e15, 1e15, pA, NULL, w);
    sh = add_plane(m, m->sys_body_adr[B]);
    add_point(m, m->sys_body_adr[A]);
    {
        cd_contact_law law = cd_contact_law_default();
        law.K = law.Kt = 1e5;
        law.D = law.Dt = 0;
        law.mu_s = law.mu_k = 100; /* it must stick */
        lid = cd_model_add_law(m, &law, &e);
    }
    cr_assert(cd_model_add_pair(m, A, -1, sh, lid, &e) >= 0, "%s", e.msg);
    finalize(m);
    d = cd_data_create(m, 0, &e);
    cr_assert(d, "%s", e.msg);
    cr_assert_eq(d->slot_mode[0], CD_MODE_STICK);
    d->y[m->ny_slot_adr] = 1e-5; /* f_t = -K_t z = -1 N along x */
    cr_assert_eq(cd_sim_advance(m, d, 0.5 * M_PI, NULL, NULL, &e), CD_OK, "%s", e.msg);
    cr_assert_eq(d->slot_mode[0], CD_MODE_STICK);
    R = d->body_R + 9 * m->sys_body_adr[B];
    f = d->slot_ft;
    fb[0] = R[0] * f[0] + R[3] * f[1] + R[6] * f[2];
    fb[1] = R[1] * f[0] + R[4] * f[1] + R[7] * f[2];
    fb[2] = R[2] * f[0] + R[5] * f[1] + R[8] * f[2];
    cr_expect_lt(fabs(fb[0] + 1.0) + fabs(fb[1]) + fabs(fb[2]), 1e-9, "body frame (%g %g %g)", fb[0], fb[1], fb[2]);
    cr_expect_lt(fabs(f[0]) + fabs(f[1] + 1.0), 1e-9, "world (%g %g %g)", f[0], f[1], f[2]);
    cd_data_free(d);
    cd_model_free(m);
}

Test(friction, a_held_slot_keeps_no_pull_and_the_cone)
{
    /* While the chattering guard suspends a slot's switches (slot_held), its
     * forces are clipped: f_n >= 0 (no pull) and |f_t| <= mu_max f_n. Here a
     * sticking point is given a stick deflection worth 10 N against a 1 N
     * normal load (mu_max = 0.5), then moved out of the plane (f_raw < 0). */
    scene r = incline(0.0, 0.5, 0.5);
    cd_error e;
    double ft;
    (void)e;
    cr_assert_eq(r.d->slot_mode[0], CD_MODE_STICK);
    r.d->y[r.m->ny_slot_adr] = 10.0 / r.m->law[0].Kt;
    cr_assert_eq(cd_forward(r.m, r.d), CD_OK);
    ft = norm3(r.d->slot_ft);
    cr_expect_gt(ft, 9.9, "not held: the spring force is what it is (%g N)", ft);
    r.d->slot_held[0] = 1;
    cr_assert_eq(cd_forward(r.m, r.d), CD_OK);
    ft = norm3(r.d->slot_ft);
    cr_expect_leq(ft, 0.5 * r.d->slot_fn[0] * (1 + 1e-12), "held: |f_t| %g > mu f_n %g", ft, 0.5 * r.d->slot_fn[0]);
    /* pulled out of the plane and receding: f_raw < 0, the force stays >= 0 */
    cd_state_of(r.m, r.d, r.block).pos[2] = 1e-6;
    cd_state_of(r.m, r.d, r.block).vel[2] = 1.0;
    cr_assert_eq(cd_forward(r.m, r.d), CD_OK);
    cr_expect_lt(r.d->slot_fnraw[0], 0.0);
    cr_expect_eq(r.d->slot_fn[0], 0.0, "held: no pull (f_n = %g)", r.d->slot_fn[0]);
    cr_expect_eq(norm3(r.d->slot_ft), 0.0);
    cd_data_free(r.d);
    cd_model_free(r.m);
}

/* A point (mass, no gravity) at pos with velocity vel over the fixed plane
 * z = 0, in contact through law; finalized (finalize()). *ball is its system. */
static cd_model *point_over_plane(const cd_contact_law *law, double mass, const double pos[3], const double vel[3],
                                  int *ball)
{
    cd_model *m = cd_model_create();
    cd_error e;
    int ground, plane, lid;
    m->gravity[0] = m->gravity[1] = m->gravity[2] = 0;
    ground = add_system(m, "ground", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    plane = add_plane(m, m->sys_body_adr[ground]);
    *ball = add_system(m, "ball", CD_BASE_FREE, mass, 1.0, pos, vel, NULL);
    add_point(m, m->sys_body_adr[*ball]);
    lid = cd_model_add_law(m, law, &e);
    cr_assert(lid >= 0, "%s", e.msg);
    cr_assert(cd_model_add_pair(m, *ball, -1, plane, lid, &e) >= 0, "%s", e.msg);
    finalize(m);
    return m;
}

Test(friction, slipping_contact_separates_on_time_with_the_coulomb_impulse)
{
    /* A point (1 kg) hits a plane at 1 m/s normal and 2 m/s tangential
     * speed, no gravity, K = 1e5 N/m, zeta = 0.2 (D = 2 zeta sqrt(K m)),
     * mu = 0.3: the slot goes open -> stick -> slip at onset and slides
     * until the linear damper's force reaches 0 (no pull). The normal motion
     * is the damped oscillator x = v0/wd e^(-zeta w t) sin(wd t), so
     * f_raw = K x + D xdot = 0 at wd t = pi - atan(2 zeta sqrt(1 - zeta^2)
     * / (1 - 2 zeta^2)); the friction -mu f_n throughout takes mu J / m off
     * the tangential speed, J = m (v0 - xdot(t_sep)) the normal impulse.
     * Between events the slip law is continued past f_n = 0 (docs/contact.md,
     * and the next test): the located separation and the impulse must not
     * see that continuation. */
    const double mass = 1.0, K = 1e5, zeta = 0.2, mu = 0.3, v0 = 1.0, vt0 = 2.0;
    const double w = sqrt(K / mass), wd = w * sqrt(1.0 - zeta * zeta);
    const double ts = (M_PI - atan(2.0 * zeta * sqrt(1.0 - zeta * zeta) / (1.0 - 2.0 * zeta * zeta))) / wd;
    const double xd_sep = v0 * exp(-zeta * w * ts) * (cos(wd * ts) - zeta * w / wd * sin(wd * ts));
    const double vt_out = vt0 - mu * (v0 - xd_sep);
    cd_data *d;
    cd_error e;
    double pos[3] = {0, 0, 0.01}, vel[3] = {vt0, 0, -v0};
    int ball, sep = -1;
    long i;
    cd_contact_law law = law_for(mass, K, K, mu, mu);
    cd_model *m;
    law.D = 2.0 * zeta * sqrt(K * mass);
    m = point_over_plane(&law, mass, pos, vel, &ball);
    m->opt.rtol = 1e-10;
    m->opt.atol = 1e-12;
    d = cd_data_create(m, 0, &e);
    cr_assert(d, "%s", e.msg);
    cr_assert_eq(cd_sim_advance(m, d, 0.012 + ts, NULL, NULL, &e), CD_OK, "%s", e.msg);
    for (i = 0; i < d->ev_count; i++)
        if (cd_data_event(d, i)->kind == CD_EV_SEPARATION) sep = (int)i;
    cr_assert_geq(sep, 2, "onset, stick -> slip, then the separation");
    cr_expect_eq(cd_data_event(d, sep - 1)->kind, CD_EV_STICK_SLIP, "it slid until it left");
    {
        cd_sys_state st = cd_state_of(m, d, ball);
        double tsep = cd_data_event(d, sep)->t - cd_data_event(d, 0)->t;
        cr_log_info("separation %.15g s after onset (closed form %.15g s, off by %.2e s); tangential speed %.15g m/s "
                    "(closed form %.15g); %ld steps, %ld rejected, %ld events",
                    tsep, ts, tsep - ts, st.vel[0], vt_out, d->stats.nsteps, d->stats.nrejected, d->ev_count);
        cr_expect_lt(fabs(tsep - ts), 2e-10, "separation %.15g s after onset, closed form %.15g s", tsep, ts);
        cr_expect_lt(fabs(st.vel[0] - vt_out), 1e-8, "tangential speed %.15g m/s, closed form %.15g m/s", st.vel[0],
                     vt_out);
        cr_expect_lt(fabs(st.vel[2] + xd_sep), 1e-8, "normal speed %.15g m/s, closed form %.15g m/s", st.vel[2],
                     -xd_sep);
    }
    cd_data_free(d);
    cd_model_free(m);
}

Test(friction, slip_law_is_continued_smoothly_past_the_separation_guard)
{
    /* The state of the test above in slip, its penetration x = 1 mm held and
     * its rate xdot swept so that f_raw = K x + D xdot runs from +20 N to -20 N
     * (the separation guard is f_raw = 0): the friction is -mu f_raw along the
     * slip on both sides, one straight line through the guard, so a trial
     * stage past a separation not yet located sees no kink (the law that
     * dropped the friction to 0 at f_raw = 0 had one there, and cascaded
     * rejected steps before soft_wrap's separations, docs/performance.md
     * section 14). A `pull` contact keeps no friction while f_n < 0. */
    const double mass = 1.0, K = 1e5, zeta = 0.2, mu = 0.3, x = 1e-3;
    int pull;
    for (pull = 0; pull < 2; pull++) {
        cd_data *d;
        cd_error e;
        int ball, i;
        const double zero[3] = {0, 0, 0};
        cd_contact_law law = law_for(mass, K, K, mu, mu);
        cd_model *m;
        law.D = 2.0 * zeta * sqrt(K * mass);
        law.pull = pull;
        m = point_over_plane(&law, mass, zero, zero, &ball);
        d = cd_data_create(m, 0, &e);
        cr_assert(d, "%s", e.msg);
        d->slot_mode[0] = CD_MODE_SLIP;
        d->slot_dir[0] = 1.0;
        d->slot_dir[1] = d->slot_dir[2] = 0.0;
        for (i = -20; i <= 20; i++) {
            double f_target = (double)i, xdot = (f_target - K * x) / law.D, ftx;
            cd_sys_state st = cd_state_of(m, d, ball);
            st.pos[2] = -x;    /* the solid is z <= 0 */
            st.vel[0] = 2.0;   /* sliding along +x */
            st.vel[2] = -xdot; /* xdot = -v.n */
            cr_assert_eq(cd_forward(m, d), CD_OK);
            cr_assert_lt(fabs(d->slot_fnraw[0] - f_target), 1e-9, "f_raw %.17g N, set %g N", d->slot_fnraw[0], f_target);
            ftx = d->slot_ft[0];
            if (!pull || f_target > 0)
                cr_expect_lt(fabs(ftx + mu * d->slot_fnraw[0]), 1e-12 * (1.0 + fabs(d->slot_fnraw[0])),
                             "pull %d, f_raw %g N: friction %.17g N, -mu f_raw %.17g N", pull, f_target, ftx,
                             -mu * d->slot_fnraw[0]);
            else
                cr_expect_eq(ftx, 0.0, "a pulling contact holds no friction: %.17g N at f_raw %g N", ftx, f_target);
            cr_expect_eq(d->slot_ft[1], 0.0);
        }
        cd_data_free(d);
        cd_model_free(m);
    }
}
