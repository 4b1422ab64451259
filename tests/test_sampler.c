/* Dense output (issue 11; src/sim/sampler.c, docs/dynamics.md "Dense
 * output"): samples by cubic Hermite interpolation inside the integrator's
 * own steps, never by shortening them.
 *
 * Closed form: a link on a revolute joint about its own CoM axis with a
 * passive spring, q(t) = q0 cos(w t), w = sqrt(k / I). The Hermite
 * interpolant of the exact solution over a step h is off by at most
 * h^4 max|q''''| / 384 = h^4 w^4 q0 / 384; with the steps at most h_max,
 * every sample must be within that bound (plus the integration error,
 * 1e-9 at rtol 1e-11). */
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include "scene_util.h"
#include <math.h>
#include <string.h>

#define Q0 0.3
#define KSPRING 4.0
#define IZZ 0.01

static cd_model *oscillator(double h_max, cd_stepper stp)
{
    cd_model *m = cd_model_create();
    cd_link_desc l = cd_link_desc_default();
    cd_joint_props p = cd_joint_props_default();
    cd_error e;
    int b;
    add_system(m, "base", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    l.parent = 0;
    l.mass = 1.0;
    memset(l.inertia, 0, sizeof l.inertia);
    l.inertia[0] = l.inertia[4] = 0.02;
    l.inertia[8] = IZZ;
    l.q0 = Q0;
    b = cd_model_add_link(m, 0, &l, &e);
    cr_assert(b > 0, "%s", e.msg);
    p.stiffness = KSPRING;
    cr_assert_eq(cd_model_set_joint(m, b, &p, &e), CD_OK, "%s", e.msg);
    m->gravity[0] = m->gravity[1] = m->gravity[2] = 0;
    cr_assert_eq(cd_model_finalize(m, &e), CD_OK, "%s", e.msg);
    m->opt.stepper = stp;
    m->opt.rtol = 1e-11;
    m->opt.atol = 1e-13;
    m->opt.h_max = h_max;
    return m;
}

typedef struct { double t[4096], q[4096]; int n; } samples;

static int keep(const cd_model *m, const cd_data *d, void *user)
{
    samples *s = (samples *)user;
    cr_assert_lt(s->n, 4096);
    s->t[s->n] = d->t;
    s->q[s->n] = d->y[m->sys_y_adr[0]];
    s->n++;
    return 0;
}

typedef struct { cd_sampler *s; samples *out; } cb_ctx;

static int on_step(const cd_model *m, cd_data *d, void *user)
{
    cb_ctx *c = (cb_ctx *)user;
    return cd_sampler_update(c->s, m, d, keep, c->out);
}

Test(sampler, samples_between_steps_follow_the_closed_form_within_the_hermite_bound)
{
    static samples S;
    const double w = sqrt(KSPRING / IZZ), dt = 1e-3, h_max = 0.02, T = 2.0;
    double bound = pow(h_max * w, 4) * Q0 / 384.0 + 1e-9, worst = 0;
    cd_model *m = oscillator(h_max, CD_STEP_RK8PD);
    cd_error e;
    cd_data *d = cd_data_create(m, 0, &e);
    cb_ctx c;
    int i;
    cr_assert(d, "%s", e.msg);
    c.s = cd_sampler_create(m, &e);
    cr_assert(c.s, "%s", e.msg);
    c.out = &S;
    S.n = 0;
    cr_assert_eq(cd_sampler_begin(c.s, m, d, dt, dt, &e), CD_OK, "%s", e.msg);
    cr_assert_eq(cd_sim_advance(m, d, T, on_step, &c, &e), CD_OK, "%s", e.msg);
    cr_expect_eq(S.n, (int)lround(T / dt), "one sample per dt up to T: %d", S.n);
    for (i = 0; i < S.n; i++) {
        double err = fabs(S.q[i] - Q0 * cos(w * S.t[i]));
        cr_expect_leq(fabs(S.t[i] - (i + 1) * dt), 1e-15, "sample %d at %.17g", i, S.t[i]);
        if (err > worst) worst = err;
    }
    cr_log_info("%d samples from %ld steps (dt %g s, steps up to %g s): worst |q - q0 cos wt| %.3g rad, bound %.3g",
                S.n, d->stats.nsteps, dt, d->stats.h_max_seen, worst, bound);
    cr_expect_leq(worst, bound, "worst sample error %.3g rad above the Hermite bound %.3g", worst, bound);
    cr_expect_lt(d->stats.nsteps, S.n / 5, "the samples did not shorten the steps: %ld steps", d->stats.nsteps);
    cd_sampler_free(c.s);
    cd_data_free(d);
    cd_model_free(m);
}

typedef struct { double t[512], z[512]; int mode[512], n, zi; } ball_samples;

static int keep_ball(const cd_model *m, const cd_data *d, void *user)
{
    ball_samples *s = (ball_samples *)user;
    (void)m;
    cr_assert_lt(s->n, 512);
    s->t[s->n] = d->t;
    s->z[s->n] = d->y[s->zi];
    s->mode[s->n] = d->slot_mode[0];
    s->n++;
    return 0;
}

typedef struct { cd_sampler *s; ball_samples *out; } ball_ctx;

static int on_ball_step(const cd_model *m, cd_data *d, void *user)
{
    ball_ctx *c = (ball_ctx *)user;
    return cd_sampler_update(c->s, m, d, keep_ball, c->out);
}

Test(sampler, events_end_steps_so_samples_keep_each_side_of_a_contact)
{
    /* A ball (check sphere 0.05 m) at 1 m/s onto a plane from 10.25 mm (the
     * onset at 10.25 ms, between samples), K 1e4, D 20, 1 kg,
     * sampled every 0.5 ms for 80 ms: every sample's contact mode equals that
     * of a run stopped at the sample time (samples never straddle the onset
     * or the separation: events end steps), and the heights agree within the
     * Hermite bound of the contact phase, (h_max w)^4 / 384 x v0 / w with
     * w = 100 rad/s, h_max = 2 ms: 1.0e-6 m. */
    static ball_samples A;
    cd_model *m = cd_model_create();
    cd_error e;
    cd_data *d, *ref;
    ball_ctx c;
    double pos[3] = {0, 0, 0.06025}, vel[3] = {0, 0, -1.0}, zero[3] = {0, 0, 0}, worst = 0, bound;
    int ground, ball, plane, lid, i, in_contact = 0;
    cd_contact_law law = cd_contact_law_default();
    ground = add_system(m, "ground", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    plane = add_plane(m, m->sys_body_adr[ground]);
    ball = add_system(m, "ball", CD_BASE_FREE, 1.0, 1e-3, pos, vel, NULL);
    cr_assert(cd_model_add_checkpoint(m, m->sys_body_adr[ball], zero, 0.05, &e) >= 0, "%s", e.msg);
    law.K = 1e4; law.D = 20; law.mu_s = law.mu_k = 0;
    lid = cd_model_add_law(m, &law, &e);
    cr_assert(lid >= 0, "%s", e.msg);
    cr_assert(cd_model_add_pair(m, ball, -1, plane, lid, &e) >= 0, "%s", e.msg);
    m->gravity[0] = m->gravity[1] = m->gravity[2] = 0;
    cr_assert_eq(cd_model_finalize(m, &e), CD_OK, "%s", e.msg);
    m->opt.rtol = 1e-10; m->opt.atol = 1e-13; m->opt.h_max = 2e-3;
    bound = pow(2e-3 * 100.0, 4) / 384.0 * (1.0 / 100.0) + 1e-9;
    d = cd_data_create(m, 0, &e);
    cr_assert(d, "%s", e.msg);
    ref = cd_data_create(m, 0, &e);
    cr_assert(ref, "%s", e.msg);
    c.s = cd_sampler_create(m, &e);
    cr_assert(c.s, "%s", e.msg);
    c.out = &A;
    A.n = 0;
    A.zi = m->sys_y_adr[ball] + 2;
    cr_assert_eq(cd_sampler_begin(c.s, m, d, 5e-4, 5e-4, &e), CD_OK, "%s", e.msg);
    cr_assert_eq(cd_sim_advance(m, d, 0.08, on_ball_step, &c, &e), CD_OK, "%s", e.msg);
    cr_assert_geq(d->ev_count, 2, "onset and separation");
    cr_expect_eq(A.n, 160);
    for (i = 0; i < A.n; i++) {
        double dz;
        cr_assert_eq(cd_sim_advance(m, ref, A.t[i], NULL, NULL, &e), CD_OK, "%s", e.msg);
        cr_expect_eq(A.mode[i], ref->slot_mode[0], "t = %.6g: sampled mode %d, stopped run %d", A.t[i], A.mode[i],
                     ref->slot_mode[0]);
        in_contact += A.mode[i] != CD_MODE_OPEN;
        dz = fabs(A.z[i] - ref->y[A.zi]);
        if (dz > worst) worst = dz;
    }
    cr_log_info("%d samples (%d in contact) from %ld steps, %ld events; worst height difference to stopping at each "
                "sample %.3g m (bound %.3g)", A.n, in_contact, d->stats.nsteps, d->ev_count, worst, bound);
    cr_expect_gt(in_contact, 5, "the contact phase is sampled");
    cr_expect_leq(worst, bound);
    cd_sampler_free(c.s);
    cd_data_free(ref);
    cd_data_free(d);
    cd_model_free(m);
}
