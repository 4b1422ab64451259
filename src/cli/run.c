/* capdyn run / capdyn check.
 *
 * run: load -> create the results file (fails before any simulation if the
 * path is not writable) -> sample every output_dt by cd_sim_advance to the
 * next sample time -> close the file with the run status -> summary.
 * The step callback (after every accepted step and event) draws the
 * progress bar, tracks the largest contact forces of every step, and
 * stops the run when SIGINT/SIGTERM set the flag. */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "capdyn/verdict.h"
#include "capdyn/build.h" /* cd_spin_steps */

#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static const char *run_help =
    "usage: capdyn run SCENARIO.toml [-o FILE.h5] [--set KEY=VALUE ...] [--quiet]\n"
    "\n"
    "Simulates the scenario and writes every output_dt a sample of the state,\n"
    "contact forces and diagnostics to an HDF5 file (docs/results-format.md).\n"
    "\n"
    "options:\n"
    "  -o, --output FILE   results file (default: the scenario's base name with\n"
    "                      .h5, in the current directory); written under a\n"
    "                      temporary name in its directory and renamed onto FILE\n"
    "                      once its layout is written, before the run, which does\n"
    "                      not start if that fails, if FILE is the scenario or\n"
    "                      another run is writing FILE\n"
    "  --set KEY=VALUE     override a scenario value (TOML syntax), repeatable,\n"
    "                      e.g. --set simulation.duration=0.5\n"
    "  -q, --quiet         no progress bar and no summary (errors still shown)\n"
    "  -h, --help          this text\n"
    "\n"
    "A progress bar is drawn on stderr when it is a terminal. Ctrl-C (SIGINT) or\n"
    "SIGTERM stops the run cleanly: the file is closed with what was computed and\n"
    "the exit status is 130. On an integrator failure (stalled step size, NaN,\n"
    "step budget) the file keeps everything up to the failure; exit status 1.\n"
    "If the results file cannot be written (disk full, file size limit), the run\n"
    "stops with one error line naming the file and exit status 1; the file keeps\n"
    "the samples committed before (docs/results-format.md, 'When writing fails').\n"
    "A run that spends its work budget (simulation.max_wall_time, max_rhs_evals)\n"
    "stops like an integrator failure: results kept, exit status 1.\n";

static const char *check_help =
    "usage: capdyn check SCENARIO.toml [--set KEY=VALUE ...]\n"
    "\n"
    "Loads and validates the scenario (with its includes and overrides) and builds\n"
    "the model, without simulating. Prints one line: systems, bodies, joints,\n"
    "check points, shapes, contact slots and state size; and a second line: the\n"
    "least work of the run (steps, right-hand-side evaluations) and its budget\n"
    "(simulation.max_rhs_evals, max_wall_time). Exit status 1 (and the loader's\n"
    "FILE:LINE:COLUMN message) if the scenario is invalid or its least work\n"
    "exceeds max_rhs_evals.\n";

static volatile sig_atomic_t g_signal = 0;
static void on_signal(int sig) { g_signal = sig; }

static void restore_signals(const struct sigaction *i, const struct sigaction *t, const struct sigaction *x,
                            const sigset_t *mask)
{
    sigprocmask(SIG_SETMASK, mask, NULL);
    sigaction(SIGINT, i, NULL);
    sigaction(SIGTERM, t, NULL);
    sigaction(SIGXFSZ, x, NULL);
}

/* SIGINT and SIGTERM stop the run (on_signal), SIGXFSZ is ignored; the
 * previous handlers and mask go to the old_* for restore_signals. */
static void catch_signals(struct sigaction *old_int, struct sigaction *old_term, struct sigaction *old_xfsz,
                          sigset_t *old_mask)
{
    struct sigaction sa;
    sigset_t unblock;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, old_int);
    sigaction(SIGTERM, &sa, old_term);
    sa.sa_handler = SIG_IGN;
    sigaction(SIGXFSZ, &sa, old_xfsz);
    /* a run started with these blocked (inherited mask) still stops on them;
     * one already pending is delivered here and stops the run at its start */
    sigemptyset(&unblock);
    sigaddset(&unblock, SIGINT);
    sigaddset(&unblock, SIGTERM);
    sigprocmask(SIG_UNBLOCK, &unblock, old_mask);
}

/* Most samples a run may ask for (the loader's limit, docs/scenario-format.md). */
#define CLI_MAX_SAMPLES 1e9

static void draw_progress(run_ctx *c, const cd_data *d, double now)
{
    char bar[31];
    double f = c->t_end > 0 ? d->t / c->t_end : 1.0;
    int i, nfull;
    if (f > 1) f = 1;
    if (f < 0) f = 0;
    nfull = (int)(f * 30.0);
    for (i = 0; i < 30; i++) bar[i] = i < nfull ? '#' : '.';
    bar[30] = 0;
    fprintf(stderr, "\r[%s] %5.1f%%  t = %-10.6g s of %g s  wall %7.1f s  events %ld ", bar, 100.0 * f, d->t,
            c->t_end, now - c->wall0, d->ev_count);
    fflush(stderr);
    c->drawn = 1;
    c->last_draw = now;
}

static void clear_progress(run_ctx *c)
{
    if (c->drawn) {
        fputs("\r\033[K", stderr);
        fflush(stderr);
        c->drawn = 0;
    }
}

/* The onset transient of slot k (cli.h, docs/cli.md "Peak forces"): a law
 * whose damper acts at zero penetration (the paper's linear law: f = D xdot
 * at first touch) jumps at onset; the window from the contact's closing to
 * the first step where the elastic term K x^p is at least the rest of the
 * raw force (fnraw - K x^p: the damper) is the onset transient, its force
 * kept apart from the body of the contact. A law without the jump (damper
 * proportional to x^p xdot with D xdot < K) never enters the window. */
static void onset_step(const cd_model *m, const cd_data *d, run_ctx *c, int k)
{
    const cd_contact_law *L = &m->law[m->slot_law[k]];
    double fn = d->slot_fn[k], el;
    if (d->slot_mode[k] == CD_MODE_OPEN || !(fn > 0)) {
        c->onset[k] = 1; /* armed for the next closing */
        return;
    }
    el = d->slot_x[k] > 0 ? L->K * pow(d->slot_x[k], L->p) : 0.0;
    if (c->onset[k] && d->slot_fnraw[k] - el > el) {
        if (fn > c->fn_onset[k]) {
            c->fn_onset[k] = fn;
            if (c->t_onset) c->t_onset[k] = d->t;
        }
        return;
    }
    c->onset[k] = 0;
    if (fn > c->fn_body[k]) {
        c->fn_body[k] = fn;
        if (c->t_body) c->t_body[k] = d->t;
    }
}

double *cli_nan_array(int n)
{
    double *v = malloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
    int i;
    for (i = 0; v && i < (n > 0 ? n : 1); i++) v[i] = NAN;
    return v;
}

/* The pace check of the wall-time budget (docs/scenario-format.md "Work
 * budget"): a run whose pace so far would need more than CLI_PACE_FACTOR
 * times simulation.max_wall_time to reach its duration is stopped once it has
 * run CLI_PACE_WAIT seconds (or a hundredth of the budget, when less), not
 * when the budget is spent: inputs that pass every check but make the steps
 * collapse (a gravity of 1e19 m/s^2, a gain of 1e9) would otherwise take an
 * hour to say so. A legitimate slow start (a contact burst) is far inside the
 * factor: the slowest shipped scenario runs at about real time. */
#define CLI_PACE_WAIT 10.0
#define CLI_PACE_FACTOR 10.0
static int off_pace(run_ctx *c, const cd_data *d, double now)
{
    double el = now - c->wall0, span = c->t_end - c->t_start, done = d->t - c->t_start, wait;
    if (!(span > 0)) return 0;
    wait = 0.01 * c->max_wall < CLI_PACE_WAIT ? 0.01 * c->max_wall : CLI_PACE_WAIT;
    if (el < wait || !(el * span > CLI_PACE_FACTOR * c->max_wall * done)) return 0;
    if (done > 0)
        snprintf(c->budget_msg, sizeof c->budget_msg,
                 "work budget: at its pace so far (t = %.3g s of %g s after %.3g s of wall-clock time, the last step "
                 "%.3g s long) the run would need about %.3g s, more than %g x simulation.max_wall_time = %g s; "
                 "stopped early (0 lifts the budget)",
                 d->t, c->t_end, el, d->stats.h_last, el * span / done, CLI_PACE_FACTOR, c->max_wall);
    else
        snprintf(c->budget_msg, sizeof c->budget_msg,
                 "work budget: no progress past t = %.9g s after %.3g s of wall-clock time, so the run cannot end "
                 "within %g x simulation.max_wall_time = %g s; stopped early (0 lifts the budget)",
                 d->t, el, CLI_PACE_FACTOR, c->max_wall);
    return 1;
}

static int step_cb(const cd_model *m, cd_data *d, void *user)
{
    run_ctx *c = (run_ctx *)user;
    int k;
    double now = -1;
    if (g_signal) return 1;
    if (c->max_rhs > 0 && (double)d->stats.nrhs > c->max_rhs) {
        snprintf(c->budget_msg, sizeof c->budget_msg,
                 "work budget spent: %ld right-hand-side evaluations, more than simulation.max_rhs_evals = %g, at t = %.9g s",
                 d->stats.nrhs, c->max_rhs, d->t);
        return 1;
    }
    if (c->max_wall > 0) {
        now = cli_wall();
        if (now - c->wall0 > c->max_wall) {
            snprintf(c->budget_msg, sizeof c->budget_msg,
                     "work budget spent: %.1f s of wall-clock time, more than simulation.max_wall_time = %g s, at t = %.9g s",
                     now - c->wall0, c->max_wall, d->t);
            return 1;
        }
        if (off_pace(c, d, now)) return 1;
    }
    for (k = 0; k < m->nslot; k++) {
        const double *ft = d->slot_ft + 3 * k;
        double a = sqrt(ft[0] * ft[0] + ft[1] * ft[1] + ft[2] * ft[2]);
        if (d->slot_fn[k] > c->fn_max[k]) c->fn_max[k] = d->slot_fn[k];
        if (a > c->ft_max[k]) c->ft_max[k] = a;
        if (c->onset) onset_step(m, d, c, k);
    }
    if (c->progress) {
        if (now < 0) now = cli_wall();
        if (now - c->last_draw >= 0.1) draw_progress(c, d, now);
    }
    return 0;
}

/* Options shared by run and check. Returns -1 when done (help printed),
 * CLI_USAGE on an error, 0 to go on. */
typedef struct {
    const char *scenario, *output;
    const char **sets;
    int nsets, quiet;
} run_opts;

static int parse_opts(const char *cmd, int argc, char **argv, run_opts *o, int is_run)
{
    int i, only_args = 0;
    memset(o, 0, sizeof *o);
    o->sets = calloc((size_t)argc + 1, sizeof *o->sets);
    if (!o->sets) {
        cli_error("out of memory");
        return CLI_FAIL;
    }
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!only_args && a[0] == '-' && a[1]) {
            if (!strcmp(a, "--")) { only_args = 1; continue; }
            if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
                fputs(is_run ? run_help : check_help, stdout);
                return -1;
            }
            if (!strcmp(a, "--set") || !strncmp(a, "--set=", 6)) {
                const char *v = a[5] == '=' ? a + 6 : (i + 1 < argc ? argv[++i] : NULL);
                if (!v) return cli_usage(cmd, "--set needs KEY=VALUE");
                if (!strchr(v, '=') || v[0] == '=') return cli_usage(cmd, "--set expects KEY=VALUE, got '%s'", v);
                o->sets[o->nsets++] = v;
                continue;
            }
            if (is_run && (!strcmp(a, "-o") || !strcmp(a, "--output") || !strncmp(a, "--output=", 9))) {
                const char *v = a[1] == '-' && a[8] == '=' ? a + 9 : (i + 1 < argc ? argv[++i] : NULL);
                if (!v || !*v) return cli_usage(cmd, "%s needs a file name", a);
                o->output = v;
                continue;
            }
            if (is_run && (!strcmp(a, "-q") || !strcmp(a, "--quiet"))) {
                o->quiet = 1;
                continue;
            }
            return cli_usage(cmd, "unknown option '%s'", a);
        }
        if (o->scenario) return cli_usage(cmd, "unexpected argument '%s' (one scenario file per run)", a);
        o->scenario = a;
    }
    if (!o->scenario) return cli_usage(cmd, "missing the scenario file");
    return 0;
}

static void default_output(const char *scenario, char *out, size_t len)
{
    const char *b = strrchr(scenario, '/');
    size_t n;
    b = b ? b + 1 : scenario;
    n = strlen(b);
    if (n > 5 && strcmp(b + n - 5, ".toml") == 0) n -= 5;
    snprintf(out, len, "%.*s.h5", (int)n, b);
}

/* The least work of the run (the loader's estimate) and its budget. */
static void print_budget(const cd_scenario *sc)
{
    char rhs[32], wall[32];
    if (sc->max_rhs_evals > 0) snprintf(rhs, sizeof rhs, "%g", sc->max_rhs_evals);
    else snprintf(rhs, sizeof rhs, "none");
    if (sc->max_wall_time > 0) snprintf(wall, sizeof wall, "%g s", sc->max_wall_time);
    else snprintf(wall, sizeof wall, "none");
    printf("work: at least %.6g steps and %.6g right-hand-side evaluations; budget: max_rhs_evals %s, "
           "max_wall_time %s\n",
           sc->min_steps, sc->min_rhs_evals, rhs, wall);
}

/* A check point that starts deeper inside a shape than its own radius and
 * than 5 mm (a heuristic: resting compliant contacts sit far shallower): the
 * initial pose overlaps (an object placed inside a finger). The run is still
 * physics (the first contact force is K x^p), but rarely what was meant.
 * Writes the deepest such slot into msg; returns how many there are (cli.h). */
int cli_initial_overlap(const cd_model *m, const cd_data *d, char *msg, size_t n)
{
    int k, worst = -1, count = 0;
    for (k = 0; k < m->nslot; k++) {
        int cp = m->slot_cp[k];
        if (d->slot_x[k] > m->cp_radius[cp] && d->slot_x[k] > CLI_OVERLAP_MIN) {
            count++;
            if (worst < 0 || d->slot_x[k] - m->cp_radius[cp] > d->slot_x[worst] - m->cp_radius[m->slot_cp[worst]]) worst = k;
        }
    }
    if (count && msg && n) {
        int cp = m->slot_cp[worst], ba = m->cp_body[cp], bb = m->shape_body[m->slot_shape[worst]];
        snprintf(msg, n,
                 "at t = 0, %d check point%s start%s deeper inside a shape than their radius and %g mm (the initial pose "
                 "overlaps); the deepest: check point %d of '%s/%s' is %.3g mm inside a shape of '%s/%s' (radius %.3g mm)",
                 count, count == 1 ? "" : "s", count == 1 ? "s" : "", 1e3 * CLI_OVERLAP_MIN, cp, m->sys_name[m->body_sys[ba]], m->body_name[ba],
                 1e3 * d->slot_x[worst], m->sys_name[m->body_sys[bb]], m->body_name[bb], 1e3 * m->cp_radius[cp]);
    }
    return count;
}

/* the loader's warnings (a non-convex URDF mesh hulled), one line each on stderr */
static void warn_loader(const char *scenario, const cd_scenario *sc)
{
    const char *p = sc->warnings;
    while (p && *p) {
        const char *e = strchr(p, '\n');
        int n = e ? (int)(e - p) : (int)strlen(p);
        fprintf(stderr, "capdyn: warning: %s: %.*s\n", scenario, n, p);
        p = e ? e + 1 : p + n;
    }
}

/* the warning of check and run: one line on stderr */
static void warn_initial_overlap(const char *scenario, const cd_model *m, const cd_data *d)
{
    char msg[512];
    if (cli_initial_overlap(m, d, msg, sizeof msg)) fprintf(stderr, "capdyn: warning: %s: %s\n", scenario, msg);
}

/* An object that starts outside the capture workspace (a sphere of radius
 * [capture] workspace about the palm centre) is 'escaped' at t = 0: one line
 * on stderr, the run goes on */
static void warn_workspace(const char *scenario, const cd_scenario *sc, const cd_data *d)
{
    const cd_model *m = sc->model;
    cd_monitor_opts op;
    cd_monitor mo;
    cd_error e;
    if (sc->capture_hand < 0 || sc->capture_object < 0) return;
    op = cd_scenario_monitor_opts(sc);
    if (cd_monitor_init(&mo, m, d, &op, &e) != CD_OK) return;
    cd_monitor_update(&mo, m, d);
    if (mo.verdict != CD_VERDICT_ESCAPED) return;
    fprintf(stderr,
            "capdyn: warning: %s: the object '%s' starts %.4g m from the palm centre, outside the capture workspace "
            "([capture] workspace = %g m): the verdict is 'escaped' at t = 0\n",
            scenario, m->sys_name[op.object], mo.offset_norm, mo.opt.workspace);
}

/* A tumbling rate that costs far more steps than the run would otherwise
 * take (cd_spin_steps, build.h: roughly; more than 1e5 steps and 10 times
 * the run's least steps): one line on stderr, the run goes on */
static void warn_fast_spin(const char *scenario, const cd_scenario *sc)
{
    const cd_model *m = sc->model;
    double w, steps;
    int s = cd_spin_steps(m, sc->duration, &w, &steps);
    if (s < 0 || !(steps > 1e5) || !(steps > 10 * sc->min_steps)) return;
    fprintf(stderr,
            "capdyn: warning: %s: system '%s' tumbles at %.3g rad/s: following it takes roughly %.2g integrator steps "
            "(%s at rtol %g) for duration = %g s, against at least %.3g otherwise\n",
            scenario, m->sys_name[s], w, steps, cd_stepper_name(m->opt.stepper), m->opt.rtol, sc->duration, sc->min_steps);
}

int cmd_check(int argc, char **argv)
{
    run_opts o;
    cd_scenario *sc;
    cd_error err;
    const cd_model *m;
    int rc = parse_opts("check", argc, argv, &o, 0), njoint = 0, s;
    if (rc) {
        free(o.sets);
        return rc < 0 ? CLI_OK : rc;
    }
    sc = cd_scenario_load(o.scenario, o.sets, o.nsets, &err);
    free(o.sets);
    if (!sc) {
        cli_error("%s", err.msg);
        return CLI_FAIL;
    }
    m = sc->model;
    for (s = 0; s < m->nsys; s++) njoint += m->sys_nbody[s] - 1;
    {   /* the initial pose: an object that starts inside a finger; and the data a run needs */
        cd_data *d = cd_data_create(m, 0, &err);
        if (!d) {
            cli_error("%s: %s", o.scenario, err.msg);
            cd_scenario_free(sc);
            return CLI_FAIL;
        }
        warn_initial_overlap(o.scenario, m, d);
        warn_workspace(o.scenario, sc, d);
        /* the first evaluation of a run: an input too large (or small) for
         * double precision stops a run at t = 0, so check says so now */
        if (cd_forward(m, d) != CD_OK) {
            cli_error("%s: the initial state (t = %g s) gives a non-finite value or a singular mass matrix, so a run "
                      "would stop at once; expected inputs a double can carry through the dynamics (look for huge "
                      "positions, velocities, torques, gains or gravity, or tiny masses and inertias)",
                      o.scenario, d->t);
            cd_data_free(d);
            cd_scenario_free(sc);
            return CLI_FAIL;
        }
        /* the first sample's energy and momenta: a velocity of 1e300 m/s
         * passes the evaluation, but its kinetic energy is inf and a run
         * stops at its first sample */
        for (s = 0; s < m->nsys; s++) {
            double ke, P[3], Lc[3], Lo[3], c[3], pe = cd_potential_energy(m, d, s);
            cd_momentum(m, d, s, &ke, P, Lc, Lo, c);
            if (!isfinite(ke + pe + P[0] + P[1] + P[2] + Lc[0] + Lc[1] + Lc[2] + Lo[0] + Lo[1] + Lo[2] + c[0] + c[1] +
                          c[2])) {
                cli_error("%s: system '%s' at the initial state (t = %g s) has a non-finite %s, so a run would stop at "
                          "its first sample; expected velocities, angular velocities, positions and masses whose "
                          "energy and momenta a double can hold",
                          o.scenario, m->sys_name[s], d->t,
                          !isfinite(ke) ? "kinetic energy" : !isfinite(pe) ? "potential energy"
                          : !isfinite(P[0] + P[1] + P[2]) ? "linear momentum" : "angular momentum or centre of mass");
                cd_data_free(d);
                cd_scenario_free(sc);
                return CLI_FAIL;
            }
        }
        cd_data_free(d);
    }
    warn_fast_spin(o.scenario, sc);
    warn_loader(o.scenario, sc);
    printf("%s: OK: '%s': %d system%s, %d bodies (%d joints), %d check points, %d shapes, %d contact slots, "
           "state size %d; %g s, output every %g s\n",
           o.scenario, sc->title ? sc->title : "", m->nsys, m->nsys == 1 ? "" : "s", m->nbody, njoint, m->ncp,
           m->nshape, m->nslot, m->ny, sc->duration, sc->output_dt);
    print_budget(sc);
    if (sc->imported && sc->imported[0]) printf("imported from URDF:\n%s", sc->imported);
    cd_scenario_free(sc);
    return CLI_OK;
}

/* The verdict and figures of merit of a monitor at the end of a run (cli.h). */
void cli_capture_of(const cd_monitor *mon, const cd_ctrl *ctl, const cd_ctrl_merit *merit, const cd_model *m,
                    const cd_data *d, cd_h5_capture *cap)
{
    int fc;
    cd_error qerr;
    memset(cap, 0, sizeof *cap);
    cap->verdict = cd_verdict_name(mon->verdict);
    cap->t = mon->verdict == CD_VERDICT_CAPTURED ? mon->t_capture
             : mon->verdict == CD_VERDICT_ESCAPED ? mon->t_escape
             : mon->verdict == CD_VERDICT_CAGED ? mon->t_cage : NAN;
    cap->peak_fn = mon->peak_fn;
    cap->peak_tau = mon->peak_tau;
    memcpy(cap->offset, mon->offset, sizeof cap->offset);
    cap->n_stick = mon->n_stick;
    cap->n_slip = mon->n_slip;
    if (cd_monitor_quality(mon, m, d, &cap->epsilon, &fc, &qerr) != CD_OK) cap->epsilon = NAN;
    if (ctl && merit) { /* the controller's figures of merit (docs/capture.md) */
        memcpy(cap->dP, merit->dP, sizeof cap->dP);
        memcpy(cap->dL, merit->dL, sizeof cap->dL);
        cap->base_angle_max = merit->base_angle_max;
        cap->base_rate_end = merit->base_rate;
        cap->t_trigger = cd_ctrl_t_trigger(ctl);
        cap->t_rigidise = mon->verdict == CD_VERDICT_CAPTURED ? mon->t_capture - cap->t_trigger : NAN;
        cap->v_rel_end = merit->v_rel;
        cap->w_rel_end = merit->w_rel;
        cap->tau_arm_max = merit->tau_arm_max;
    }
}

/* Where the samples of a run go, whichever way they are taken: the file,
 * the monitor, the controller's figures of merit, the periodic flush. */
typedef struct {
    run_ctx *c;
    cd_h5_writer *w;
    cd_monitor *mon;
    const cd_scenario *sc;
    cd_status wst;        /* the first failure of a sample (writer, or an unevaluable sample) */
    cd_error werr;
    double t_last_sample, last_flush;
    int verdict_stop;     /* stopped at the monitor's verdict (--until-verdict) */
} sample_out;

/* One sample: 0 to go on, 1 to stop (a failure in o->wst, or the verdict). */
static int take_sample(sample_out *o, const cd_model *m, const cd_data *s)
{
    cd_status st = CD_OK;
    if (o->w) st = cd_h5_append(o->w, m, s, &o->werr);
    /* a sample with a non-finite value is kept in the file (CD_ENUMERIC) */
    if (st == CD_OK || st == CD_ENUMERIC) o->t_last_sample = s->t;
    if (st != CD_OK) { o->wst = st; return 1; }
    if (o->mon) cd_monitor_update(o->mon, m, s);
    if (o->c->ctl && o->c->merit) cd_ctrl_merit_update(o->c->merit, o->c->ctl, m, s);
    /* capdyn sweep --until-verdict: at a final verdict (a cage may still
     * become a grip or let the object go) */
    if (o->mon && o->c->until_verdict &&
        (o->mon->verdict == CD_VERDICT_CAPTURED || o->mon->verdict == CD_VERDICT_ESCAPED)) {
        o->verdict_stop = 1;
        return 1;
    }
    if (o->w && cli_wall() - o->last_flush >= o->sc->flush_every) {
        st = cd_h5_flush(o->w, &o->werr);
        if (st != CD_OK) { o->wst = st; return 1; }
        o->last_flush = cli_wall();
    }
    return 0;
}

/* Dense output (simulation.sampling = "interpolate"): one cd_sim_advance over
 * the whole run; the step callback hands every accepted step to the sampler,
 * whose samples (k output_dt below the duration) are taken; the last sample
 * is the run's own state at the duration. */
typedef struct {
    sample_out *o;
    cd_sampler *smp;
} dense_ctx;

static int dense_sample(const cd_model *m, const cd_data *s, void *user)
{
    sample_out *o = (sample_out *)user;
    if (s->t >= o->sc->duration * (1.0 - 1e-12)) return 0; /* the final one is taken at the end */
    return take_sample(o, m, s);
}

static int dense_step_cb(const cd_model *m, cd_data *d, void *user)
{
    dense_ctx *x = (dense_ctx *)user;
    int r = step_cb(m, d, x->o->c);
    if (r) return r;
    r = cd_sampler_update(x->smp, m, d, dense_sample, x->o);
    if (r < 0) { /* a sample state that cannot be evaluated */
        x->o->wst = CD_ENUMERIC;
        snprintf(x->o->werr.msg, sizeof x->o->werr.msg, "an interpolated sample after t = %.9g s cannot be evaluated", d->t);
        return 1;
    }
    return r;
}

static cd_status dense_loop(const cd_scenario *sc, cd_data *d, sample_out *o, cd_error *err)
{
    const cd_model *m = sc->model;
    dense_ctx x;
    cd_status st;
    x.o = o;
    x.smp = cd_sampler_create(m, err);
    if (!x.smp) return err->status;
    st = cd_sampler_begin(x.smp, m, d, 0.0, sc->output_dt, err); /* k output_dt, as the stopping loop */
    if (st == CD_OK) st = cd_sim_advance(m, d, sc->duration, dense_step_cb, &x, err);
    if (o->verdict_stop && st == CD_EINTERRUPT) st = CD_OK;
    else if (st == CD_OK && o->wst == CD_OK) (void)take_sample(o, m, d); /* the last sample: the state at the duration */
    if (o->wst != CD_OK) { st = o->wst; *err = o->werr; }
    cd_sampler_free(x.smp);
    return st;
}

/* The run loop of capdyn run, shared with capdyn sweep (cli.h). */
cd_status cli_run_loop(const cd_scenario *sc, cd_data *d, cd_h5_writer *w, cd_monitor *mon, run_ctx *c,
                       cd_error *errp, char *wmsg, size_t wlen)
{
    const cd_model *m = sc->model;
    cd_error err, werr;
    cd_status st = CD_OK;
    long i, nout;
    double ratio = sc->duration / sc->output_dt;
    sample_out o;
    /* the state at t = 0 counts for the maxima too (contacts closed at start) */
    c->t_start = d->t;
    (void)step_cb(m, d, c);
    if (c->ctl && c->merit) cd_ctrl_merit_init(c->merit, c->ctl, m, d); /* docs/capture.md */

    err.status = werr.status = CD_OK;
    err.msg[0] = werr.msg[0] = 0;
    if (wlen) wmsg[0] = 0;
    if (w) st = cd_h5_append(w, m, d, &werr);
    if (st != CD_OK) err = werr;
    /* a signal that came while the file was being created */
    if (st == CD_OK && g_signal) st = CD_EINTERRUPT;
    memset(&o, 0, sizeof o);
    o.c = c; o.w = w; o.mon = mon; o.sc = sc;
    o.t_last_sample = d->t;
    o.last_flush = cli_wall();
    /* samples at k output_dt; the last one exactly at the duration */
    nout = (long)ceil(ratio - 1e-9);
    if (st == CD_OK && sc->interpolate) {
        st = dense_loop(sc, d, &o, &err);
        nout = 0;
    }
    for (i = 1; st == CD_OK && i <= nout; i++) {
        double tn = i == nout ? sc->duration : (double)i * sc->output_dt;
        if (tn > sc->duration) tn = sc->duration;
        st = cd_sim_advance(m, d, tn, step_cb, c, &err);
        if (st != CD_OK) break;
        if (take_sample(&o, m, d)) {
            if (o.wst != CD_OK) { st = o.wst; err = o.werr; }
            break;
        }
        if (g_signal) { st = CD_EINTERRUPT; break; }
    }
    if (st == CD_EINTERRUPT && c->budget_msg[0]) snprintf(err.msg, sizeof err.msg, "%s", c->budget_msg);
    if (st != CD_OK && err.msg[0] == 0) snprintf(err.msg, sizeof err.msg, "%s at t = %.9g s", cd_status_string(st), d->t);
    /* the writer's errors are the only CD_EIO of a run */
    if (st == CD_EIO) snprintf(wmsg, wlen, "%s", err.msg);
    clear_progress(c);

    /* keep the last good state of a failed or interrupted run */
    if (w && st != CD_OK && st != CD_EIO && d->t > o.t_last_sample) (void)cd_h5_append(w, m, d, &werr);
    *errp = err;
    return st;
}

/* The end of capdyn run: the file's summary on stdout (unless --quiet or
 * the file could not be written), then one line on stderr if the run did
 * not finish (msg: how it ended; wmsg: the first write error, "" if none). */
static void run_report(const run_opts *o, const char *out, const run_ctx *ctx, const cd_data *d, cd_status st,
                       int exitc, const char *msg, const char *wmsg, int attitude)
{
    if (!wmsg[0] && !o->quiet) {
        cd_error rerr;
        cd_h5r *r = cd_h5r_open(out, &rerr);
        if (r) {
            cli_run_extra x;
            x.wall = ctx->wall0;
            x.fn_max = ctx->fn_max;
            x.ft_max = ctx->ft_max;
            x.fn_onset = ctx->fn_onset;
            x.fn_body = ctx->fn_body;
            x.t_onset = ctx->t_onset;
            x.t_body = ctx->t_body;
            x.attitude = attitude;
            cli_report(stdout, r, out, &x);
            cd_h5r_close(r);
        } else {
            cli_error("reading back '%s': %s", out, rerr.msg);
        }
    }
    fflush(stdout);
    if (wmsg[0]) {
        /* one line: the first write error (it names the file and what failed) */
        if (st != CD_OK && st != CD_EIO)
            cli_error("run failed (%s): %s", cd_status_string(st), msg);
        cli_error("%s (simulation at t = %.9g s)", wmsg, d->t);
    } else if (exitc == CLI_INTERRUPT)
        fprintf(stderr, "capdyn: %s; results up to t = %.9g s kept in '%s'\n", msg, d->t, out);
    else if (exitc != CLI_OK)
        cli_error("run failed (%s): %s; results up to t = %.9g s kept in '%s'", cd_status_string(st), msg, d->t,
                  out);
}

/* The scenario of capdyn run (o->sets freed), its data and controller
 * (may be NULL): CLI_OK, or CLI_FAIL after one error line with nothing
 * left allocated. */
static int run_setup(run_opts *o, cd_scenario **scp, cd_data **dp, cd_ctrl **ctlp)
{
    cd_scenario *sc;
    const cd_model *m;
    cd_data *d;
    cd_ctrl *ctl = NULL;
    cd_error err;
    double ratio;
    *scp = NULL;
    *dp = NULL;
    *ctlp = NULL;
    *scp = sc = cd_scenario_load(o->scenario, o->sets, o->nsets, &err);
    free(o->sets);
    if (!sc) {
        cli_error("%s", err.msg);
        return CLI_FAIL;
    }
    m = sc->model;
    if (!(sc->duration > 0) || !(sc->output_dt > 0) || !isfinite(sc->duration)) {
        cli_error("%s: duration and output_dt must be positive and finite", o->scenario);
        cd_scenario_free(sc);
        return CLI_FAIL;
    }
    /* the loader bounds duration / output_dt; this guards the conversion to
     * an integer (undefined behaviour when out of range) all the same */
    ratio = sc->duration / sc->output_dt;
    if (!(ratio <= CLI_MAX_SAMPLES)) {
        cli_error("%s: duration / output_dt = %g samples is more than %g; raise simulation.output_dt",
                  o->scenario, ratio, CLI_MAX_SAMPLES);
        cd_scenario_free(sc);
        return CLI_FAIL;
    }
    /* the data and the [control] controller: cd_scenario_setup (io.h), the
     * same code path as the FMU's (src/fmu/, docs/fmu.md) */
    if (cd_scenario_setup(sc, &d, &ctl, &err) != CD_OK) {
        if (!strncmp(err.msg, "control:", 8)) cli_error("%s: %s", o->scenario, err.msg);
        else cli_error("%s", err.msg);
        cd_scenario_free(sc);
        return CLI_FAIL;
    }
    *dp = d;
    *ctlp = ctl;
    warn_initial_overlap(o->scenario, m, d);
    warn_workspace(o->scenario, sc, d);
    warn_fast_spin(o->scenario, sc);
    warn_loader(o->scenario, sc);
    return CLI_OK;
}

int cmd_run(int argc, char **argv)
{
    run_opts o;
    cd_scenario *sc;
    const cd_model *m;
    cd_data *d = NULL;
    cd_h5_writer *w;
    cd_error err, werr;
    cd_status st = CD_OK, cst;
    cd_monitor mon;
    cd_ctrl *ctl = NULL;
    cd_ctrl_merit merit;
    int have_mon = 0;
    run_ctx ctx;
    char outbuf[1024], msg[768], wmsg[512];
    const char *out;
    int rc = parse_opts("run", argc, argv, &o, 1), exitc;
    struct sigaction old_int, old_term, old_xfsz;
    sigset_t old_mask;

    if (rc) {
        free(o.sets);
        return rc < 0 ? CLI_OK : rc;
    }
    if (o.output) out = o.output;
    else {
        default_output(o.scenario, outbuf, sizeof outbuf);
        out = outbuf;
    }
    if (run_setup(&o, &sc, &d, &ctl) != CLI_OK) return CLI_FAIL;
    m = sc->model;
    /* Signals are caught before the results file exists, so that a SIGINT
     * while it is being created still ends with a closed file. SIGXFSZ
     * (file size limit, ulimit -f) would kill the process in the middle of
     * an HDF5 write: ignored, the write fails with EFBIG and is reported. */
    catch_signals(&old_int, &old_term, &old_xfsz, &old_mask);

    /* the results file first: an unwritable path fails before any work */
    w = cd_h5_create(out, m, sc, &err);
    if (!w) {
        cli_error("%s", err.msg);
        restore_signals(&old_int, &old_term, &old_xfsz, &old_mask);
        cd_data_free(d);
        cd_ctrl_free(ctl);
        cd_scenario_free(sc);
        return CLI_FAIL;
    }

    memset(&ctx, 0, sizeof ctx);
    ctx.fn_max = calloc((size_t)(m->nslot ? m->nslot : 1), sizeof(double));
    ctx.ft_max = calloc((size_t)(m->nslot ? m->nslot : 1), sizeof(double));
    ctx.fn_onset = calloc((size_t)(m->nslot ? m->nslot : 1), sizeof(double));
    ctx.fn_body = calloc((size_t)(m->nslot ? m->nslot : 1), sizeof(double));
    ctx.t_onset = cli_nan_array(m->nslot);
    ctx.t_body = cli_nan_array(m->nslot);
    ctx.onset = malloc((size_t)(m->nslot ? m->nslot : 1));
    if (ctx.onset) memset(ctx.onset, 1, (size_t)(m->nslot ? m->nslot : 1));
    ctx.t_end = sc->duration;
    ctx.wall0 = cli_wall();
    ctx.last_draw = -1e300;
    ctx.progress = !o.quiet && isatty(STDERR_FILENO);
    ctx.max_wall = sc->max_wall_time;
    ctx.max_rhs = sc->max_rhs_evals;
    if (!ctx.fn_max || !ctx.ft_max || !ctx.fn_onset || !ctx.fn_body || !ctx.t_onset || !ctx.t_body || !ctx.onset) {
        cli_error("out of memory");
        cd_h5_close(w, m, d, CD_ENOMEM, "out of memory", NULL);
        restore_signals(&old_int, &old_term, &old_xfsz, &old_mask);
        free(ctx.fn_max);
        free(ctx.ft_max);
        free(ctx.fn_onset);
        free(ctx.fn_body);
        free(ctx.t_onset);
        free(ctx.t_body);
        free(ctx.onset);
        cd_data_free(d);
        cd_ctrl_free(ctl);
        cd_scenario_free(sc);
        return CLI_FAIL;
    }
    /* the capture verdict, when the scenario has a gripper and an object */
    have_mon = sc->capture_hand >= 0 && sc->capture_object >= 0;
    if (have_mon) {
        cd_monitor_opts mop = cd_scenario_monitor_opts(sc);
        if (cd_monitor_init(&mon, m, d, &mop, &err) != CD_OK) {
            cli_error("%s", err.msg);
            have_mon = 0;
        } else {
            cd_monitor_update(&mon, m, d);
        }
    }
    ctx.ctl = ctl;
    ctx.merit = ctl ? &merit : NULL;
    st = cli_run_loop(sc, d, w, have_mon ? &mon : NULL, &ctx, &err, wmsg, sizeof wmsg);
    if (st == CD_EINTERRUPT && g_signal)
        snprintf(msg, sizeof msg, "stopped by %s at t = %.9g s", g_signal == SIGINT ? "SIGINT" : "SIGTERM", d->t);
    else if (st == CD_OK)
        snprintf(msg, sizeof msg, "finished at t = %.9g s", d->t);
    else
        snprintf(msg, sizeof msg, "%s", err.msg);
    if (have_mon) { /* the verdict goes into the file (capdyn info, the summary below) */
        cd_h5_capture cap;
        cli_capture_of(&mon, ctl, ctl ? &merit : NULL, m, d, &cap);
        cd_h5_set_capture(w, &cap);
    }
    /* the peaks over steps go into the file too, so that capdyn info prints
     * the lines this run prints (docs/cli.md, "Peak forces") */
    {
        cd_h5_step_peaks pk = {ctx.fn_max, ctx.fn_body, ctx.fn_onset, ctx.ft_max, ctx.t_body, ctx.t_onset};
        cd_h5_set_step_peaks(w, m->nslot, &pk);
    }
    cst = cd_h5_close(w, m, d, st, msg, &werr);
    if (cst != CD_OK && !wmsg[0]) snprintf(wmsg, sizeof wmsg, "%s", werr.msg);
    ctx.wall0 = cli_wall() - ctx.wall0;
    restore_signals(&old_int, &old_term, &old_xfsz, &old_mask);

    /* a results file that could not be written is a failure, whatever the
     * simulation did */
    if (wmsg[0]) exitc = CLI_FAIL;
    else if (st == CD_OK) exitc = CLI_OK;
    else if (st == CD_EINTERRUPT && g_signal) exitc = CLI_INTERRUPT;
    else exitc = CLI_FAIL;

    run_report(&o, out, &ctx, d, st, exitc, msg, wmsg, sc->control && sc->control->attitude);
    free(ctx.fn_max);
    free(ctx.ft_max);
    free(ctx.fn_onset);
    free(ctx.fn_body);
    free(ctx.t_onset);
    free(ctx.t_body);
    free(ctx.onset);
    cd_data_free(d);
    cd_ctrl_free(ctl);
    cd_scenario_free(sc);
    return exitc;
}
