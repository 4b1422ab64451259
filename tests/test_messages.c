/* Messages of the embedding API name the offending input (issue 24): a
 * non-finite input names its array, index and actuator or body; an unnamed
 * link is named by its place, never as "joint ''". */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <capdyn/io.h>
#include <math.h>
#include <string.h>
#include "proc_util.h"

static cd_scenario *arm(cd_stepper stp)
{
    char p[512];
    cd_error e;
    cd_scenario *sc;
    scen(p, sizeof p, "free_floating_arm.toml");
    sc = cd_scenario_load(p, NULL, 0, &e);
    cr_assert_not_null(sc, "%s", e.msg);
    sc->model->opt.stepper = stp;
    return sc;
}

Test(messages, a_nan_control_input_is_named_with_its_actuator)
{
    /* The free-floating arm: d->ctrl[1] = NaN before a call, with the
     * adaptive stepper (cd_sim_advance) and the fixed RK4 (cd_step). Both
     * CD_ENUMERIC (as before) with "d->ctrl[1] (actuator '<name>') is NaN". */
    cd_stepper stp[2] = {CD_STEP_RK8PD, CD_STEP_RK4_FIXED};
    int i;
    for (i = 0; i < 2; i++) {
        cd_scenario *sc = arm(stp[i]);
        cd_error e;
        cd_data *d = cd_data_create(sc->model, 0, &e);
        cd_status st;
        char want[200];
        cr_assert_not_null(d, "%s", e.msg);
        cr_assert_geq(sc->model->nu, 2);
        snprintf(want, sizeof want, "d->ctrl[1] (actuator '%s') is NaN", sc->model->act_name[1]);
        d->ctrl[1] = NAN;
        st = i == 0 ? cd_sim_advance(sc->model, d, 0.01, NULL, NULL, &e) : cd_step(sc->model, d, 1e-3, &e);
        cr_expect_eq(st, CD_ENUMERIC, "%s: status %d (%s)", cd_stepper_name(stp[i]), st, e.msg);
        cr_expect(strstr(e.msg, want) != NULL, "%s: '%s' in: %s", cd_stepper_name(stp[i]), want, e.msg);
        cd_data_free(d);
        cd_scenario_free(sc);
    }
}

Test(messages, a_nan_applied_wrench_names_its_body)
{
    cd_scenario *sc = arm(CD_STEP_RK8PD);
    cd_error e;
    cd_data *d = cd_data_create(sc->model, 0, &e);
    char want[200];
    snprintf(want, sizeof want, "d->xfrc_applied[9] (body 1 '%s') is NaN", sc->model->body_name[1]);
    d->xfrc_applied[9] = NAN;
    cr_expect_eq(cd_sim_advance(sc->model, d, 0.01, NULL, NULL, &e), CD_ENUMERIC, "%s", e.msg);
    cr_expect(strstr(e.msg, want) != NULL, "'%s' in: %s", want, e.msg);
    cd_data_free(d);
    cd_scenario_free(sc);
}

Test(messages, an_unnamed_link_is_named_by_its_place)
{
    /* A link added without a name: a bad joint property and a bad link
     * description are reported with "body N (unnamed)" and "the unnamed
     * link N of system 'arm'", never "''". */
    cd_model *m = cd_model_create();
    cd_error e;
    cd_system_desc s = cd_system_desc_default();
    cd_link_desc l = cd_link_desc_default();
    cd_joint_props p = cd_joint_props_default();
    int sys, b;
    s.name = "arm";
    s.type = CD_BASE_FIXED;
    sys = cd_model_add_system(m, &s, &e);
    cr_assert_geq(sys, 0, "%s", e.msg);
    l.parent = m->sys_body_adr[sys];
    l.type = CD_JOINT_REVOLUTE;
    l.axis[2] = 1.0;
    l.mass = 1.0;
    l.inertia[0] = l.inertia[4] = l.inertia[8] = 0.1;
    l.name = NULL;
    b = cd_model_add_link(m, sys, &l, &e);
    cr_assert_geq(b, 0, "%s", e.msg);
    p.damping = -1.0;
    cr_expect_eq(cd_model_set_joint(m, b, &p, &e), CD_EINVAL);
    cr_expect(strstr(e.msg, "body 1 (unnamed)") != NULL && strstr(e.msg, "''") == NULL, "%s", e.msg);
    l.name = "";
    l.mass = NAN;
    cr_expect_lt(cd_model_add_link(m, sys, &l, &e), 0);
    cr_expect(strstr(e.msg, "the unnamed link 2 of system 'arm'") != NULL && strstr(e.msg, "''") == NULL, "%s", e.msg);
    cd_model_free(m);
}
