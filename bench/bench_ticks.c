/* Tick-time distribution of a fixed-rate control loop, per stepper
 * (`make bench`, docs/performance.md "Control-loop ticks").
 *
 * Two loops, each run once per stepper:
 *   example  the loop of examples/control_loop.c: its plant and controller
 *            (examples/control_loop_model.h, included, not copied), 1 kHz,
 *            5 s: control_tick (the law, written into d->ctrl) then
 *            cd_step(m, d, 1 ms);
 *   capture  an arm with a gripper catching a free object:
 *            scenarios/capture_handrail_tumbling.toml (6-joint arm, 4 two-link
 *            fingers, a tumbling target, 432 contact slots) with its built-in
 *            controller as the control callback, ticked at 100 Hz for its
 *            4.5 s: one cd_sim_advance to the next tick each (cd_step for the
 *            adaptive steppers is the same call; the fixed-step rk4 takes
 *            h_fixed substeps, 1e-4 s here).
 * A tick's time is measured around the tick's whole work (law + step), on
 * the wall clock and as this thread's CPU time (the machine may be shared:
 * the CPU time is what the tick cost, the wall time what a real-time loop
 * would have seen). Printed per loop and stepper: ticks, median, p99 and
 * max of both, ticks over the period (wall), evaluations per tick (median,
 * max), heap allocations per tick (max, total: malloc, calloc and realloc
 * are counted while a tick runs), and the run's status.
 *
 * Usage: bench_ticks [-o results.txt] [--loop example|capture]... [--stepper NAME]...
 *                    [--set KEY=VALUE]... [--ticks FILE]
 * (run from the repository root). --ticks writes one row per tick (time,
 * evaluations, steps, rejections, events, locating work, stiff stepper used)
 * for finding what the long ticks do. --set overrides a key of the capture
 * scenario after the stepper's (e.g. the flight-loop setting of
 * docs/performance.md: --set simulation.rtol=1e-6 --set simulation.atol=1e-9). */
#include <capdyn/capdyn.h>
#include <capdyn/io.h>
#include "../examples/control_loop_model.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* ---- allocation counting (glibc: the interposed functions forward) ---- */
extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
static volatile int counting;
static volatile long nalloc;
void *malloc(size_t n)
{
    if (counting) nalloc++;
    return __libc_malloc(n);
}
void *calloc(size_t a, size_t b)
{
    if (counting) nalloc++;
    return __libc_calloc(a, b);
}
void *realloc(void *p, size_t n)
{
    if (counting) nalloc++;
    return __libc_realloc(p, n);
}

#include "bench_util.h"



/* quantile q of v[0..n-1] (sorted in place): the smallest value with at least q n values at or below it */
static double quantile(double *v, long n, double q)
{
    long i;
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    i = (long)ceil(q * (double)n) - 1;
    if (i < 0) i = 0;
    if (i >= n) i = n - 1;
    return v[i];
}

typedef struct {
    long n;
    double *wall, *cpu, *evals;
    long alloc_max, alloc_total, over;
} ticks;

static int ticks_init(ticks *t, long cap)
{
    memset(t, 0, sizeof *t);
    t->wall = (double *)__libc_malloc((size_t)cap * sizeof(double));
    t->cpu = (double *)__libc_malloc((size_t)cap * sizeof(double));
    t->evals = (double *)__libc_malloc((size_t)cap * sizeof(double));
    return t->wall && t->cpu && t->evals;
}

static void ticks_free(ticks *t)
{
    free(t->wall);
    free(t->cpu);
    free(t->evals);
}

static void report(const char *loop, const char *stepper, double period, ticks *t, const cd_data *d, cd_status st,
                   const char *msg)
{
    double wmed, w99, wmax, cmed, c99, cmax, emed, emax;
    if (t->n == 0) {
        say("%-8s %-9s no tick completed: %s\n", loop, stepper, msg);
        return;
    }
    wmed = quantile(t->wall, t->n, 0.5); w99 = quantile(t->wall, t->n, 0.99); wmax = t->wall[t->n - 1];
    cmed = quantile(t->cpu, t->n, 0.5); c99 = quantile(t->cpu, t->n, 0.99); cmax = t->cpu[t->n - 1];
    emed = quantile(t->evals, t->n, 0.5); emax = t->evals[t->n - 1];
    say("%-8s %-9s %6ld %8.3f %8.3f %8.2f %8.3f %8.3f %8.2f %6ld %6.0f %6.0f %6ld %6ld  %s%s%s (t = %.3g s, %ld events)\n",
        loop, stepper, t->n, 1e3 * wmed, 1e3 * w99, 1e3 * wmax, 1e3 * cmed, 1e3 * c99, 1e3 * cmax, t->over, emed,
        emax, t->alloc_max, t->alloc_total, cd_status_string(st), st == CD_OK ? "" : ": ", msg, d ? d->t : 0.0,
        d ? d->stats.nevents : 0L);
    (void)period;
}

/* one tick's bookkeeping around the work done between w0/c0/a0/s0 and now */
static FILE *tick_file; /* --ticks FILE: one row per tick */
static void tick_done(ticks *t, double period, double w0, double c0, long a0, const cd_data *d,
                      const char *loop, const char *stepper, const cd_stats *s0)
{
    double w = clock_s(CLOCK_MONOTONIC) - w0, c = clock_s(CLOCK_THREAD_CPUTIME_ID) - c0;
    long a = nalloc - a0;
    if (tick_file)
        fprintf(tick_file, "%s %s %ld %.4f %.4f %.4f %ld %ld %ld %ld %ld %ld %d\n", loop,
                stepper, t->n, d->t, 1e3 * w, 1e3 * c, d->stats.nrhs - s0->nrhs,
                d->stats.nsteps - s0->nsteps, d->stats.nrejected - s0->nrejected, d->stats.nevents - s0->nevents,
                d->stats.nlocate_interp - s0->nlocate_interp, d->stats.nlocate_steps - s0->nlocate_steps,
                d->stats.t_stiff > s0->t_stiff);
    t->wall[t->n] = w;
    t->cpu[t->n] = c;
    t->evals[t->n] = (double)(d->stats.nrhs - s0->nrhs);
    if (w > period) t->over++;
    if (a > t->alloc_max) t->alloc_max = a;
    t->alloc_total += a;
    t->n++;
}

/* the loop of examples/control_loop.c with the given stepper */
static void loop_example(cd_stepper stepper)
{
    const double h = 1.0 / RATE_HZ;
    const long n_ticks = (long)(T_END * RATE_HZ + 0.5);
    cd_error err;
    arm_ids ids;
    controller ctl;
    cd_model *m;
    cd_data *d = NULL;
    cd_status st = CD_OK;
    ticks t;
    long k;
    const double wn = 2 * 3.14159265358979323846 * 1.5;
    memset(&err, 0, sizeof err);
    ctl.q0[0] = 0.0; ctl.q0[1] = 0.3; ctl.q0[2] = -0.6;
    ctl.qT[0] = 0.8; ctl.qT[1] = -0.4; ctl.qT[2] = 1.0;
    ctl.kp = wn * wn;
    ctl.kd = 2 * wn;
    m = build_model(ctl.q0, &ids, &err);
    if (!m || !ticks_init(&t, n_ticks)) { say("example: %s\n", err.msg); cd_model_free(m); return; }
    m->opt.stepper = stepper;
    d = cd_data_create(m, 64, &err);
    if (!d) { say("example  %-9s data: %s\n", cd_stepper_name(stepper), err.msg); ticks_free(&t); cd_model_free(m); return; }
    for (k = 0; k < n_ticks; k++) {
        double w0 = clock_s(CLOCK_MONOTONIC), c0 = clock_s(CLOCK_THREAD_CPUTIME_ID);
        long a0 = nalloc;
        cd_stats s0 = d->stats;
        counting = 1;
        if (control_tick(m, d, &ctl, &ids) != 0) { counting = 0; st = CD_ENUMERIC; snprintf(err.msg, sizeof err.msg, "controller"); break; }
        st = cd_step(m, d, h, &err);
        counting = 0;
        if (st != CD_OK) break;
        tick_done(&t, h, w0, c0, a0, d, "example", cd_stepper_name(stepper), &s0);
    }
    report("example", cd_stepper_name(stepper), h, &t, d, st, st == CD_OK ? "" : err.msg);
    ticks_free(&t);
    cd_data_free(d);
    cd_model_free(m);
}

/* the capture scenario at 100 Hz with the given stepper */
#define MAX_SETS 8
static const char *user_sets[MAX_SETS];
static int n_user_sets;

static void loop_capture(cd_stepper stepper)
{
    const char *path = "scenarios/capture_handrail_tumbling.toml";
    const double period = 0.01;
    char ov[3][64];
    const char *ovp[3 + MAX_SETS];
    int nov = 0, i;
    cd_error err;
    cd_scenario *sc;
    cd_data *d = NULL;
    cd_ctrl *ctl = NULL;
    cd_status st = CD_OK;
    ticks t;
    long k, n_ticks;
    memset(&err, 0, sizeof err);
    snprintf(ov[nov++], sizeof ov[0], "simulation.integrator=\"%s\"", cd_stepper_name(stepper));
    if (stepper == CD_STEP_ROS34PW2) snprintf(ov[nov++], sizeof ov[0], "simulation.h_max=0.05");
    if (stepper == CD_STEP_RK4_FIXED) snprintf(ov[nov++], sizeof ov[0], "simulation.h_fixed=1e-4");
    for (i = 0; i < nov; i++) ovp[i] = ov[i];
    for (i = 0; i < n_user_sets; i++) ovp[nov++] = user_sets[i];
    sc = cd_scenario_load(path, ovp, nov, &err);
    if (!sc) { say("capture  %-9s load: %s\n", cd_stepper_name(stepper), err.msg); return; }
    n_ticks = (long)(sc->duration / period + 0.5);
    d = cd_data_create(sc->model, sc->event_capacity, &err);
    if (d && sc->control && (ctl = cd_ctrl_create(sc->model, sc->control, &err))) cd_ctrl_install(ctl, d);
    if (!d || (sc->control && !ctl) || !ticks_init(&t, n_ticks)) {
        say("capture  %-9s set-up: %s\n", cd_stepper_name(stepper), err.msg);
        cd_ctrl_free(ctl); cd_data_free(d); cd_scenario_free(sc);
        return;
    }
    for (k = 0; k < n_ticks; k++) {
        double w0 = clock_s(CLOCK_MONOTONIC), c0 = clock_s(CLOCK_THREAD_CPUTIME_ID);
        long a0 = nalloc;
        cd_stats s0 = d->stats;
        counting = 1;
        st = cd_sim_advance(sc->model, d, (double)(k + 1) * period, NULL, NULL, &err);
        counting = 0;
        if (st != CD_OK) break;
        tick_done(&t, period, w0, c0, a0, d, "capture", cd_stepper_name(stepper), &s0);
    }
    report("capture", cd_stepper_name(stepper), period, &t, d, st, st == CD_OK ? "" : err.msg);
    ticks_free(&t);
    cd_ctrl_free(ctl);
    cd_data_free(d);
    cd_scenario_free(sc);
}

int main(int argc, char **argv)
{
    static const cd_stepper ex_default[] = {CD_STEP_RK4_FIXED, CD_STEP_RK8PD, CD_STEP_ROS34PW2, CD_STEP_RKF45,
                                            CD_STEP_RKCK, CD_STEP_RK4IMP, CD_STEP_MSBDF};
    static const cd_stepper cap_default[] = {CD_STEP_AUTO, CD_STEP_RK8PD, CD_STEP_ROS34PW2, CD_STEP_RK4_FIXED, CD_STEP_RKF45};
    cd_stepper steppers[CD_STEP_NTYPES];
    int nstep = 0, do_ex = 0, do_cap = 0, i;
    const char *out = NULL;
    time_t now = time(NULL);
    char stamp[64];
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "-o") && i + 1 < argc) out = argv[++i];
        else if (!strcmp(argv[i], "--loop") && i + 1 < argc) {
            i++;
            if (!strcmp(argv[i], "example")) do_ex = 1;
            else if (!strcmp(argv[i], "capture")) do_cap = 1;
            else { fprintf(stderr, "%s: unknown loop '%s' (example, capture)\n", argv[0], argv[i]); return 2; }
        } else if (!strcmp(argv[i], "--stepper") && i + 1 < argc && nstep < CD_STEP_NTYPES) {
            int s = cd_stepper_from_name(argv[++i]);
            if (s < 0) { fprintf(stderr, "%s: unknown stepper '%s'\n", argv[0], argv[i]); return 2; }
            steppers[nstep++] = (cd_stepper)s;
        } else if (!strcmp(argv[i], "--ticks") && i + 1 < argc) {
            if (!(tick_file = fopen(argv[++i], "w"))) { fprintf(stderr, "%s: cannot open %s\n", argv[0], argv[i]); return 1; }
            fprintf(tick_file, "# loop stepper tick t wall_ms cpu_ms evals steps rejected events locate_interp "
                               "locate_steps stiff\n");
        } else if (!strcmp(argv[i], "--set") && i + 1 < argc && n_user_sets < MAX_SETS) {
            user_sets[n_user_sets++] = argv[++i];
        } else {
            fprintf(stderr, "usage: %s [-o file] [--loop example|capture]... [--stepper NAME]... [--set KEY=VALUE]... [--ticks FILE]\n",
                    argv[0]);
            return 2;
        }
    }
    if (!do_ex && !do_cap) do_ex = do_cap = 1;
    if (out && !(out_file = fopen(out, "w"))) { fprintf(stderr, "%s: cannot open %s\n", argv[0], out); return 1; }
    strftime(stamp, sizeof stamp, "%Y-%m-%d %H:%M:%S UTC", gmtime(&now));
    say("\n== bench_ticks: control-loop tick times per stepper, capdyn %s, %s\n", cd_version(), stamp);
    say("   example: examples/control_loop.c's loop, 1 kHz, 5 s; capture: capture_handrail_tumbling.toml, 100 Hz, 4.5 s\n");
    for (i = 0; i < n_user_sets; i++) say("   capture loop with --set %s\n", user_sets[i]);
    say("   times in ms per tick (wall clock | this thread's CPU); over = ticks longer than the period (wall)\n");
    say("%-8s %-9s %6s %8s %8s %8s %8s %8s %8s %6s %6s %6s %6s %6s  %s\n", "loop", "stepper", "ticks", "wall med",
        "wall p99", "wall max", "cpu med", "cpu p99", "cpu max", "over", "ev med", "ev max", "al max", "al sum",
        "status");
    if (do_ex)
        for (i = 0; i < (nstep ? nstep : (int)(sizeof ex_default / sizeof *ex_default)); i++)
            loop_example(nstep ? steppers[i] : ex_default[i]);
    if (do_cap)
        for (i = 0; i < (nstep ? nstep : (int)(sizeof cap_default / sizeof *cap_default)); i++)
            loop_capture(nstep ? steppers[i] : cap_default[i]);
    if (out_file) fclose(out_file);
    if (tick_file) fclose(tick_file);
    return 0;
}
