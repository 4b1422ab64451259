/* The cost of driving a scenario in ticks: cd_sim_advance to every multiple
 * of DT up to T, as an FMU's doStep or a flight loop does, and the run's
 * statistics at the end (steps, right-hand-side evaluations, rejected
 * steps, events, auto's switches and its time on the stiff stepper).
 * Compare DT = T (one call) with short ticks, and auto with msbdf
 * (docs/dynamics.md, "auto": short advance calls; docs/performance.md
 * section 22).
 *
 * Usage: advance_ticks SCENARIO.toml DT T [--set KEY=VALUE]...
 * (run from the repository root; built by `make build/advance_ticks`), e.g.
 *   build/advance_ticks scenarios/paper_fig5_envelope_grasp.toml 0.01 12 \
 *       --set simulation.duration=12.0 --set 'simulation.integrator="msbdf"' */
#include <capdyn/capdyn.h>
#include <capdyn/io.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_SETS 16

int main(int argc, char **argv)
{
    const char *sets[MAX_SETS];
    int nset = 0, i;
    double dt, T;
    long k, nt;
    cd_error e;
    cd_scenario *sc;
    cd_data *d;
    if (argc < 4) {
        fprintf(stderr, "usage: %s SCENARIO.toml DT T [--set KEY=VALUE]...\n", argv[0]);
        return 2;
    }
    dt = atof(argv[2]);
    T = atof(argv[3]);
    if (!(dt > 0) || !(T >= dt) || !isfinite(T) || T / dt > 1e8) {
        fprintf(stderr, "%s: DT must be > 0 and T >= DT, at most 1e8 ticks (got DT %s, T %s)\n", argv[0], argv[2],
                argv[3]);
        return 2;
    }
    for (i = 4; i < argc; i++) {
        if (strcmp(argv[i], "--set") == 0 && i + 1 < argc && nset < MAX_SETS) sets[nset++] = argv[++i];
        else {
            fprintf(stderr, "%s: unexpected argument '%s' (at most %d --set KEY=VALUE)\n", argv[0], argv[i], MAX_SETS);
            return 2;
        }
    }
    sc = cd_scenario_load(argv[1], sets, nset, &e);
    if (!sc) {
        fprintf(stderr, "%s\n", e.msg);
        return 1;
    }
    d = cd_data_create(sc->model, sc->event_capacity, &e);
    if (!d) {
        fprintf(stderr, "%s\n", e.msg);
        cd_scenario_free(sc);
        return 1;
    }
    nt = (long)floor(T / dt + 0.5);
    for (k = 1; k <= nt; k++)
        if (cd_sim_advance(sc->model, d, k == nt ? T : (double)k * dt, NULL, NULL, &e) != CD_OK) {
            fprintf(stderr, "at t = %g s: %s\n", d->t, e.msg);
            cd_data_free(d);
            cd_scenario_free(sc);
            return 1;
        }
    printf("%s, ticks of %g s to %g s: steps %ld, evaluations %ld, rejected %ld, events %ld, "
           "auto: to the stiff stepper %ld, back %ld, %.3f s on it\n",
           argv[1], dt, T, d->stats.nsteps, d->stats.nrhs, d->stats.nrejected, d->stats.nevents,
           d->stats.nswitch_stiff, d->stats.nswitch_explicit, d->stats.t_stiff);
    cd_data_free(d);
    cd_scenario_free(sc);
    return 0;
}
