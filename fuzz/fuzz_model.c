/* libFuzzer target: load (fuzz/fuzz_common.h), then create the data and
 * run a short simulation: at most 0.01 s of simulated time and 2000 steps,
 * on models of at most 600 states (larger ones are only built). Findings:
 * any crash, sanitizer report (NaN is not one: the integrator reports it as
 * a status), stack overflow at 256 KiB, leak, or an error status without a
 * message. */
#include "fuzz_common.h"
#include "capdyn/sim.h"

#include <gsl/gsl_errno.h>
#include <math.h>

static void build_and_run(const char *path, const char *const *sets, int nsets)
{
    cd_error err;
    cd_scenario *sc = cd_scenario_load(path, sets, nsets, &err);
    cd_data *d;
    cd_status st;
    double t_end;
    if (!sc) {
        fuzz_check_error(&err);
        return;
    }
    if (sc->model->ny > 600) {
        cd_scenario_free(sc);
        return;
    }
    /* a short run: the model is ours until freed, its step budget is lowered */
    sc->model->opt.max_steps = 2000;
    d = cd_data_create(sc->model, sc->event_capacity < 64 ? sc->event_capacity : 64, &err);
    if (!d) {
        fuzz_check_error(&err);
        cd_scenario_free(sc);
        return;
    }
    t_end = sc->duration < 0.01 ? sc->duration : 0.01;
    st = cd_sim_advance(sc->model, d, t_end, NULL, NULL, &err);
    if (st != CD_OK && err.msg[0] == 0) {
        fprintf(stderr, "run failed with status %d and no message\n", (int)st);
        abort();
    }
    if (st == CD_OK && !(fabs(d->t - t_end) <= 1e-9 * (1 + t_end))) {
        fprintf(stderr, "run ended at t = %.17g instead of %.17g\n", d->t, t_end);
        abort();
    }
    cd_data_free(d);
    cd_scenario_free(sc);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static int init = 0;
    if (!init) {
        gsl_set_error_handler_off(); /* as the CLI does: GSL's default aborts */
        init = 1;
    }
    fuzz_run(data, size, build_and_run);
    return 0;
}
