/* What the caller writes between calls takes effect exactly at the call
 * boundary (docs/embedding.md, "What may be written between calls"): the
 * four cases its "Known limitations" listed, now fixed (issue 24). With the
 * fixed-step RK4, a cd_step call whose inputs did not change costs 4
 * right-hand-side evaluations (the previous end evaluation is the first
 * stage); a call after a change restarts the stepper and costs 5. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <string.h>

static double g_never(const cd_model *m, const cd_data *d, int i, void *user)
{
    (void)m; (void)d; (void)i; (void)user;
    return 1.0; /* never switches */
}
static int tr_same(const cd_model *m, cd_data *d, int i, void *user)
{
    (void)m; (void)user;
    return d->user_mode[i];
}
static void law_a(const cd_model *m, cd_data *d, void *user)
{
    (void)m; (void)user;
    d->ctrl[0] = 0.1 * (d->user_mode[0] + 1);
}
static void law_b(const cd_model *m, cd_data *d, void *user)
{
    (void)m; (void)user;
    d->ctrl[0] = -0.1;
}

/* a free base with one revolute link driven by actuator 0; 1 user switch */
static cd_model *arm(void)
{
    cd_model *m = cd_model_create();
    cd_error e;
    cd_system_desc s = cd_system_desc_default();
    cd_link_desc l = cd_link_desc_default();
    cd_actuator_desc a = cd_actuator_desc_default();
    double ratio = 1.0;
    int sys, b;
    s.name = "base";
    sys = cd_model_add_system(m, &s, &e);
    cr_assert_geq(sys, 0, "%s", e.msg);
    l.name = "link";
    l.parent = m->sys_body_adr[sys];
    l.com[0] = 0.5;
    b = cd_model_add_link(m, sys, &l, &e);
    cr_assert_geq(b, 0, "%s", e.msg);
    a.name = "motor";
    a.type = CD_ACT_NONE;
    a.ntrn = 1;
    a.trn_body = &b;
    a.trn_ratio = &ratio;
    cr_assert_geq(cd_model_add_actuator(m, &a, &e), 0, "%s", e.msg);
    cr_assert_eq(cd_model_set_user_switches(m, 1, &e), CD_OK, "%s", e.msg);
    m->opt.stepper = CD_STEP_RK4_FIXED;
    cr_assert_eq(cd_model_finalize(m, &e), CD_OK, "%s", e.msg);
    return m;
}

/* evaluations of one cd_step of 1 ms */
static long step_cost(const cd_model *m, cd_data *d)
{
    cd_error e;
    long n0 = d->stats.nrhs;
    cr_assert_eq(cd_step(m, d, 1e-3, &e), CD_OK, "%s", e.msg);
    return d->stats.nrhs - n0;
}

Test(call_boundary, user_modes_callbacks_and_rejected_calls_are_seen_at_the_next_call)
{
    cd_model *m = arm();
    cd_error e;
    cd_data *d = cd_data_create(m, 0, &e);
    cr_assert_not_null(d, "%s", e.msg);
    cd_data_set_user_switches(d, g_never, tr_same, NULL);
    cd_data_set_control(d, law_a, NULL);
    (void)step_cost(m, d);
    cr_expect_eq(step_cost(m, d), 4, "nothing changed: 4 evaluations");
    d->user_mode[0] = 1;
    cr_expect_eq(step_cost(m, d), 5, "a user mode written between calls restarts the stepper");
    cr_expect_eq(step_cost(m, d), 4);
    cd_data_set_control(d, law_b, NULL);
    cr_expect_eq(step_cost(m, d), 5, "a new control callback restarts the stepper");
    cd_data_set_control(d, law_b, &e); /* same function, another user pointer */
    cr_expect_eq(step_cost(m, d), 5, "a new user pointer restarts the stepper");
    cd_data_set_user_switches(d, g_never, tr_same, &e);
    cr_expect_eq(step_cost(m, d), 5, "new user-switch functions restart the stepper");
    /* a rejected call leaves no trace: the state edit made before it is
     * still seen by the next call */
    d->y[0] += 1e-3;
    cr_expect_eq(cd_sim_advance(m, d, d->t - 1.0, NULL, NULL, &e), CD_EINVAL);
    cr_expect_eq(cd_step(m, d, -1.0, &e), CD_EINVAL);
    cr_expect_eq(step_cost(m, d), 5, "the edit before the rejected calls restarts the stepper");
    cd_data_free(d);
    cd_model_free(m);
}

Test(call_boundary, h_fixed_takes_effect_at_the_next_call)
{
    /* cd_sim_advance with the fixed RK4 steps h_fixed: changed between
     * calls from 1e-3 to 2.5e-4 s, the next 10 ms take 40 steps, not 10. */
    cd_model *m = arm();
    cd_error e;
    cd_data *d;
    long n0;
    m->opt.h_fixed = 1e-3;
    d = cd_data_create(m, 0, &e);
    cr_assert_not_null(d, "%s", e.msg);
    n0 = d->stats.nsteps;
    cr_assert_eq(cd_sim_advance(m, d, 0.01, NULL, NULL, &e), CD_OK, "%s", e.msg);
    cr_expect_eq(d->stats.nsteps - n0, 10);
    d->opt.h_fixed = 2.5e-4;
    n0 = d->stats.nsteps;
    cr_assert_eq(cd_sim_advance(m, d, 0.02, NULL, NULL, &e), CD_OK, "%s", e.msg);
    cr_expect_eq(d->stats.nsteps - n0, 40, "steps of the new h_fixed: %ld", d->stats.nsteps - n0);
    cd_data_free(d);
    cd_model_free(m);
}
