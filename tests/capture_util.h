/* The capture tests' common start (test_capture.c, test_capture_scenarios.c):
 * a scenario with a [control] table loaded, its data, its controller
 * installed and the capture monitor started, as `capdyn run` does; every
 * failure is a Criterion assertion. */
#ifndef CD_TEST_CAPTURE_UTIL_H
#define CD_TEST_CAPTURE_UTIL_H
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <capdyn/io.h>

static inline void capture_open(const char *path, const char *const *ov, int nov, cd_scenario **sc, cd_data **d,
                                cd_ctrl **c, cd_monitor *mon)
{
    cd_error err;
    cd_monitor_opts mo;
    *sc = cd_scenario_load(path, ov, nov, &err);
    cr_assert_not_null(*sc, "%s", err.msg);
    cr_assert_not_null((*sc)->control, "%s has a [control] table", path);
    *d = cd_data_create((*sc)->model, 0, &err);
    cr_assert_not_null(*d, "%s", err.msg);
    *c = cd_ctrl_create((*sc)->model, (*sc)->control, &err);
    cr_assert_not_null(*c, "%s", err.msg);
    cd_ctrl_install(*c, *d);
    mo = cd_scenario_monitor_opts(*sc);
    cr_assert_eq(cd_monitor_init(mon, (*sc)->model, *d, &mo, &err), CD_OK, "%s", err.msg);
}
#endif
