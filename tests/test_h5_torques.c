/* Results record the applied joint torques and the generalized inputs as
 * series (issue 7): /systems/<s>/tau, tau_actuator, tau_passive, tau_applied.
 * Checked on the paper's Fig. 3 mechanism, whose rear spring is a passive
 * joint spring (K_a = 2500 N/m, c = 0.5 N s/m): at every sample the recorded
 * passive force is -K_a q - c qdot of the recorded state, the actuators give
 * nothing, and the total is the sum. */
#include <criterion/criterion.h>
#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "h5_test_util.h"

Test(h5_torques, joint_torque_series_match_the_spring_law_of_the_recorded_state)
{
    const char *bin = getenv("CAPDYN_BIN"), *root = getenv("CAPDYN_ROOT");
    char dir[] = "/tmp/capdyn_tau_XXXXXX", cmd[2048], h5[512];
    size_t n, n2, i;
    double *q, *qd, *tau, *ta, *tp, *tap, worst = 0, scale = 0;
    hid_t f;
    cr_assert(bin && root, "CAPDYN_BIN and CAPDYN_ROOT");
    cr_assert(mkdtemp(dir));
    snprintf(h5, sizeof h5, "%s/fig3.h5", dir);
    snprintf(cmd, sizeof cmd, "'%s' run '%s/scenarios/paper_fig3_impact.toml' -o '%s' -q --set simulation.duration=0.3",
             bin, root, h5);
    cr_assert_eq(system(cmd), 0, "%s", cmd);
    f = H5Fopen(h5, H5F_ACC_RDONLY, H5P_DEFAULT);
    cr_assert(f >= 0);
    q = read_all(f, "/systems/carrier/q", &n);
    qd = read_all(f, "/systems/carrier/qd", &n2);
    tau = read_all(f, "/systems/carrier/tau", &n2);
    ta = read_all(f, "/systems/carrier/tau_actuator", &n2);
    tp = read_all(f, "/systems/carrier/tau_passive", &n2);
    tap = read_all(f, "/systems/carrier/tau_applied", &n2);
    cr_assert(q && qd && tau && ta && tp && tap && n2 == n && n > 100, "series (%zu samples)", n);
    for (i = 0; i < n; i++) {
        double want = -2500.0 * q[i] - 0.5 * qd[i];
        if (fabs(tp[i] - want) > worst) worst = fabs(tp[i] - want);
        if (fabs(want) > scale) scale = fabs(want);
        cr_expect_eq(ta[i], 0.0);
        cr_expect_eq(tap[i], 0.0);
        cr_expect_eq(tau[i], ta[i] + tp[i] + tap[i]);
    }
    cr_log_info("tau_passive vs -K q - c qd: worst %.3e N of %.3e N", worst, scale);
    cr_expect_gt(scale, 1.0, "the spring is loaded during the impact (%.3g N)", scale);
    cr_expect_leq(worst, 1e-12 * scale, "worst %.3e", worst);
    free(q); free(qd); free(tau); free(ta); free(tp); free(tap);
    H5Fclose(f);
    unlink(h5);
    rmdir(dir);
}

Test(h5_torques, actuator_series_and_the_transmission_they_drive)
{
    /* tests/data/scenarios/joints_transmission.toml: actuator 0 drives
     * finger/l1 (ratio 1), actuator 1 ("tendon") drives l1 and l2 with ratios
     * 2 and 1. The recorded joint torques of the actuators are the recorded
     * actuator torques through the ratios, at every sample (1e-12); no
     * control input was given (ctrl = 0). */
    const char *bin = getenv("CAPDYN_BIN"), *root = getenv("CAPDYN_ROOT");
    char dir[] = "/tmp/capdyn_act_XXXXXX", cmd[2048], h5[512];
    size_t n, n2, i;
    double *ctrl, *force, *ta, worst = 0;
    hid_t f;
    cr_assert(bin && root);
    cr_assert(mkdtemp(dir));
    snprintf(h5, sizeof h5, "%s/jt.h5", dir);
    snprintf(cmd, sizeof cmd, "'%s' run '%s/tests/data/scenarios/joints_transmission.toml' -o '%s' -q", bin, root, h5);
    cr_assert_eq(system(cmd), 0, "%s", cmd);
    f = H5Fopen(h5, H5F_ACC_RDONLY, H5P_DEFAULT);
    cr_assert(f >= 0);
    {
        hid_t g = H5Gopen2(f, "/actuators", H5P_DEFAULT);
        cr_assert(g >= 0, "/actuators");
        cr_expect_eq(attr_ll(g, "nactuator"), 2);
        H5Gclose(g);
    }
    ctrl = read_all(f, "/actuators/ctrl", &n);
    force = read_all(f, "/actuators/force", &n2);
    cr_assert(ctrl && force && n == n2 && n % 2 == 0, "actuator series");
    ta = read_all(f, "/systems/finger/tau_actuator", &n2);
    cr_assert(ta && n2 == (n / 2) * 4, "tau_actuator (%zu values)", n2);
    for (i = 0; i < n / 2; i++) {
        double l1 = force[2 * i] + 2.0 * force[2 * i + 1], l2 = force[2 * i + 1];
        if (fabs(ta[4 * i] - l1) > worst) worst = fabs(ta[4 * i] - l1);
        if (fabs(ta[4 * i + 1] - l2) > worst) worst = fabs(ta[4 * i + 1] - l2);
        cr_expect_eq(ctrl[2 * i], 0.0);
    }
    cr_expect_leq(worst, 1e-12, "transmission of the recorded actuator torques: worst %.3e", worst);
    free(ctrl); free(force); free(ta);
    H5Fclose(f);
    unlink(h5);
    rmdir(dir);
}

Test(h5_torques, the_capture_verdict_is_in_the_results_file)
{
    /* capdyn run of the handrail scenario writes its verdict as the root
     * attributes capture_*: captured, with the bar's panel held by >= 2
     * contacts and a positive grasp quality (force closure). */
    const char *bin = getenv("CAPDYN_BIN"), *root = getenv("CAPDYN_ROOT");
    char dir[] = "/tmp/capdyn_cap_XXXXXX", cmd[2048], h5[512], verdict[16];
    hid_t f;
    double t = NAN, eps = NAN;
    cr_assert(bin && root);
    cr_assert(mkdtemp(dir));
    snprintf(h5, sizeof h5, "%s/hr.h5", dir);
    snprintf(cmd, sizeof cmd, "'%s' run '%s/scenarios/space_gripper_handrail.toml' -o '%s' -q --set simulation.duration=1.0",
             bin, root, h5);
    cr_assert_eq(system(cmd), 0, "%s", cmd);
    f = H5Fopen(h5, H5F_ACC_RDONLY, H5P_DEFAULT);
    cr_assert(f >= 0);
    attr_s(f, "capture_verdict", verdict, sizeof verdict);
    t = attr_d(f, "capture_t");
    eps = attr_d(f, "capture_epsilon");
    cr_expect_str_eq(verdict, "captured");
    cr_expect(t > 0 && t < 1.0, "captured at %g s", t);
    cr_expect_geq(attr_ll(f, "capture_n_stick") + attr_ll(f, "capture_n_slip"), 2);
    cr_expect_gt(eps, 0.0, "force closure: epsilon %g", eps);
    H5Fclose(f);
    unlink(h5);
    rmdir(dir);
}
