/* Every shipped scenario with its own settings, through the library
 * (`make bench`, docs/performance.md "Every scenario").
 *
 * For each scenario file: load it (not timed), create its data, install its
 * [control] controller if it has one, and run it to its duration as `capdyn
 * run` does (dense output: one cd_sim_advance over the whole run; stopping at
 * samples: one call per output_dt; a step callback as the CLI's, which
 * changes nothing), without writing results. Printed per scenario: stepper,
 * duration, wall time (median and min over the repetitions), CPU time, the
 * real-time factor RTF = duration / median wall time (and duration / median
 * CPU time: on a shared machine the CPU time is what the run cost), accepted
 * steps, right-hand-side evaluations, Jacobians (stats.njac),
 * events, and the run's status.
 *
 * --ab-broad-phase: for each scenario, the run with opt.broad_phase = 1 and
 * = 0, interleaved (the order alternates with the repetition); prints the
 * median wall and CPU times of both and the speed-up x = time without /
 * time with (min and median over the repetitions, wall and CPU), and checks
 * that both runs took the same steps, evaluations and events and ended in
 * the bit-identical state.
 *
 * Usage: bench_scenarios [-r reps] [-o results.txt] [--cap S] [--ab-broad-phase]
 *                        [--set key=value]... scenario.toml...
 * --cap S: no further repetition of a scenario whose first run took more than
 * S seconds of wall time (default 30). Run from the repository root. */
#include <capdyn/capdyn.h>
#include <capdyn/io.h>

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define MAXREP 32
#define MAXSET 16

#include "bench_util.h"



static double median(const double *v, int n)
{
    double s[MAXREP];
    memcpy(s, v, (size_t)n * sizeof *s);
    qsort(s, (size_t)n, sizeof *s, cmp_double);
    return n % 2 ? s[n / 2] : 0.5 * (s[n / 2 - 1] + s[n / 2]);
}

static double minimum(const double *v, int n)
{
    double x = v[0];
    int i;
    for (i = 1; i < n; i++)
        if (v[i] < x) x = v[i];
    return x;
}

typedef struct {
    double wall, cpu;
    cd_stats stats;
    cd_status st;
    double *y;     /* final state (malloc'd, ny) */
    int ny;
    char msg[160];
} run_result;

static int no_op(const cd_model *m, cd_data *d, void *user)
{
    (void)m; (void)d; (void)user;
    return 0;
}

/* One run of sc to its duration; broad_phase -1 leaves the option as loaded. */
static void run_once(const cd_scenario *sc, int broad_phase, run_result *r)
{
    const cd_model *m = sc->model;
    cd_error err;
    cd_ctrl *ctl = NULL;
    cd_data *d;
    double w0, c0;
    memset(r, 0, sizeof *r);
    err.msg[0] = 0;
    d = cd_data_create(m, sc->event_capacity, &err);
    if (!d) { r->st = err.status; snprintf(r->msg, sizeof r->msg, "%s", err.msg); return; }
    if (sc->control) {
        ctl = cd_ctrl_create(m, sc->control, &err);
        if (!ctl) { r->st = err.status; snprintf(r->msg, sizeof r->msg, "%s", err.msg); cd_data_free(d); return; }
        cd_ctrl_install(ctl, d);
    }
    if (broad_phase >= 0) d->opt.broad_phase = broad_phase;
    w0 = clock_s(CLOCK_MONOTONIC);
    c0 = clock_s(CLOCK_PROCESS_CPUTIME_ID);
    if (sc->interpolate) {
        r->st = cd_sim_advance(m, d, sc->duration, no_op, NULL, &err);
    } else {
        long i, nout = (long)ceil(sc->duration / sc->output_dt - 1e-9);
        r->st = CD_OK;
        for (i = 1; r->st == CD_OK && i <= nout; i++) {
            double tn = i == nout ? sc->duration : (double)i * sc->output_dt;
            if (tn > sc->duration) tn = sc->duration;
            r->st = cd_sim_advance(m, d, tn, no_op, NULL, &err);
        }
    }
    r->wall = clock_s(CLOCK_MONOTONIC) - w0;
    r->cpu = clock_s(CLOCK_PROCESS_CPUTIME_ID) - c0;
    if (r->st != CD_OK) snprintf(r->msg, sizeof r->msg, "%s", err.msg);
    r->stats = d->stats;
    r->ny = m->ny;
    r->y = (double *)malloc((size_t)m->ny * sizeof(double));
    if (r->y) memcpy(r->y, d->y, (size_t)m->ny * sizeof(double));
    cd_ctrl_free(ctl);
    cd_data_free(d);
}

static const char *base_name(const char *p)
{
    const char *s = strrchr(p, '/');
    return s ? s + 1 : p;
}

static int same_run(const run_result *a, const run_result *b)
{
    return a->st == b->st && a->stats.nsteps == b->stats.nsteps && a->stats.nrhs == b->stats.nrhs &&
           a->stats.nevents == b->stats.nevents && a->stats.nrejected == b->stats.nrejected && a->y && b->y &&
           memcmp(a->y, b->y, (size_t)a->ny * sizeof(double)) == 0;
}

int main(int argc, char **argv)
{
    const char *files[256], *sets[MAXSET], *out = NULL;
    int nfiles = 0, nset = 0, reps = 1, ab = 0, i, f;
    double cap = 30.0;
    time_t now = time(NULL);
    char stamp[64];
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "-r") && i + 1 < argc) reps = atoi(argv[++i]);
        else if (!strcmp(argv[i], "-o") && i + 1 < argc) out = argv[++i];
        else if (!strcmp(argv[i], "--cap") && i + 1 < argc) cap = atof(argv[++i]);
        else if (!strcmp(argv[i], "--set") && i + 1 < argc && nset < MAXSET) sets[nset++] = argv[++i];
        else if (!strcmp(argv[i], "--ab-broad-phase")) ab = 1;
        else if (argv[i][0] == '-') {
            fprintf(stderr, "usage: %s [-r reps] [-o file] [--cap S] [--ab-broad-phase] [--set key=value]... scenario.toml...\n",
                    argv[0]);
            return 2;
        } else if (nfiles < 256) files[nfiles++] = argv[i];
    }
    if (reps < 1 || reps > MAXREP || nfiles == 0) {
        fprintf(stderr, "%s: need 1 <= reps <= %d and at least one scenario\n", argv[0], MAXREP);
        return 2;
    }
    if (out && !(out_file = fopen(out, "w"))) { fprintf(stderr, "%s: cannot open %s\n", argv[0], out); return 1; }
    strftime(stamp, sizeof stamp, "%Y-%m-%d %H:%M:%S UTC", gmtime(&now));
    say("\n== %s: %s, %d repetition(s)%s, capdyn %s, %s", base_name(argv[0]),
        ab ? "broad phase on vs off (interleaved)" : "every scenario with its own settings", reps,
        ab ? "" : " (fewer for runs longer than the cap)", cd_version(), stamp);
    for (i = 0; i < nset; i++) say("%s--set %s", i ? " " : "\n   overrides: ", sets[i]);
    say("\n   (library runs, no results written; wall = median [min] over the repetitions; RTF = duration / median wall,"
        " RTF cpu = duration / median CPU time)\n");
    if (!ab)
        say("%-34s %-9s %7s %9s %9s %8s %8s %8s %9s %9s %7s %7s %s\n", "scenario", "stepper", "dur [s]", "wall [s]",
            "min [s]", "cpu [s]", "RTF", "RTF cpu", "steps", "rhs", "jac", "events", "status");
    else
        say("%-30s %-9s %8s %8s %7s %7s %8s %8s %7s %7s %9s %7s %s\n", "scenario", "stepper", "wall on", "wall off",
            "x min", "x med", "cpu on", "cpu off", "x min", "x med", "rhs", "events", "identical");
    for (f = 0; f < nfiles; f++) {
        cd_error err;
        cd_scenario *sc = cd_scenario_load(files[f], sets, nset, &err);
        double wall[MAXREP], cpu[MAXREP], woff[MAXREP], coff[MAXREP], ratio[MAXREP], cratio[MAXREP];
        run_result r, r0, first;
        int n = 0, ident = 1;
        if (!sc) { say("%-34s load failed: %s\n", base_name(files[f]), err.msg); continue; }
        memset(&first, 0, sizeof first);
        for (i = 0; i < reps; i++) {
            if (!ab) {
                run_once(sc, -1, &r);
                wall[n] = r.wall; cpu[n] = r.cpu; n++;
                if (i == 0) first = r; else free(r.y);
                if (r.st != CD_OK || r.wall > cap) break;
            } else {
                if (i % 2 == 0) { run_once(sc, 1, &r); run_once(sc, 0, &r0); }
                else { run_once(sc, 0, &r0); run_once(sc, 1, &r); }
                wall[n] = r.wall; woff[n] = r0.wall; ratio[n] = r0.wall / r.wall;
                cpu[n] = r.cpu; coff[n] = r0.cpu; cratio[n] = r0.cpu / r.cpu; n++;
                if (!same_run(&r, &r0)) ident = 0;
                free(r0.y);
                if (i == 0) first = r; else free(r.y);
                if (r.st != CD_OK || r.wall + r0.wall > cap) break;
            }
        }
        if (!ab)
            say("%-34s %-9s %7.3g %9.3f %9.3f %8.3f %8.3g %8.3g %9ld %9ld %7ld %7ld %s%s%s\n", base_name(files[f]),
                cd_stepper_name(sc->model->opt.stepper), sc->duration, median(wall, n), minimum(wall, n), median(cpu, n),
                sc->duration / median(wall, n), sc->duration / median(cpu, n), first.stats.nsteps, first.stats.nrhs, first.stats.njac,
                first.stats.nevents, cd_status_string(first.st), first.st == CD_OK ? "" : ": ", first.msg);
        else
            say("%-30s %-9s %8.3f %8.3f %7.2f %7.2f %8.3f %8.3f %7.2f %7.2f %9ld %7ld %s\n", base_name(files[f]),
                cd_stepper_name(sc->model->opt.stepper), median(wall, n), median(woff, n), minimum(ratio, n),
                median(ratio, n), median(cpu, n), median(coff, n), minimum(cratio, n), median(cratio, n),
                first.stats.nrhs, first.stats.nevents, ident ? "yes" : "NO");
        free(first.y);
        cd_scenario_free(sc);
    }
    if (out_file) fclose(out_file);
    return 0;
}
