/* Loader keys of the core seams (issue 7): joint springs, dampers, friction,
 * enforced limits with their stop law, prescribed joints and bases, STEPS
 * schedules, motor models, [[actuator]] transmissions, the contact law's
 * pull / p_t / q_t, equilibrium_start; and their error messages. */
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <capdyn/io.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const double DEG = 3.14159265358979323846 / 180.0;

static void path_of(char *out, size_t n, const char *rel)
{
    const char *r = getenv("CAPDYN_ROOT");
    snprintf(out, n, "%s/%s", r ? r : ".", rel);
}

static cd_scenario *load(const char *rel, const char *const *sets, int nsets, cd_error *e)
{
    char p[1024];
    path_of(p, sizeof p, rel);
    return cd_scenario_load(p, sets, nsets, e);
}

Test(scenario_seams, joint_elements_schedules_motors_and_transmissions_load)
{
    cd_error e;
    cd_scenario *sc = load("tests/data/scenarios/joints_transmission.toml", NULL, 0, &e);
    const cd_model *m;
    int l1, l2, l3, sl, a, tr;
    cr_assert(sc, "%s", e.msg);
    m = sc->model;
    l1 = cd_model_body_id(m, "finger/l1");
    l2 = cd_model_body_id(m, "finger/l2");
    l3 = cd_model_body_id(m, "finger/l3");
    sl = cd_model_body_id(m, "finger/slide");
    cr_assert(l1 > 0 && l2 > 0 && l3 > 0 && sl > 0);
    /* limits in radians, stop law as given (D) and defaults (p = q = 1) */
    cr_expect_eq(m->nlim, 1);
    cr_expect_lt(fabs(m->body_limit[6 * l1] + 10 * DEG), 1e-15);
    cr_expect_lt(fabs(m->body_limit[6 * l1 + 1] - 90 * DEG), 1e-15);
    cr_expect_eq(m->body_limit[6 * l1 + 2], 200.0);
    cr_expect_eq(m->body_limit[6 * l1 + 3], 0.5);
    cr_expect_eq(m->body_limit[6 * l1 + 4], 1.0);
    cr_expect_eq(m->body_spring[2 * l1], 0.3);
    cr_expect_lt(fabs(m->body_spring[2 * l1 + 1] - 10 * DEG), 1e-15);
    cr_expect_eq(m->body_damping[l1], 0.01);
    cr_expect_eq(m->nfric, 1);
    cr_expect_eq(m->body_fric[3 * l1], 0.02);
    cr_expect_lt(fabs(m->body_fric[3 * l1 + 1] - 0.02 / 1e-4), 1e-9, "default stick stiffness: breakaway at 1e-4 rad");
    /* prescribed */
    cr_expect_eq(m->body_presc[l3], CD_PRESCRIBE_WAYPOINTS);
    cr_expect_lt(fabs(m->tbl_v[m->body_wp_adr[l3]] - 30 * DEG), 1e-15);
    cr_expect_eq(m->body_presc[sl], CD_PRESCRIBE_VELOCITY);
    cr_expect_eq(m->body_presc_prm[6 * sl], 0.02);
    cr_expect_eq(m->body_presc_prm[6 * sl + 1], 0.01);
    cr_expect_eq(m->body_presc[m->sys_body_adr[1]], CD_PRESCRIBE_VELOCITY, "prescribed base");
    cr_expect_lt(fabs(m->body_presc_prm[6 * m->sys_body_adr[1] + 5] - 5 * DEG), 1e-15);
    /* actuators: the link's STEPS schedule with a motor, the tendon */
    a = m->body_act[l1];
    cr_assert(a >= 0);
    cr_expect_eq(m->act_type[a], CD_ACT_STEPS);
    cr_expect_eq(m->act_tbl_n[a], 2);
    cr_expect_eq(m->act_motor[2 * a], 0.5);
    cr_expect_eq(m->act_motor[2 * a + 1], 20.0);
    tr = cd_model_actuator_id(m, "tendon");
    cr_assert(tr >= 0);
    cr_expect_eq(m->act_type[tr], CD_ACT_PD);
    cr_expect_eq(m->act_trn_n[tr], 2);
    cr_expect_eq(m->trn_body[m->act_trn_adr[tr]], l1);
    cr_expect_eq(m->trn_ratio[m->act_trn_adr[tr]], 2.0);
    cr_expect_eq(m->trn_body[m->act_trn_adr[tr] + 1], l2);
    cr_expect_lt(fabs(m->act_prm[4 * tr + 3] - 45 * DEG), 1e-15);
    /* breakpoints: the schedule rows, the waypoints, the velocity start */
    cr_expect_eq(m->nbreak, 4, "breaks: %d", m->nbreak);
    /* the contact law's options, the run option */
    cr_expect_eq(m->law[0].pull, 1);
    cr_expect_eq(m->law[0].pt, 1.5);
    cr_expect_eq(m->opt.equilibrium_start, 1);
    cd_scenario_free(sc);
}

Test(scenario_seams, the_file_runs)
{
    cd_error e;
    cd_scenario *sc = load("tests/data/scenarios/joints_transmission.toml", NULL, 0, &e);
    cd_data *d;
    int l3;
    cr_assert(sc, "%s", e.msg);
    d = cd_data_create(sc->model, 0, &e);
    cr_assert(d, "%s", e.msg);
    cr_assert_eq(cd_sim_advance(sc->model, d, 0.1, NULL, NULL, &e), CD_OK, "%s", e.msg);
    l3 = cd_model_body_id(sc->model, "finger/l3");
    cr_expect_lt(fabs(cd_joint_q(sc->model, d, l3)), 1e-12, "l3 back at its last waypoint");
    cd_data_free(d);
    cd_scenario_free(sc);
}

/* one override that must fail with a message containing `needle` */
static void bad(const char *set, const char *needle)
{
    cd_error e;
    const char *sets[1] = {set};
    cd_scenario *sc = load("tests/data/scenarios/joints_transmission.toml", sets, 1, &e);
    cr_expect_null(sc, "'%s' was accepted", set);
    if (sc) { cd_scenario_free(sc); return; }
    cr_expect(strstr(e.msg, needle) != NULL, "'%s': message \"%s\" lacks \"%s\"", set, e.msg, needle);
}

Test(scenario_seams, mistakes_are_named)
{
    bad("system[0].link[1].stop={K=1.0}", "a stop needs the joint's limit_deg");
    bad("actuator[0].ratios=[1.0]", "expected 2 ratios (one per joint)");
    bad("actuator[0].joints=[\"finger/l1\",\"finger/nope\"]", "expected the name of a joint");
    bad("actuator[0].joints=[\"finger/l1\",\"finger/l1\"]", "twice");
    bad("system[0].link[0].friction={stiffness=3.0}", "friction.torque");
    bad("system[0].link[2].prescribed={type=\"velocity\",waypoints_deg=[[0.1,1.0]]}", "does not apply to a 'velocity' profile");
    bad("system[0].link[2].prescribed={type=\"jump\"}", "prescribed.type");
    bad("system[0].link[0].actuator.motor={stall_torque=1.0}", "noload_speed");
    bad("contact.pull=1", "expected true or false");
    bad("simulation.equilibrium_start=\"yes\"", "expected true or false");
    bad("contact.p_t=0.5", "p_t");
    bad("system[0].link[0].limit_deg=[-10.0,-5.0]", "initial position within");
}
