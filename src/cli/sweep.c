/* capdyn sweep: many variants of one scenario, each a normal run, on every
 * core (docs/sweep.md).
 *
 * The plan (grid or Latin hypercube over 1-4 --set keys) is made in the
 * parent. Variants run in worker processes (fork; HDF5 is not thread-safe
 * and a variant that crashes takes only its worker down), handed out one at
 * a time (dynamic distribution) through a pipe per worker; each worker loads
 * the scenario with the variant's overrides (cd_scenario_load) and runs the
 * loop of capdyn run (cli_run_loop) without a results file unless
 * --keep-runs. Results come back as fixed-size records and are stored by
 * variant index, so the summary does not depend on -j or on the order in
 * which variants finish. The parent writes the summary (sweep_h5.c) every
 * SW_CHECKPOINT seconds, on SIGINT/SIGTERM and at the end; --resume reads
 * it back and runs only the variants not yet run. */
#define _POSIX_C_SOURCE 200809L
#include "sweep.h"
#include "capdyn/verdict.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#ifdef CAPDYN_MPI
#include <mpi.h>
#endif

/* Seconds of wall time between two summary checkpoints: a sweep killed
 * without a chance to write (SIGKILL, power) loses at most this much work. */
#define SW_CHECKPOINT 10.0
#define SW_MAX_JOBS 1024

static const char *sweep_help =
    "usage: capdyn sweep SCENARIO.toml --vary KEY=SPEC [--vary KEY=SPEC ...] [options]\n"
    "       capdyn sweep --table SUMMARY.h5\n"
    "\n"
    "Runs one variant of the scenario per point of a grid (default) or of a Latin\n"
    "hypercube over 1 to 4 keys, on every core, and writes one HDF5 summary: the\n"
    "swept values, each variant's verdict and figures of merit, failure reasons,\n"
    "and wall times (docs/sweep.md).\n"
    "\n"
    "SPEC:  A:B:N         N values from A to B, both included (grid); the interval\n"
    "                     [A, B] under --lhs (N is then unused; A:B also works)\n"
    "       V1,V2,...     a list of TOML values (\"tako\",\"space\" needs the quotes\n"
    "                     escaped for the shell; bare words are strings)\n"
    "\n"
    "options:\n"
    "  -o, --output FILE   the summary (default: the scenario's base name with\n"
    "                      _sweep.h5); written under a temporary name, renamed\n"
    "  --set KEY=VALUE     an override of every variant (before the swept keys)\n"
    "  --lhs N             N variants of a Latin hypercube instead of the grid\n"
    "  --seed S            the hypercube's seed (default 1)\n"
    "  -j, --jobs N        worker processes (default: the online cores)\n"
    "  --resume            continue the sweep in FILE: run only what it lacks\n"
    "  --keep-runs DIR     also write each variant's results file DIR/variant_NNNNNN.h5\n"
    "  --until-verdict     end each variant at its verdict (captured or escaped)\n"
    "                      instead of at the scenario's duration\n"
    "  --length L          [m] the gripper's total finger length: positions and the\n"
    "                      region area are normalised by it\n"
    "  -q, --quiet         no progress bar and no summary line\n"
    "  --table FILE        print a summary as columns for gnuplot and exit\n"
    "  -h, --help          this text\n"
    "\n"
    "A variant that fails (numerical failure, work budget, an override its\n"
    "scenario refuses, a crash) is recorded with its reason and the sweep goes on.\n"
    "Ctrl-C (SIGINT) or SIGTERM stops the workers and writes the summary of what\n"
    "finished (exit 130); --resume completes it. Exit 0 when every variant ran\n"
    "(failed ones included), 1 on an error, 2 on a bad command line.\n";

static volatile sig_atomic_t g_stop = 0;
static void on_stop(int sig) { g_stop = sig; }

typedef struct {
    const char *scenario, *output, *keep_dir, *table;
    const char **sets;
    int nsets;
    const char *vary[SW_MAX_KEYS + 1];
    int nvary;
    long lhs, jobs;
    unsigned long long seed;
    int quiet, resume, have_jobs, until_verdict;
    double length;
} sw_opts;

/* ---- the plan ------------------------------------------------------------- */

/* A number written so that strtod gives it back exactly, as short as that allows. */
static void fmt_num(char *buf, size_t len, double v)
{
    int prec;
    for (prec = 15; prec <= 17; prec++) {
        snprintf(buf, len, "%.*g", prec, v);
        if (strtod(buf, NULL) == v) return;
    }
}

/* A grid value rounded to a millionth of the grid step, in decimal, so that
 * -0.1:0.1:41 gives 0.005, not 0.004999999999999999 (the text is the value
 * every variant's loader parses, stored in the summary). */
static void fmt_grid(char *buf, size_t len, double v, double step)
{
    int dec;
    char *e;
    step = fabs(step);
    if (!(step > 0) || !(fabs(v) < 1e15) || step < 1e-290) {
        fmt_num(buf, len, v);
        return;
    }
    dec = 6 - (int)floor(log10(step));
    if (dec < 0) dec = 0;
    if (dec > 20) {
        fmt_num(buf, len, v);
        return;
    }
    snprintf(buf, len, "%.*f", dec, v);
    if (strchr(buf, '.')) { /* drop trailing zeros (and a bare point) */
        e = buf + strlen(buf) - 1;
        while (*e == '0') *e-- = 0;
        if (*e == '.') *e = 0;
    }
    if (!strcmp(buf, "-0")) strcpy(buf, "0");
}

static char *dup_str(const char *s, size_t n)
{
    char *d = malloc(n + 1);
    if (d) {
        memcpy(d, s, n);
        d[n] = 0;
    }
    return d;
}

/* Splits a list at the commas outside quotes and brackets. */
static int split_list(sw_key *k, const char *s, char *msg, size_t len)
{
    const char *p = s, *start = s;
    int depth = 0;
    char q = 0;
    long cap = 8;
    k->vals = malloc(sizeof(char *) * (size_t)cap);
    if (!k->vals) return -1;
    for (;; p++) {
        if (q) {
            if (*p == '\\' && q == '"' && p[1]) p++;
            else if (*p == q) q = 0;
            else if (!*p) break;
            continue;
        }
        if (*p == '"' || *p == '\'') q = *p;
        else if (*p == '[' || *p == '{') depth++;
        else if ((*p == ']' || *p == '}') && depth > 0) depth--;
        else if ((*p == ',' && depth == 0) || !*p) {
            if (p == start) {
                snprintf(msg, len, "--vary %s: an empty value in the list '%s'", k->key, s);
                return -1;
            }
            if (k->nval == cap) {
                char **nv = realloc(k->vals, sizeof(char *) * (size_t)(cap *= 2));
                if (!nv) return -1;
                k->vals = nv;
            }
            if (!(k->vals[k->nval++] = dup_str(start, (size_t)(p - start)))) return -1;
            if (!*p) return 0;
            start = p + 1;
        }
    }
    snprintf(msg, len, "--vary %s: an unterminated quote in '%s'", k->key, s);
    return -1;
}

/* KEY=SPEC into k. 0, or -1 with msg. */
static int parse_vary(sw_key *k, const char *arg, int lhs, char *msg, size_t len)
{
    const char *eq = strchr(arg, '=');
    const char *c1, *c2;
    memset(k, 0, sizeof *k);
    if (!eq || eq == arg || !eq[1]) {
        snprintf(msg, len, "--vary expects KEY=A:B:N or KEY=V1,V2,..., got '%s'", arg);
        return -1;
    }
    k->key = dup_str(arg, (size_t)(eq - arg));
    k->spec = dup_str(eq + 1, strlen(eq + 1));
    if (!k->key || !k->spec) return -1;
    /* a range: two or three numbers separated by ':' */
    c1 = strchr(k->spec, ':');
    c2 = c1 ? strchr(c1 + 1, ':') : NULL;
    if (c1 && !strchr(k->spec, ',') && !strchr(k->spec, '"') && (!c2 || !strchr(c2 + 1, ':'))) {
        char *a = dup_str(k->spec, (size_t)(c1 - k->spec));
        char *b = c2 ? dup_str(c1 + 1, (size_t)(c2 - c1 - 1)) : dup_str(c1 + 1, strlen(c1 + 1));
        long n = 0;
        int bad = !a || !b || cli_number(a, &k->a) || cli_number(b, &k->b);
        free(a);
        free(b);
        if (!bad && c2) bad = cli_count(c2 + 1, &n) || n < 1 || n > SW_MAX_VARIANTS;
        if (bad || (!c2 && !lhs)) {
            snprintf(msg, len,
                     "--vary %s: expected A:B:N (numbers A, B and a count N from 1 to %ld; A:B under --lhs), got '%s'",
                     k->key, SW_MAX_VARIANTS, k->spec);
            return -1;
        }
        k->is_range = 1;
        k->n = c2 ? n : 0; /* its values are made once the grid's size is known (grid_values) */
        return 0;
    }
    return split_list(k, k->spec, msg, len);
}

/* The n values of a range key of a grid. 0, or -1 (out of memory). */
static int grid_values(sw_key *k)
{
    long i, n = k->n;
    char buf[64];
    k->vals = malloc(sizeof(char *) * (size_t)n);
    if (!k->vals) return -1;
    for (i = 0; i < n; i++) {
        /* weights of both ends: exact at both, symmetric about the middle */
        double v = n == 1 ? k->a : i == n - 1 ? k->b : (k->a * (double)(n - 1 - i) + k->b * (double)i) / (double)(n - 1);
        fmt_grid(buf, sizeof buf, v, n > 1 ? (k->b - k->a) / (double)(n - 1) : 0);
        if (!(k->vals[k->nval++] = dup_str(buf, strlen(buf)))) return -1;
    }
    return 0;
}

/* splitmix64: the hypercube's random numbers, the same on every machine */
static unsigned long long sm64(unsigned long long *s)
{
    unsigned long long z = (*s += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}
static double u01(unsigned long long *s) { return (double)(sm64(s) >> 11) * (1.0 / 9007199254740992.0); }

/* The variants: the grid in C order (the first key slowest), or the Latin
 * hypercube (per key an independent permutation of the N strata, a uniform
 * point in each; a list key takes the value of its stratum). */
static int make_plan(sw_plan *p, char *msg, size_t len)
{
    long i;
    int k;
    char buf[64];
    if (!p->lhs) {
        /* the size first: no key's values are made for a grid too large */
        double nv = 1;
        for (k = 0; k < p->nkey; k++) nv *= (double)(p->key[k].is_range ? p->key[k].n : p->key[k].nval);
        if (nv > (double)SW_MAX_VARIANTS) {
            char b[CLI_NUM];
            snprintf(msg, len, "the grid has %s variants, more than %ld", cli_fmt_num(b, nv), SW_MAX_VARIANTS);
            return -1;
        }
        p->nvar = (long)nv;
        for (k = 0; k < p->nkey; k++)
            if (p->key[k].is_range && grid_values(&p->key[k]) != 0) return -1;
    } else
        p->nvar = p->lhs_n;
    p->val = calloc((size_t)(p->nvar * p->nkey + 1), sizeof(char *));
    if (!p->val) return -1;
    if (!p->lhs) {
        for (i = 0; i < p->nvar; i++) {
            long r = i;
            for (k = p->nkey - 1; k >= 0; k--) {
                const sw_key *K = &p->key[k];
                const char *v = K->vals[r % K->nval];
                r /= K->nval;
                if (!(p->val[i * p->nkey + k] = dup_str(v, strlen(v)))) return -1;
            }
        }
        return 0;
    }
    {
        unsigned long long s = p->seed;
        long *perm = malloc(sizeof(long) * (size_t)p->nvar);
        if (!perm) return -1;
        for (k = 0; k < p->nkey; k++) {
            const sw_key *K = &p->key[k];
            for (i = 0; i < p->nvar; i++) perm[i] = i;
            for (i = p->nvar - 1; i > 0; i--) { /* Fisher-Yates */
                long j = (long)(sm64(&s) % (unsigned long long)(i + 1)), t = perm[i];
                perm[i] = perm[j];
                perm[j] = t;
            }
            for (i = 0; i < p->nvar; i++) {
                double u = ((double)perm[i] + u01(&s)) / (double)p->nvar;
                const char *v;
                if (K->is_range) {
                    fmt_num(buf, sizeof buf, K->a + (K->b - K->a) * u);
                    v = buf;
                } else {
                    long j = (long)(u * (double)K->nval);
                    v = K->vals[j < K->nval ? j : K->nval - 1];
                }
                if (!(p->val[i * p->nkey + k] = dup_str(v, strlen(v)))) {
                    free(perm);
                    return -1;
                }
            }
        }
        free(perm);
    }
    return 0;
}

static void free_plan(sw_plan *p)
{
    long i;
    int k;
    for (k = 0; k < p->nkey; k++) {
        for (i = 0; i < p->key[k].nval; i++) free(p->key[k].vals[i]);
        free(p->key[k].vals);
        free(p->key[k].key);
        free(p->key[k].spec);
    }
    if (p->val)
        for (i = 0; i < p->nvar * p->nkey; i++) free(p->val[i]);
    free(p->val);
}

long sw_region(const sw_plan *p, const sw_result *res, double length, double *area, long *ncap, char *label)
{
    int k, kx = -1, ky = -1;
    long nslice = 1, i, s, stride[SW_MAX_KEYS];
    double cell, L = length > 0 ? length : 1.0;
    if (p->lhs) return 0;
    for (k = 0; k < p->nkey; k++)
        if (p->key[k].is_range && p->key[k].nval >= 2) {
            if (kx < 0) kx = k;
            else if (ky < 0) ky = k;
        }
    if (ky < 0) return 0;
    for (k = 0; k < p->nkey; k++)
        if (k != kx && k != ky) nslice *= p->key[k].nval;
    if (!area) return nslice;
    cell = fabs((p->key[kx].b - p->key[kx].a) / (double)(p->key[kx].nval - 1) * (p->key[ky].b - p->key[ky].a) /
                (double)(p->key[ky].nval - 1)) /
           (L * L);
    stride[p->nkey - 1] = 1;
    for (k = p->nkey - 2; k >= 0; k--) stride[k] = stride[k + 1] * p->key[k + 1].nval;
    for (s = 0; s < nslice; s++) ncap[s] = 0;
    for (i = 0; i < p->nvar; i++) {
        long sl = 0;
        for (k = 0; k < p->nkey; k++)
            if (k != kx && k != ky) sl = sl * p->key[k].nval + (i / stride[k]) % p->key[k].nval;
        if (res[i].status == 0 && res[i].verdict == CD_VERDICT_CAPTURED) ncap[sl]++;
    }
    for (s = 0; s < nslice; s++) {
        long r = s;
        char *lab = label + s * SW_LABEL;
        size_t used = 0;
        int first = 1;
        lab[0] = 0;
        area[s] = (double)ncap[s] * cell;
        /* "key=value key=value" of the slice (the plane keys excluded) */
        {
            long idx[SW_MAX_KEYS];
            for (k = p->nkey - 1; k >= 0; k--) {
                if (k == kx || k == ky) continue;
                idx[k] = r % p->key[k].nval;
                r /= p->key[k].nval;
            }
            for (k = 0; k < p->nkey; k++) {
                int w;
                if (k == kx || k == ky) continue;
                w = snprintf(lab + used, SW_LABEL - used, "%s%s=%s", first ? "" : " ", p->key[k].key,
                             p->key[k].vals[idx[k]]);
                if (w < 0 || (size_t)w >= SW_LABEL - used) break;
                used += (size_t)w;
                first = 0;
            }
        }
        if (first) snprintf(lab, SW_LABEL, "all");
    }
    return nslice;
}

/* ---- one variant ---------------------------------------------------------- */

typedef struct {
    const sw_opts *o;
    const sw_plan *p;
    sw_out *out;    /* the summary (rank 0 / the parent only) */
} sw_ctx;

static void run_variant(const sw_ctx *cx, long idx, sw_result *r)
{
    const sw_plan *p = cx->p;
    int nov = cx->o->nsets + p->nkey, k, have_mon = 0;
    const char **ov = malloc(sizeof(char *) * (size_t)(nov + 1));
    char **own = calloc((size_t)p->nkey + 1, sizeof(char *));
    cd_scenario *sc = NULL;
    cd_data *d = NULL;
    cd_h5_writer *w = NULL;
    cd_monitor mon;
    cd_error err;
    run_ctx ctx;
    cd_status st;
    cd_ctrl *ctl = NULL;
    cd_ctrl_merit merit;
    char wmsg[512], path[4096];
    double t0 = cli_wall();
    sw_result_blank(r, idx);
    memset(&ctx, 0, sizeof ctx);
    if (!ov || !own) {
        r->status = CD_ENOMEM;
        snprintf(r->reason, sizeof r->reason, "out of memory");
        goto out;
    }
    for (k = 0; k < cx->o->nsets; k++) ov[k] = cx->o->sets[k];
    for (k = 0; k < p->nkey; k++) {
        const char *v = p->val[idx * p->nkey + k];
        own[k] = malloc(strlen(p->key[k].key) + strlen(v) + 2);
        if (!own[k]) {
            r->status = CD_ENOMEM;
            snprintf(r->reason, sizeof r->reason, "out of memory");
            goto out;
        }
        sprintf(own[k], "%s=%s", p->key[k].key, v);
        ov[cx->o->nsets + k] = own[k];
    }
    sc = cd_scenario_load(cx->o->scenario, ov, nov, &err);
    if (!sc) {
        r->status = SW_ELOAD;
        snprintf(r->reason, sizeof r->reason, "%s", err.msg);
        goto out;
    }
    if (!(sc->duration > 0) || !(sc->output_dt > 0) || !isfinite(sc->duration) ||
        !(sc->duration / sc->output_dt <= 1e9)) {
        r->status = SW_ELOAD;
        snprintf(r->reason, sizeof r->reason, "duration and output_dt must be positive, at most 1e9 samples");
        goto out;
    }
    d = cd_data_create(sc->model, sc->event_capacity, &err);
    if (!d) {
        r->status = err.status ? (int)err.status : CD_ENOMEM;
        snprintf(r->reason, sizeof r->reason, "%s", err.msg);
        goto out;
    }
    /* the scenario's built-in controller ([control], docs/capture.md), as capdyn run */
    if (sc->control) {
        ctl = cd_ctrl_create(sc->model, sc->control, &err);
        if (!ctl) {
            r->status = SW_ELOAD;
            snprintf(r->reason, sizeof r->reason, "%s", err.msg);
            goto out;
        }
        cd_ctrl_install(ctl, d);
    }
    if (cx->o->keep_dir) {
        snprintf(path, sizeof path, "%s/variant_%06ld.h5", cx->o->keep_dir, idx);
        w = cd_h5_create(path, sc->model, sc, &err);
        if (!w) {
            r->status = CD_EIO;
            snprintf(r->reason, sizeof r->reason, "%s", err.msg);
            goto out;
        }
    }
    ctx.fn_max = calloc((size_t)(sc->model->nslot ? sc->model->nslot : 1), sizeof(double));
    ctx.ft_max = calloc((size_t)(sc->model->nslot ? sc->model->nslot : 1), sizeof(double));
    ctx.t_end = sc->duration;
    ctx.wall0 = t0;
    ctx.last_draw = -1e300;
    ctx.max_wall = sc->max_wall_time;
    ctx.max_rhs = sc->max_rhs_evals;
    ctx.until_verdict = cx->o->until_verdict;
    ctx.ctl = ctl;
    ctx.merit = ctl ? &merit : NULL;
    if (!ctx.fn_max || !ctx.ft_max) {
        r->status = CD_ENOMEM;
        snprintf(r->reason, sizeof r->reason, "out of memory");
        goto out;
    }
    have_mon = sc->capture_hand >= 0 && sc->capture_object >= 0;
    if (have_mon) {
        cd_monitor_opts mop = cd_scenario_monitor_opts(sc);
        if (cd_monitor_init(&mon, sc->model, d, &mop, &err) != CD_OK) {
            r->status = err.status;
            snprintf(r->reason, sizeof r->reason, "%s", err.msg);
            goto out;
        }
        cd_monitor_update(&mon, sc->model, d);
    }
    st = cli_run_loop(sc, d, w, have_mon ? &mon : NULL, &ctx, &err, wmsg, sizeof wmsg);
    r->status = (int)st;
    if (st != CD_OK) snprintf(r->reason, sizeof r->reason, "%s", err.msg);
    r->t_final = d->t;
    r->nrhs = d->stats.nrhs;
    r->nsteps = d->stats.nsteps;
    r->nevents = d->ev_count;
    r->fn_step_max = 0;
    for (k = 0; k < sc->model->nslot; k++)
        if (ctx.fn_max[k] > r->fn_step_max) r->fn_step_max = ctx.fn_max[k];
    if (have_mon) {
        cd_h5_capture cap;
        cli_capture_of(&mon, ctl, ctl ? &merit : NULL, sc->model, d, &cap);
        r->verdict = (int)mon.verdict;
        r->t_capture = mon.t_capture;
        r->t_escape = mon.t_escape;
        r->peak_fn = cap.peak_fn;
        r->peak_tau = cap.peak_tau;
        r->epsilon = cap.epsilon;
        memcpy(r->offset, cap.offset, sizeof r->offset);
        r->n_stick = cap.n_stick;
        r->n_slip = cap.n_slip;
        if (w) cd_h5_set_capture(w, &cap);
    }
    if (w) {
        cd_error cerr;
        char msg[SW_REASON + 64];
        if (st == CD_OK) snprintf(msg, sizeof msg, "finished at t = %.9g s", d->t);
        else snprintf(msg, sizeof msg, "%s", r->reason);
        if (cd_h5_close(w, sc->model, d, st, msg, &cerr) != CD_OK && r->status == CD_OK) {
            r->status = CD_EIO;
            snprintf(r->reason, sizeof r->reason, "%s", cerr.msg);
        }
        w = NULL;
    }
out:
    if (w) cd_h5_close(w, sc->model, d, (cd_status)r->status, r->reason, NULL);
    free(ctx.fn_max);
    free(ctx.ft_max);
    cd_data_free(d);
    cd_ctrl_free(ctl);
    cd_scenario_free(sc);
    if (own)
        for (k = 0; k < p->nkey; k++) free(own[k]);
    free(own);
    free(ov);
    r->wall = cli_wall() - t0;
}

/* ---- worker processes ----------------------------------------------------- */

static int write_full(int fd, const void *buf, size_t n)
{
    const char *p = buf;
    while (n > 0) {
        ssize_t w = write(fd, p, n);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) return -1;
        p += w;
        n -= (size_t)w;
    }
    return 0;
}
/* 1 read, 0 end of file, -1 error */
static int read_full(int fd, void *buf, size_t n)
{
    char *p = buf;
    size_t got = 0;
    while (got < n) {
        ssize_t r = read(fd, p + got, n - got);
        if (r < 0 && errno == EINTR) continue;
        if (r < 0) return -1;
        if (r == 0) return got == 0 ? 0 : -1;
        got += (size_t)r;
    }
    return 1;
}

typedef struct {
    pid_t pid;
    int task_fd, res_fd; /* parent's ends */
    long busy;           /* variant being run, -1 idle */
} sw_worker;

static void worker_loop(const sw_ctx *cx, int task_fd, int res_fd)
{
    long idx;
    sw_result r;
    /* the parent decides about SIGINT (the terminal sends it to the whole
     * group); SIGTERM from the parent ends the worker */
    signal(SIGINT, SIG_IGN);
    signal(SIGTERM, SIG_DFL);
    signal(SIGPIPE, SIG_DFL);
    while (read_full(task_fd, &idx, sizeof idx) == 1 && idx >= 0) {
        run_variant(cx, idx, &r);
        if (write_full(res_fd, &r, sizeof r) != 0) break;
    }
    _exit(0);
}

static int spawn_worker(const sw_ctx *cx, sw_worker *wk, sw_worker *all, int nall)
{
    int tp[2], rp[2], i;
    if (pipe(tp) != 0) return -1;
    if (pipe(rp) != 0) {
        close(tp[0]);
        close(tp[1]);
        return -1;
    }
    fflush(NULL);
    wk->pid = fork();
    if (wk->pid < 0) {
        close(tp[0]);
        close(tp[1]);
        close(rp[0]);
        close(rp[1]);
        return -1;
    }
    if (wk->pid == 0) {
        for (i = 0; i < nall; i++) /* the other workers' pipes */
            if (&all[i] != wk && all[i].pid > 0) {
                close(all[i].task_fd);
                close(all[i].res_fd);
            }
        close(tp[1]);
        close(rp[0]);
        worker_loop(cx, tp[0], rp[1]);
    }
    close(tp[0]);
    close(rp[1]);
    wk->task_fd = tp[1];
    wk->res_fd = rp[0];
    wk->busy = -1;
    return 0;
}

static void stop_worker(sw_worker *wk, int kill_it)
{
    int st;
    if (wk->pid <= 0) return;
    if (kill_it) kill(wk->pid, SIGTERM);
    close(wk->task_fd);
    close(wk->res_fd);
    while (waitpid(wk->pid, &st, 0) < 0 && errno == EINTR) {
    }
    wk->pid = -1;
}

/* ---- progress ------------------------------------------------------------- */

typedef struct {
    int on, drawn;
    double t0, last;
    long total, done0; /* done0: finished before this invocation (resume) */
} sw_progress;

static void fmt_dur(char *b, size_t n, double s)
{
    if (!(s >= 0) || s > 1e8) snprintf(b, n, "?");
    else if (s < 60) snprintf(b, n, "%.0fs", s);
    else if (s < 3600) snprintf(b, n, "%dm%02ds", (int)(s / 60), (int)fmod(s, 60));
    else snprintf(b, n, "%dh%02dm", (int)(s / 3600), (int)fmod(s / 60, 60));
}

static void draw(sw_progress *pg, long done, long failed, int force)
{
    char bar[31], eta[32];
    double now = cli_wall(), rate, f;
    int i, nf;
    if (!pg->on || (!force && now - pg->last < 0.2)) return;
    f = pg->total ? (double)done / (double)pg->total : 1;
    nf = (int)(f * 30);
    for (i = 0; i < 30; i++) bar[i] = i < nf ? '#' : '.';
    bar[30] = 0;
    rate = now > pg->t0 ? (double)(done - pg->done0) / (now - pg->t0) : 0;
    fmt_dur(eta, sizeof eta, rate > 0 ? (double)(pg->total - done) / rate : -1);
    fprintf(stderr, "\r[%s] %ld/%ld variants  %ld failed  %.2f/s  ETA %s ", bar, done, pg->total, failed, rate, eta);
    fflush(stderr);
    pg->drawn = 1;
    pg->last = now;
}

static void clear(sw_progress *pg)
{
    if (pg->drawn) fputs("\r\033[K", stderr);
    pg->drawn = 0;
}

/* ---- the sweep ------------------------------------------------------------ */

static int parse(int argc, char **argv, sw_opts *o)
{
    int i, only = 0;
    memset(o, 0, sizeof *o);
    o->seed = 1;
    o->sets = calloc((size_t)argc + 1, sizeof *o->sets);
    if (!o->sets) {
        cli_error("out of memory");
        return CLI_FAIL;
    }
#define VAL(name) (i + 1 < argc ? argv[++i] : NULL)
    for (i = 1; i < argc; i++) {
        const char *a = argv[i], *v;
        if (!only && a[0] == '-' && a[1]) {
            if (!strcmp(a, "--")) { only = 1; continue; }
            if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
                fputs(sweep_help, stdout);
                return -1;
            }
            if (!strcmp(a, "--set")) {
                if (!(v = VAL(a)) || !strchr(v, '=') || v[0] == '=')
                    return cli_usage("sweep", "--set expects KEY=VALUE, got '%s'", v ? v : "");
                o->sets[o->nsets++] = v;
            } else if (!strcmp(a, "--vary")) {
                if (!(v = VAL(a))) return cli_usage("sweep", "--vary needs KEY=SPEC");
                if (o->nvary == SW_MAX_KEYS) return cli_usage("sweep", "at most %d --vary keys", SW_MAX_KEYS);
                o->vary[o->nvary++] = v;
            } else if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
                if (!(v = VAL(a)) || !*v) return cli_usage("sweep", "%s needs a file name", a);
                o->output = v;
            } else if (!strcmp(a, "--keep-runs")) {
                if (!(v = VAL(a)) || !*v) return cli_usage("sweep", "--keep-runs needs a directory");
                o->keep_dir = v;
            } else if (!strcmp(a, "--table")) {
                if (!(v = VAL(a)) || !*v) return cli_usage("sweep", "--table needs a summary file");
                o->table = v;
            } else if (!strcmp(a, "--lhs")) {
                if (!(v = VAL(a)) || cli_count(v, &o->lhs) || o->lhs < 1 || o->lhs > SW_MAX_VARIANTS)
                    return cli_usage("sweep", "--lhs expects a number of variants from 1 to %ld, got '%s'",
                                     SW_MAX_VARIANTS, v ? v : "");
            } else if (!strcmp(a, "--seed")) {
                long s;
                if (!(v = VAL(a)) || cli_count(v, &s))
                    return cli_usage("sweep", "--seed expects a non-negative integer, got '%s'", v ? v : "");
                o->seed = (unsigned long long)s;
            } else if (!strcmp(a, "-j") || !strcmp(a, "--jobs")) {
                if (!(v = VAL(a)) || cli_count(v, &o->jobs) || o->jobs < 1 || o->jobs > SW_MAX_JOBS)
                    return cli_usage("sweep", "%s expects a number of processes from 1 to %d, got '%s'", a,
                                     SW_MAX_JOBS, v ? v : "");
                o->have_jobs = 1;
            } else if (!strcmp(a, "--length")) {
                if (!(v = VAL(a)) || cli_number(v, &o->length) || !(o->length > 0))
                    return cli_usage("sweep", "--length expects a positive length in metres, got '%s'", v ? v : "");
            } else if (!strcmp(a, "--until-verdict")) {
                o->until_verdict = 1;
            } else if (!strcmp(a, "--resume")) {
                o->resume = 1;
            } else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
                o->quiet = 1;
            } else
                return cli_usage("sweep", "unknown option '%s'", a);
            continue;
        }
        if (o->scenario) return cli_usage("sweep", "unexpected argument '%s' (one scenario per sweep)", a);
        o->scenario = a;
    }
#undef VAL
    if (o->table) return 0;
    if (!o->scenario) return cli_usage("sweep", "missing the scenario file");
    if (o->nvary == 0) return cli_usage("sweep", "nothing to vary: give 1 to %d --vary KEY=SPEC", SW_MAX_KEYS);
    return 0;
}

/* The overrides of every variant, one per line (stored in the summary). */
static char *join_sets(const sw_opts *o)
{
    size_t n = 1;
    int i;
    char *s;
    for (i = 0; i < o->nsets; i++) n += strlen(o->sets[i]) + 1;
    s = malloc(n);
    if (!s) return NULL;
    s[0] = 0;
    for (i = 0; i < o->nsets; i++) {
        strcat(s, o->sets[i]);
        if (i + 1 < o->nsets) strcat(s, "\n");
    }
    return s;
}

/* Runs the variants not yet run (res[i].status == SW_NOT_RUN) on nj worker
 * processes; writes checkpoints. Returns 0, or the signal that stopped it. */
static int run_local(const sw_ctx *cx, const sw_meta *meta, sw_result *res, int nj, sw_progress *pg, long *ndone,
                     long *nfail, double wall0)
{
    const sw_plan *p = cx->p;
    sw_worker *wk = calloc((size_t)nj, sizeof *wk);
    struct pollfd *pf = calloc((size_t)nj, sizeof *pf);
    long next = 0, inflight = 0, i;
    double last_ckpt = cli_wall();
    int j, stopped = 0;
    char msg[1024];
    if (!wk || !pf) {
        free(wk);
        free(pf);
        cli_error("out of memory");
        return -1;
    }
    for (j = 0; j < nj; j++) { /* no process, no variant: stop_worker and the clean-up below skip it */
        wk[j].pid = -1;
        wk[j].busy = -1;
    }
    for (;;) {
        /* hand out work: one variant per idle worker */
        for (j = 0; j < nj && !g_stop; j++) {
            while (next < p->nvar && res[next].status != SW_NOT_RUN) next++;
            if (next >= p->nvar) break;
            if (wk[j].pid <= 0 && spawn_worker(cx, &wk[j], wk, nj) != 0) {
                cli_error("cannot start a worker process: %s", strerror(errno));
                g_stop = -1;
                break;
            }
            if (wk[j].busy >= 0) continue;
            if (write_full(wk[j].task_fd, &next, sizeof next) != 0) {
                stop_worker(&wk[j], 1); /* respawned above next time */
                continue;
            }
            wk[j].busy = next++;
            inflight++;
        }
        if (inflight == 0 || g_stop) break;
        for (j = 0; j < nj; j++) {
            pf[j].fd = wk[j].busy >= 0 ? wk[j].res_fd : -1;
            pf[j].events = POLLIN;
            pf[j].revents = 0;
        }
        if (poll(pf, (nfds_t)nj, 200) < 0 && errno != EINTR) {
            cli_error("poll: %s", strerror(errno));
            g_stop = -1;
            break;
        }
        for (j = 0; j < nj; j++) {
            sw_result r;
            int rr;
            if (wk[j].busy < 0 || !(pf[j].revents & (POLLIN | POLLHUP | POLLERR))) continue;
            rr = read_full(wk[j].res_fd, &r, sizeof r);
            if (rr == 1 && r.index == wk[j].busy) {
                res[r.index] = r;
            } else { /* the worker died running it */
                int st = 0;
                long idx = wk[j].busy;
                kill(wk[j].pid, SIGKILL);
                close(wk[j].task_fd);
                close(wk[j].res_fd);
                while (waitpid(wk[j].pid, &st, 0) < 0 && errno == EINTR) {
                }
                wk[j].pid = -1;
                sw_result_blank(&res[idx], idx);
                res[idx].status = SW_ECRASH;
                if (WIFSIGNALED(st))
                    snprintf(res[idx].reason, sizeof res[idx].reason, "the worker process died: %s (signal %d)",
                             strsignal(WTERMSIG(st)), WTERMSIG(st));
                else
                    snprintf(res[idx].reason, sizeof res[idx].reason, "the worker process ended without a result");
                res[idx].wall = NAN;
            }
            if (res[wk[j].busy].status != 0) (*nfail)++;
            wk[j].busy = -1;
            inflight--;
            (*ndone)++;
        }
        draw(pg, *ndone, *nfail, 0);
        if (cli_wall() - last_ckpt >= SW_CHECKPOINT) {
            if (sw_summary_write(cx->out, meta, p, res, nj, cli_wall() - wall0, msg, sizeof msg) != 0)
                cli_error("%s", msg);
            last_ckpt = cli_wall();
        }
    }
    stopped = g_stop;
    for (j = 0; j < nj; j++) {
        if (wk[j].busy >= 0) { /* interrupted: not run */
            sw_result_blank(&res[wk[j].busy], wk[j].busy);
        }
        stop_worker(&wk[j], wk[j].busy >= 0 || stopped);
    }
    (void)i;
    free(wk);
    free(pf);
    return stopped;
}

#ifdef CAPDYN_MPI
/* ---- MPI (make MPI=1) ------------------------------------------------------ */

#define SW_TAG_TASK 1
#define SW_TAG_RESULT 2

/* Started by an MPI launcher (Open MPI's mpirun, PMI/PMIx: Slurm's srun)? */
static int under_mpi(void)
{
    return getenv("OMPI_COMM_WORLD_SIZE") || getenv("PMI_SIZE") || getenv("PMIX_RANK") || getenv("PMI_RANK");
}

static void mpi_worker(const sw_ctx *cx)
{
    long idx;
    sw_result r;
    /* rank 0 decides (a launcher or Slurm's time limit signals every rank):
     * it writes the summary, then aborts the job */
    signal(SIGINT, SIG_IGN);
    signal(SIGTERM, SIG_IGN);
    for (;;) {
        MPI_Recv(&idx, 1, MPI_LONG, 0, SW_TAG_TASK, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        if (idx < 0) break;
        run_variant(cx, idx, &r);
        MPI_Send(&r, (int)sizeof r, MPI_BYTE, 0, SW_TAG_RESULT, MPI_COMM_WORLD);
    }
}

/* Rank 0: one variant at a time to each idle rank (dynamic distribution),
 * results stored by index; checkpoints as run_local. */
static int run_mpi(const sw_ctx *cx, const sw_meta *meta, sw_result *res, int size, sw_progress *pg, long *ndone,
                   long *nfail, double wall0)
{
    const sw_plan *p = cx->p;
    long next = 0, stop = -1, *busy = malloc(sizeof(long) * (size_t)size);
    int inflight = 0, r;
    double last_ckpt = cli_wall();
    char msg[1024];
    if (!busy) {
        cli_error("out of memory");
        MPI_Abort(MPI_COMM_WORLD, CLI_FAIL);
    }
    for (r = 1; r < size; r++) {
        while (next < p->nvar && res[next].status != SW_NOT_RUN) next++;
        busy[r] = next < p->nvar ? next++ : -1;
        if (busy[r] >= 0) inflight++;
        MPI_Send(busy[r] >= 0 ? &busy[r] : &stop, 1, MPI_LONG, r, SW_TAG_TASK, MPI_COMM_WORLD);
    }
    while (inflight > 0 && !g_stop) {
        int flag = 0;
        MPI_Status st;
        sw_result x;
        MPI_Iprobe(MPI_ANY_SOURCE, SW_TAG_RESULT, MPI_COMM_WORLD, &flag, &st);
        if (!flag) {
            struct timespec ts = {0, 5000000L};
            nanosleep(&ts, NULL);
        } else {
            r = st.MPI_SOURCE;
            MPI_Recv(&x, (int)sizeof x, MPI_BYTE, r, SW_TAG_RESULT, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
            if (x.index >= 0 && x.index < p->nvar) res[x.index] = x;
            if (x.status != 0) (*nfail)++;
            (*ndone)++;
            inflight--;
            while (next < p->nvar && res[next].status != SW_NOT_RUN) next++;
            busy[r] = next < p->nvar ? next++ : -1;
            if (busy[r] >= 0) inflight++;
            MPI_Send(busy[r] >= 0 ? &busy[r] : &stop, 1, MPI_LONG, r, SW_TAG_TASK, MPI_COMM_WORLD);
        }
        draw(pg, *ndone, *nfail, 0);
        if (cli_wall() - last_ckpt >= SW_CHECKPOINT) {
            if (sw_summary_write(cx->out, meta, p, res, size, cli_wall() - wall0, msg, sizeof msg) != 0)
                cli_error("%s", msg);
            last_ckpt = cli_wall();
        }
    }
    if (g_stop) /* the variants still running are not run; MPI_Abort ends them after the summary */
        for (r = 1; r < size; r++)
            if (busy[r] >= 0) sw_result_blank(&res[busy[r]], busy[r]);
    free(busy);
    return g_stop;
}
#endif

static int sweep_main(int argc, char **argv, int rank, int size)
{
    sw_opts o;
    sw_plan p;
    sw_meta meta;
    sw_ctx cx;
    sw_out out;
    sw_result *res = NULL;
    sw_progress pg;
    cd_scenario *sc = NULL;
    cd_error err;
    char msg[2048], outbuf[1024];
    int rc, k, nj, stopped, exitc = CLI_OK, bcast_done = 0;
    long i, ndone = 0, nfail = 0, nrun0 = 0, counts[3] = {0, 0, 0};
    char *overrides = NULL;
    double wall0 = cli_wall(), wall;
    struct sigaction sa, old_int, old_term, old_pipe;

    memset(&p, 0, sizeof p);
    memset(&out, 0, sizeof out);
    out.lock_fd = -1;
    cx.o = &o;
    cx.p = &p;
    cx.out = &out;
    /* every rank parses the same command line and makes the same plan; only
     * rank 0 says what is wrong with it */
    {
        int saved = -1, nul;
        if (rank > 0 && (nul = open("/dev/null", O_WRONLY)) >= 0) {
            fflush(stderr);
            saved = dup(STDERR_FILENO);
            dup2(nul, STDERR_FILENO);
            close(nul);
        }
        rc = parse(argc, argv, &o);
        if (saved >= 0) {
            fflush(stderr);
            dup2(saved, STDERR_FILENO);
            close(saved);
        }
    }
    if (rc) {
        free(o.sets);
        return rc < 0 ? CLI_OK : rc;
    }
    if (o.table) {
        free(o.sets);
        return sw_summary_table(o.table);
    }
    if (!o.output) {
        const char *b = strrchr(o.scenario, '/');
        size_t n;
        b = b ? b + 1 : o.scenario;
        n = strlen(b);
        if (n > 5 && !strcmp(b + n - 5, ".toml")) n -= 5;
        snprintf(outbuf, sizeof outbuf, "%.*s_sweep.h5", (int)n, b);
        o.output = outbuf;
    }
    p.lhs = o.lhs > 0;
    p.lhs_n = o.lhs;
    p.seed = o.seed;
    for (k = 0; k < o.nvary; k++) {
        int j;
        if (parse_vary(&p.key[p.nkey], o.vary[k], p.lhs, msg, sizeof msg) != 0) {
            p.nkey++;
            free_plan(&p);
            free(o.sets);
            return msg[0] ? cli_usage("sweep", "%s", msg) : (cli_error("out of memory"), CLI_FAIL);
        }
        p.nkey++;
        for (j = 0; j < k; j++)
            if (!strcmp(p.key[j].key, p.key[k].key)) {
                free_plan(&p);
                free(o.sets);
                return cli_usage("sweep", "--vary %s is given twice", o.vary[k]);
            }
    }
    msg[0] = 0;
    if (make_plan(&p, msg, sizeof msg) != 0) {
        if (msg[0]) cli_error("%s", msg);
        else cli_error("out of memory");
        free_plan(&p);
        free(o.sets);
        return CLI_FAIL;
    }
#ifdef CAPDYN_MPI
    if (rank > 0) { /* a worker rank: run what rank 0 hands out, once it has checked the sweep */
        int ok = 0;
        MPI_Bcast(&ok, 1, MPI_INT, 0, MPI_COMM_WORLD);
        if (ok) mpi_worker(&cx);
        free_plan(&p);
        free(o.sets);
        return ok ? CLI_OK : CLI_FAIL;
    }
#endif
    /* the base scenario (its text goes into the summary), then the first
     * variant: a misspelt key stops here, not in every variant */
    sc = cd_scenario_load(o.scenario, o.sets, o.nsets, &err);
    if (!sc) {
        cli_error("%s", err.msg);
        exitc = CLI_FAIL;
        goto out;
    }
    /* SIGXFSZ (file size limit, ulimit -f) would kill the sweep in the middle
     * of a write and leave its temporary file: ignored, the write fails
     * with EFBIG and is reported (workers inherit this, as capdyn run) */
    signal(SIGXFSZ, SIG_IGN);
    /* the summary: never the scenario, a file another process writes or a
     * non-regular file (checked again, under a lock, at every write) */
    {
        const char *in[1];
        in[0] = o.scenario;
        if (sw_out_open(&out, o.output, in, 1, msg, sizeof msg) != 0) {
            cli_error("%s", msg);
            exitc = CLI_FAIL;
            goto out;
        }
    }
    {
        const char **ov = malloc(sizeof(char *) * (size_t)(o.nsets + p.nkey + 1));
        char **own = calloc((size_t)p.nkey + 1, sizeof(char *));
        cd_scenario *s0 = NULL;
        int ok = ov && own;
        for (k = 0; ok && k < o.nsets; k++) ov[k] = o.sets[k];
        for (k = 0; ok && k < p.nkey; k++) {
            own[k] = malloc(strlen(p.key[k].key) + strlen(p.val[k]) + 2);
            if (!own[k]) ok = 0;
            else sprintf(own[k], "%s=%s", p.key[k].key, p.val[k]);
            ov[o.nsets + k] = own[k];
        }
        if (ok) s0 = cd_scenario_load(o.scenario, ov, o.nsets + p.nkey, &err);
        else snprintf(err.msg, sizeof err.msg, "out of memory");
        for (k = 0; own && k < p.nkey; k++) free(own[k]);
        free(own);
        free(ov);
        if (!s0) {
            cli_error("%s (the first variant)", err.msg);
            exitc = CLI_FAIL;
            goto out;
        }
        cd_scenario_free(s0);
    }
    overrides = join_sets(&o);
    res = malloc(sizeof *res * (size_t)p.nvar);
    if (!overrides || !res) {
        cli_error("out of memory");
        exitc = CLI_FAIL;
        goto out;
    }
    meta.scenario = o.scenario;
    meta.scenario_text = sc->text ? sc->text : "";
    meta.overrides = overrides;
    meta.length = o.length;
    meta.until_verdict = o.until_verdict;
    for (i = 0; i < p.nvar; i++) sw_result_blank(&res[i], i);
    if (o.resume) {
        if (sw_summary_resume(o.output, &meta, &p, res) != 0) {
            exitc = CLI_FAIL;
            goto out;
        }
        for (i = 0; i < p.nvar; i++)
            if (res[i].status != SW_NOT_RUN) {
                nrun0++;
                if (res[i].status != 0) nfail++;
            }
    }
    if (o.keep_dir && mkdir(o.keep_dir, 0777) != 0 && errno != EEXIST) {
        cli_error("--keep-runs: cannot create the directory '%s': %s", o.keep_dir, strerror(errno));
        exitc = CLI_FAIL;
        goto out;
    }
    /* the summary is written once before any work: an unwritable -o fails now */
    if (sw_summary_write(&out, &meta, &p, res, 0, 0, msg, sizeof msg) != 0) {
        cli_error("%s", msg);
        exitc = CLI_FAIL;
        goto out;
    }
#ifdef CAPDYN_MPI
    if (size > 1) { /* the worker ranks may start */
        int ok = 1;
        MPI_Bcast(&ok, 1, MPI_INT, 0, MPI_COMM_WORLD);
        bcast_done = 1;
    }
#endif
    if (size > 1) nj = size;
    else if (o.have_jobs) nj = (int)o.jobs;
    else {
        long nc = sysconf(_SC_NPROCESSORS_ONLN);
        nj = nc > 0 ? (int)(nc < SW_MAX_JOBS ? nc : SW_MAX_JOBS) : 1;
    }
    if (size == 1 && nj > p.nvar - nrun0) nj = (int)(p.nvar - nrun0 > 0 ? p.nvar - nrun0 : 1);

    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old_int);
    sigaction(SIGTERM, &sa, &old_term);
    sa.sa_handler = SIG_IGN;
    sigaction(SIGPIPE, &sa, &old_pipe);
    g_stop = 0;

    memset(&pg, 0, sizeof pg);
    pg.on = !o.quiet && isatty(STDERR_FILENO);
    pg.t0 = cli_wall();
    pg.total = p.nvar;
    pg.done0 = nrun0;
    ndone = nrun0;
    draw(&pg, ndone, nfail, 1);
#ifdef CAPDYN_MPI
    if (size > 1) stopped = run_mpi(&cx, &meta, res, size, &pg, &ndone, &nfail, wall0);
    else
#endif
        stopped = run_local(&cx, &meta, res, nj, &pg, &ndone, &nfail, wall0);
    clear(&pg);
    wall = cli_wall() - wall0;
    sigaction(SIGINT, &old_int, NULL);
    sigaction(SIGTERM, &old_term, NULL);
    sigaction(SIGPIPE, &old_pipe, NULL);

    if (sw_summary_write(&out, &meta, &p, res, nj, wall, msg, sizeof msg) != 0) {
        cli_error("%s", msg);
        exitc = CLI_FAIL;
        goto out;
    }
    for (i = 0; i < p.nvar; i++)
        if (res[i].status == 0 && res[i].verdict >= 0 && res[i].verdict <= 2) counts[res[i].verdict]++;
    if (!o.quiet) {
        long nslice = sw_region(&p, res, o.length, NULL, NULL, NULL), s;
        printf("sweep: %ld of %ld variants run (%ld failed), %ld in %.2f s (%.3g variants/s, -j %d); captured %ld, "
               "escaped %ld, unresolved %ld; summary '%s'\n",
               ndone, p.nvar, nfail, ndone - nrun0, wall, wall > 0 ? (double)(ndone - nrun0) / wall : 0.0, nj,
               counts[CD_VERDICT_CAPTURED], counts[CD_VERDICT_ESCAPED], counts[CD_VERDICT_UNRESOLVED], o.output);
        if (nslice > 0) {
            double *area = malloc(sizeof(double) * (size_t)nslice);
            long *ncap = malloc(sizeof(long) * (size_t)nslice);
            char *lab = malloc((size_t)nslice * SW_LABEL);
            if (area && ncap && lab) {
                sw_region(&p, res, o.length, area, ncap, lab);
                for (s = 0; s < nslice; s++)
                    printf("region %s: %ld captured, area %.6g %s\n", lab + s * SW_LABEL, ncap[s], area[s],
                           o.length > 0 ? "(normalised by length^2)" : "m^2");
            }
            free(area);
            free(ncap);
            free(lab);
        }
        for (i = 0; i < p.nvar && nfail; i++)
            if (res[i].status != 0 && res[i].status != SW_NOT_RUN)
                printf("variant %ld failed: %s\n", i, res[i].reason);
    }
    if (stopped > 0) {
        fprintf(stderr, "capdyn: sweep stopped by %s: %ld of %ld variants in '%s'; continue with --resume\n",
                stopped == SIGINT ? "SIGINT" : "SIGTERM", ndone, p.nvar, o.output);
        exitc = CLI_INTERRUPT;
    } else if (stopped < 0)
        exitc = CLI_FAIL;
out:
#ifdef CAPDYN_MPI
    if (size > 1 && !bcast_done) { /* tell the worker ranks there is nothing to do */
        int ok = 0;
        MPI_Bcast(&ok, 1, MPI_INT, 0, MPI_COMM_WORLD);
    }
    /* stopped: the summary is written; end the ranks still running a variant */
    if (size > 1 && exitc == CLI_INTERRUPT) {
        fflush(NULL);
        MPI_Abort(MPI_COMM_WORLD, CLI_INTERRUPT);
    }
#endif
    (void)bcast_done;
    fflush(stdout);
    free(res);
    free(overrides);
    sw_out_close(&out);
    cd_scenario_free(sc);
    free_plan(&p);
    free(o.sets);
    return exitc;
}

/* Under an MPI launcher (mpirun, srun) in a build with MPI (make MPI=1),
 * rank 0 hands out the variants and writes the summary, the other ranks run
 * them; elsewhere, worker processes on this machine (docs/sweep.md). */
int cmd_sweep(int argc, char **argv)
{
#ifdef CAPDYN_MPI
    if (under_mpi()) {
        int rank = 0, size = 1, rc;
        MPI_Init(&argc, &argv);
        MPI_Comm_rank(MPI_COMM_WORLD, &rank);
        MPI_Comm_size(MPI_COMM_WORLD, &size);
        rc = sweep_main(argc, argv, rank, size);
        MPI_Finalize();
        return rc;
    }
#endif
    return sweep_main(argc, argv, 0, 1);
}
