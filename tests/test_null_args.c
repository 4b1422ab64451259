/* Every public function handles a NULL pointer argument the one documented
 * way (docs/embedding.md, "NULL arguments"; issue 24): a function returning
 * cd_status returns CD_EINVAL with err naming the function (err itself may
 * always be NULL), a constructor returns NULL, a function returning an id or
 * index -1, a double NaN, a size 0, a pointer NULL; a void function does
 * nothing; *_free(NULL) is a no-op. Each call runs in a child process, so
 * that a crash is reported with the call that crashed. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <capdyn/io.h>
#include <capdyn/control.h>
#include <capdyn/verdict.h>
#include <capdyn/analysis.h>
#include <math.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>
#include "proc_util.h"

static cd_scenario *g_sc;
static cd_data *g_d;
static int g_bad;

/* err filled with CD_EINVAL and a message naming fn */
static int einval(cd_status st, const cd_error *e, const char *fn)
{
    return st == CD_EINVAL && e->status == CD_EINVAL && strstr(e->msg, fn) != NULL;
}

#define CHECK(desc, expr)                                                        \
    do {                                                                         \
        pid_t pid_;                                                              \
        int ws_;                                                                 \
        fflush(NULL);                                                            \
        pid_ = fork();                                                           \
        cr_assert(pid_ >= 0);                                                    \
        if (pid_ == 0) {                                                         \
            cd_error e;                                                          \
            memset(&e, 0, sizeof e);                                             \
            (void)e;                                                             \
            _exit((expr) ? 0 : 1);                                               \
        }                                                                        \
        cr_assert_eq(waitpid(pid_, &ws_, 0), pid_);                              \
        if (WIFSIGNALED(ws_)) {                                                  \
            g_bad++;                                                             \
            cr_log_error("%s: crashed (signal %d)", desc, WTERMSIG(ws_));        \
        } else if (WEXITSTATUS(ws_) != 0) {                                      \
            g_bad++;                                                             \
            cr_log_error("%s: not the documented result", desc);                 \
        }                                                                        \
    } while (0)

Test(null_args, every_public_function_refuses_null_the_documented_way, .timeout = 120)
{
    char p[512];
    cd_error e0;
    const cd_model *m;
    cd_data *d;
    double v3[3] = {0, 0, 0}, buf[64];
    scen(p, sizeof p, "free_floating_arm.toml");
    g_sc = cd_scenario_load(p, NULL, 0, &e0);
    cr_assert_not_null(g_sc, "%s", e0.msg);
    m = g_sc->model;
    g_d = d = cd_data_create(m, 0, &e0);
    cr_assert_not_null(d, "%s", e0.msg);
    (void)buf;

    /* model.h */
    CHECK("cd_error_set(NULL, ...)", (cd_error_set(NULL, CD_EINVAL, "x"), 1));
    CHECK("cd_shape_type_from_name(NULL)", cd_shape_type_from_name(NULL) == -1);
    CHECK("cd_stepper_from_name(NULL)", cd_stepper_from_name(NULL) == -1);
    CHECK("cd_options_check(NULL)", einval(cd_options_check(NULL, &e), &e, "cd_options_check"));
    CHECK("cd_model_free(NULL)", (cd_model_free(NULL), 1));
    CHECK("cd_model_add_system(NULL)", cd_model_add_system(NULL, NULL, &e) == -1 && e.status == CD_EINVAL);
    CHECK("cd_model_add_system(m, NULL)", cd_model_add_system(cd_model_create(), NULL, &e) == -1 && e.status == CD_EINVAL);
    CHECK("cd_model_add_link(NULL)", cd_model_add_link(NULL, 0, NULL, &e) == -1 && e.status == CD_EINVAL);
    CHECK("cd_model_add_checkpoint(NULL)", cd_model_add_checkpoint(NULL, 0, v3, 0.01, &e) == -1 && e.status == CD_EINVAL);
    CHECK("cd_model_add_shape(NULL)", cd_model_add_shape(NULL, 0, CD_SHAPE_SPHERE, v3, NULL, v3, NULL, 0, &e) == -1 &&
                                          e.status == CD_EINVAL);
    CHECK("cd_model_add_law(NULL)", cd_model_add_law(NULL, NULL, &e) == -1 && e.status == CD_EINVAL);
    CHECK("cd_model_add_pair(NULL)", cd_model_add_pair(NULL, 0, 0, 0, 0, &e) == -1 && e.status == CD_EINVAL);
    CHECK("cd_model_set_actuator(NULL)", einval(cd_model_set_actuator(NULL, 0, NULL, &e), &e, "cd_model_set_actuator"));
    CHECK("cd_model_add_actuator(NULL)", cd_model_add_actuator(NULL, NULL, &e) == -1 && e.status == CD_EINVAL);
    CHECK("cd_model_set_joint(NULL)", einval(cd_model_set_joint(NULL, 0, NULL, &e), &e, "cd_model_set_joint"));
    CHECK("cd_model_prescribe_base(NULL)", einval(cd_model_prescribe_base(NULL, 0, v3, v3, &e), &e, "cd_model_prescribe_base"));
    CHECK("cd_model_add_finger(NULL)", cd_model_add_finger(NULL, NULL, &e) == -1 && e.status == CD_EINVAL);
    CHECK("cd_model_set_user_switches(NULL)", einval(cd_model_set_user_switches(NULL, 1, &e), &e, "cd_model_set_user_switches"));
    CHECK("cd_model_actuator_id(NULL)", cd_model_actuator_id(NULL, "x") == -1 && cd_model_actuator_id(m, NULL) == -1);
    CHECK("cd_model_body_id(NULL)", cd_model_body_id(NULL, "x") == -1 && cd_model_body_id(m, NULL) == -1);
    CHECK("cd_model_system_id(NULL)", cd_model_system_id(NULL, "x") == -1 && cd_model_system_id(m, NULL) == -1);
    CHECK("cd_model_finalize(NULL)", einval(cd_model_finalize(NULL, &e), &e, "cd_model_finalize"));
    CHECK("cd_model_finalize(NULL, NULL)", cd_model_finalize(NULL, NULL) == CD_EINVAL);

    /* data.h */
    CHECK("cd_data_create(NULL)", cd_data_create(NULL, 0, &e) == NULL && e.status == CD_EINVAL);
    CHECK("cd_data_create_ex(NULL)", cd_data_create_ex(NULL, 0, NULL, &e) == NULL && e.status == CD_EINVAL);
    CHECK("cd_data_free(NULL)", (cd_data_free(NULL), 1));
    CHECK("cd_data_reset(NULL, d)", einval(cd_data_reset(NULL, d, &e), &e, "cd_data_reset"));
    CHECK("cd_data_reset(m, NULL)", einval(cd_data_reset(m, NULL, &e), &e, "cd_data_reset"));
    CHECK("cd_data_set_control(NULL)", (cd_data_set_control(NULL, NULL, NULL), 1));
    CHECK("cd_data_set_user_switches(NULL)", (cd_data_set_user_switches(NULL, NULL, NULL, NULL), 1));
    CHECK("cd_data_event(NULL)", cd_data_event(NULL, 0) == NULL);
    CHECK("cd_state_size(NULL)", cd_state_size(NULL) == 0);
    CHECK("cd_state_get(NULL)", (cd_state_get(NULL, d, buf), cd_state_get(m, NULL, buf), cd_state_get(m, d, NULL), 1));
    CHECK("cd_state_set(NULL, d, buf)", einval(cd_state_set(NULL, d, buf, &e), &e, "cd_state_set"));
    CHECK("cd_state_set(m, NULL, buf)", einval(cd_state_set(m, NULL, buf, &e), &e, "cd_state_set"));
    CHECK("cd_state_set(m, d, NULL)", einval(cd_state_set(m, d, NULL, &e), &e, "cd_state_set"));
    CHECK("cd_state_copy(NULL)", einval(cd_state_copy(NULL, d, d, &e), &e, "cd_state_copy") &&
                                     einval(cd_state_copy(m, NULL, d, &e), &e, "cd_state_copy") &&
                                     einval(cd_state_copy(m, d, NULL, &e), &e, "cd_state_copy"));
    CHECK("cd_state_of(NULL)", cd_state_of(NULL, d, 0).q == NULL && cd_state_of(m, NULL, 0).q == NULL);
    CHECK("cd_joint_q(NULL)", isnan(cd_joint_q(NULL, d, 1)) && isnan(cd_joint_q(m, NULL, 1)));
    CHECK("cd_joint_qd(NULL)", isnan(cd_joint_qd(NULL, d, 1)) && isnan(cd_joint_qd(m, NULL, 1)));

    /* sim.h */
    CHECK("cd_kinematics(NULL)", (cd_kinematics(NULL, d), cd_kinematics(m, NULL), 1));
    CHECK("cd_point_world(NULL)", (cd_point_world(NULL, d, 0, v3, v3, v3), cd_point_world(m, NULL, 0, v3, v3, v3), 1));
    CHECK("cd_inverse_dynamics(NULL)", (cd_inverse_dynamics(NULL, d, 0, NULL, NULL), cd_inverse_dynamics(m, NULL, 0, buf, buf), 1));
    CHECK("cd_mass_matrix(NULL)", (cd_mass_matrix(NULL, d, 0, buf), cd_mass_matrix(m, NULL, 0, buf), cd_mass_matrix(m, d, 0, NULL), 1));
    CHECK("cd_forward_dynamics(NULL)", cd_forward_dynamics(NULL, d) == CD_EINVAL && cd_forward_dynamics(m, NULL) == CD_EINVAL);
    CHECK("cd_point_jacobian(NULL)", (cd_point_jacobian(NULL, d, 0, v3, buf), cd_point_jacobian(m, d, 0, v3, NULL), 1));
    CHECK("cd_generalized_jacobian(NULL)", einval(cd_generalized_jacobian(NULL, d, 1, v3, buf, &e), &e, "cd_generalized_jacobian") &&
                                               einval(cd_generalized_jacobian(m, NULL, 1, v3, buf, &e), &e, "cd_generalized_jacobian") &&
                                               einval(cd_generalized_jacobian(m, d, 1, v3, NULL, &e), &e, "cd_generalized_jacobian"));
    CHECK("cd_momentum(NULL)", (cd_momentum(NULL, d, 0, NULL, NULL, NULL, NULL, NULL), cd_momentum(m, NULL, 0, buf, v3, v3, v3, v3), 1));
    CHECK("cd_potential_energy(NULL)", isnan(cd_potential_energy(NULL, d, 0)) && isnan(cd_potential_energy(m, NULL, 0)));
    CHECK("cd_forward(NULL)", cd_forward(NULL, d) == CD_EINVAL && cd_forward(m, NULL) == CD_EINVAL);
    CHECK("cd_shape_distance(NULL)", cd_shape_distance(NULL, 0, v3, 0, buf, v3, v3) == -1);
    CHECK("cd_shape_distance_ccd(NULL)", cd_shape_distance_ccd(NULL, 0, v3, 0, buf, v3, v3) == -1);
    CHECK("cd_sim_advance(NULL, d)", einval(cd_sim_advance(NULL, d, 1, NULL, NULL, &e), &e, "cd_sim_advance"));
    CHECK("cd_sim_advance(m, NULL)", einval(cd_sim_advance(m, NULL, 1, NULL, NULL, &e), &e, "cd_sim_advance"));
    CHECK("cd_step(NULL, d)", einval(cd_step(NULL, d, 1e-3, &e), &e, "cd_step"));
    CHECK("cd_step(m, NULL)", einval(cd_step(m, NULL, 1e-3, &e), &e, "cd_step"));
    CHECK("cd_step(m, NULL, err NULL)", cd_step(m, NULL, 1e-3, NULL) == CD_EINVAL);
    CHECK("cd_sampler_create(NULL)", cd_sampler_create(NULL, &e) == NULL && e.status == CD_EINVAL);
    CHECK("cd_sampler_free(NULL)", (cd_sampler_free(NULL), 1));
    CHECK("cd_sampler_begin(NULL)", einval(cd_sampler_begin(NULL, m, d, 0, 0.1, &e), &e, "cd_sampler_begin"));
    CHECK("cd_sampler_update(NULL)", cd_sampler_update(NULL, m, d, NULL, NULL) == -1);
    CHECK("cd_sampler_next(NULL)", isnan(cd_sampler_next(NULL)));

    /* control.h, verdict.h, analysis.h, io.h */
    CHECK("cd_ctrl_create(NULL)", cd_ctrl_create(NULL, NULL, &e) == NULL && e.status == CD_EINVAL);
    CHECK("cd_ctrl_free(NULL)", (cd_ctrl_free(NULL), 1));
    CHECK("cd_ctrl_install(NULL)", (cd_ctrl_install(NULL, d), 1));
    CHECK("cd_ctrl_t_trigger(NULL)", isnan(cd_ctrl_t_trigger(NULL)) && isnan(cd_ctrl_t_hold(NULL)) &&
                                         isnan(cd_ctrl_t_detumble(NULL)));
    CHECK("cd_ctrl_state_size(NULL)", cd_ctrl_state_size(NULL) == 0);
    CHECK("cd_ctrl_state_get(NULL)", (cd_ctrl_state_get(NULL, buf), 1));
    CHECK("cd_ctrl_state_set(NULL)", einval(cd_ctrl_state_set(NULL, buf, &e), &e, "cd_ctrl_state_set"));
    CHECK("cd_ctrl_base_angle(NULL)", isnan(cd_ctrl_base_angle(NULL, m, d)));
    CHECK("cd_monitor_init(NULL)", einval(cd_monitor_init(NULL, m, d, NULL, &e), &e, "cd_monitor_init"));
    CHECK("cd_monitor_update(NULL)", (cd_monitor_update(NULL, m, d), 1));
    CHECK("cd_monitor_quality(NULL)", einval(cd_monitor_quality(NULL, m, d, buf, NULL, &e), &e, "cd_monitor_quality"));
    CHECK("cd_grasp_quality_eval(NULL)", einval(cd_grasp_quality_eval(NULL, 1, v3, NULL, NULL, &e), &e, "grasp quality: result pointer q is NULL"));
    CHECK("cd_scenario_load(NULL)", cd_scenario_load(NULL, NULL, 0, &e) == NULL && e.status != CD_OK);
    CHECK("cd_scenario_free(NULL)", (cd_scenario_free(NULL), 1));
    CHECK("cd_h5_create(NULL)", cd_h5_create(NULL, m, NULL, &e) == NULL && e.status == CD_EINVAL);
    CHECK("cd_h5_append(NULL)", einval(cd_h5_append(NULL, m, d, &e), &e, "cd_h5_append"));
    CHECK("cd_h5_flush(NULL)", einval(cd_h5_flush(NULL, &e), &e, "cd_h5_flush"));
    CHECK("cd_h5_set_capture(NULL)", (cd_h5_set_capture(NULL, NULL), 1));
    CHECK("cd_h5_set_step_peaks(NULL)", (cd_h5_set_step_peaks(NULL, 1, NULL), 1));
    CHECK("cd_h5_close(NULL)", cd_h5_close(NULL, m, d, CD_OK, "", &e) == CD_OK);

    cr_expect_eq(g_bad, 0, "%d calls with a NULL argument crashed or did not give the documented result", g_bad);
    cd_data_free(d);
    cd_scenario_free(g_sc);
}
