/* The verdict tests' common run (test_verdict.c, test_verdict_cage.c): a
 * scenario loaded, its data and the capture monitor started, then advanced
 * sample by sample (output_dt) with the monitor updated at every sample, as
 * `capdyn run` does; every failure is a Criterion assertion. */
#ifndef CD_TEST_VERDICT_UTIL_H
#define CD_TEST_VERDICT_UTIL_H
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <capdyn/io.h>
#include <string.h>

typedef struct {
    cd_scenario *sc;
    cd_data *d;
    cd_monitor mon;
} vrun;

static inline void vrun_open(vrun *r, const char *path, const char *const *ov, int nov)
{
    cd_error err;
    cd_monitor_opts mo;
    memset(r, 0, sizeof *r);
    r->sc = cd_scenario_load(path, ov, nov, &err);
    cr_assert_not_null(r->sc, "%s", err.msg);
    r->d = cd_data_create(r->sc->model, 0, &err);
    cr_assert_not_null(r->d, "%s", err.msg);
    mo = cd_scenario_monitor_opts(r->sc);
    cr_assert_eq(cd_monitor_init(&r->mon, r->sc->model, r->d, &mo, &err), CD_OK, "%s", err.msg);
    cd_monitor_update(&r->mon, r->sc->model, r->d);
}

/* to t_end, one sample at a time; after each sample's monitor update,
 * at_sample(user) if given */
static inline void vrun_until(vrun *r, double t_end, void (*at_sample)(void *), void *user)
{
    cd_error err;
    double dt = r->sc->output_dt;
    while (r->d->t < t_end - 1e-12) {
        double tn = r->d->t + dt > t_end ? t_end : r->d->t + dt;
        cr_assert_eq(cd_sim_advance(r->sc->model, r->d, tn, NULL, NULL, &err), CD_OK, "%s", err.msg);
        cd_monitor_update(&r->mon, r->sc->model, r->d);
        if (at_sample) at_sample(user);
    }
}

static inline void vrun_to(vrun *r, double t_end) { vrun_until(r, t_end, NULL, NULL); }

static inline void vrun_close(vrun *r)
{
    cd_data_free(r->d);
    cd_scenario_free(r->sc);
}
#endif
