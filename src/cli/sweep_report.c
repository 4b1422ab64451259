/* capdyn sweep: what it prints (docs/sweep.md): the progress bar on
 * stderr, the end-of-sweep report, and a summary as columns (--table).
 * Numbers without a stated precision are printed in the shortest form that
 * reads back as the same double (cli_fmt_num). */
#define _POSIX_C_SOURCE 200809L
#include "sweep.h"
#include "capdyn/verdict.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---- progress ------------------------------------------------------------- */

static void fmt_dur(char *b, size_t n, double s)
{
    if (!(s >= 0) || s > 1e8) snprintf(b, n, "?");
    else if (s < 60) snprintf(b, n, "%.0fs", s);
    else if (s < 3600) snprintf(b, n, "%dm%02ds", (int)(s / 60), (int)fmod(s, 60));
    else snprintf(b, n, "%dh%02dm", (int)(s / 3600), (int)fmod(s / 60, 60));
}

void sw_draw(sw_progress *pg, long done, long failed, int force)
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

void sw_clear(sw_progress *pg)
{
    if (pg->drawn) fputs("\r\033[K", stderr);
    pg->drawn = 0;
}

/* ---- the end of a sweep ---------------------------------------------------- */

void sw_report_end(const sw_opts *o, const sw_plan *p, const sw_result *res, long ndone, long nfail, long nrun0,
                   double wall, int nj)
{
    long counts[4] = {0, 0, 0, 0}, i, s, nslice = sw_region(p, res, o->length, NULL, NULL, NULL);
    for (i = 0; i < p->nvar; i++)
        if (res[i].status == 0 && res[i].verdict >= 0 && res[i].verdict <= 3) counts[res[i].verdict]++;
    printf("sweep: %ld of %ld variants run (%ld failed), %ld in %.2f s (%.3g variants/s, -j %d); captured %ld, "
           "caged %ld, escaped %ld, unresolved %ld; summary '%s'\n",
           ndone, p->nvar, nfail, ndone - nrun0, wall, wall > 0 ? (double)(ndone - nrun0) / wall : 0.0, nj,
           counts[CD_VERDICT_CAPTURED], counts[CD_VERDICT_CAGED], counts[CD_VERDICT_ESCAPED], counts[CD_VERDICT_UNRESOLVED],
           o->output);
    if (nslice > 0) {
        double *area = malloc(sizeof(double) * (size_t)nslice);
        long *ncap = malloc(sizeof(long) * (size_t)nslice);
        char *lab = malloc((size_t)nslice * SW_LABEL), num[CLI_NUM];
        if (area && ncap && lab) {
            sw_region(p, res, o->length, area, ncap, lab);
            for (s = 0; s < nslice; s++)
                printf("region %s: %ld captured, area %s %s\n", lab + s * SW_LABEL, ncap[s], cli_fmt_num(num, area[s]),
                       o->length > 0 ? "(normalised by length^2)" : "m^2");
        }
        free(area);
        free(ncap);
        free(lab);
    }
    if (p->mc > 0) { /* the capture probability per grid cell */
        sw_cell *cell = malloc(sizeof *cell * (size_t)(p->ncell + 1));
        if (cell && sw_mc_cells(p, res, cell) == 0)
            for (s = 0; s < p->ncell && s < 100; s++) {
                int k;
                printf("cell %ld", s);
                for (k = 0; k < p->nvary; k++) printf(" %s=%s", p->key[k].key, p->val[s * p->mc * p->nkey + k]);
                printf(": captured %ld of %ld, p = %.4f, Wilson 95 %% [%.4f, %.4f]", cell[s].ncap, cell[s].n, cell[s].p,
                       cell[s].lo, cell[s].hi);
                if (cell[s].ncap > 0) printf("; capture time mean %.4g s, median %.4g s", cell[s].t_mean, cell[s].t_p50);
                printf("\n");
            }
        if (p->ncell > 100) printf("(%ld cells more in /mc of the summary)\n", p->ncell - 100);
        free(cell);
    }
    for (i = 0; i < p->nvar && nfail; i++)
        if (res[i].status != 0 && res[i].status != SW_NOT_RUN) printf("variant %ld failed: %s\n", i, res[i].reason);
}

/* ---- --table ----------------------------------------------------------------- */

/* a list value as a gnuplot word: quotes dropped, blanks as '_' */
static void put_word(FILE *out, const char *v)
{
    size_t n = strlen(v), i;
    if (n >= 2 && (v[0] == '"' || v[0] == '\'') && v[n - 1] == v[0]) {
        v++;
        n -= 2;
    }
    if (n == 0) fputs("\"\"", out);
    for (i = 0; i < n; i++) fputc(v[i] == ' ' || v[i] == '\t' ? '_' : v[i], out);
}

/* A Monte Carlo summary's table: one row per grid cell (the variants are
 * cell-major), the --vary values, then the counts and the probability. */
static void print_cells(const sw_summary *s, const char *path, FILE *out)
{
    sw_plan p;
    sw_cell *cell;
    long c, k;
    memset(&p, 0, sizeof p);
    p.mc = (long)s->mc;
    p.nvar = (long)s->nvar;
    p.ncell = p.nvar / p.mc;
    cell = malloc(sizeof *cell * (size_t)(p.ncell + 1));
    if (!cell || sw_mc_cells(&p, s->res, cell) != 0) {
        free(cell);
        fputs("# out of memory\n", out);
        return;
    }
    fprintf(out, "# capdyn sweep summary '%s': %ld cells x %lld draws (Monte Carlo)\n", path, p.ncell, s->mc);
    fputs("# cell", out);
    for (k = 0; k < s->nvary; k++) fprintf(out, " %s", s->names[k]);
    fputs(" n n_captured n_caged n_failed p_capture p_low p_high t_capture_mean peak_fn_mean epsilon_mean\n", out);
    fputs("# p_low, p_high: Wilson 95 %; n_caged: verdict code 3; NaN: no value\n", out);
    for (c = 0; c < p.ncell; c++) {
        const sw_cell *C = &cell[c];
        fprintf(out, "%ld", c);
        for (k = 0; k < s->nvary; k++) {
            fputc(' ', out);
            put_word(out, s->vals[c * p.mc * s->nkey + k]);
        }
        fprintf(out, " %ld %ld %ld %ld %.17g %.17g %.17g %.17g %.17g %.17g\n", C->n, C->ncap, C->nverdict[3], C->nfail,
                C->p, C->lo, C->hi, C->t_mean, C->f_mean, C->e_mean);
    }
    free(cell);
}

static void print_table(const sw_summary *s, const char *path, FILE *out)
{
    long i, k, n = (long)s->nvar, nk = s->nkey;
    size_t c;
    fprintf(out, "# capdyn sweep summary '%s': %ld variants\n", path, n);
    fputs("# length ", out);
    cli_put_num(out, s->length);
    fputs(" m (keys with \"position\" in their path / length in the *_norm columns; 0: not normalised)\n", out);
    for (i = 0; i < s->nslice; i++) {
        fprintf(out, "# region %s area ", s->slice[i]);
        cli_put_num(out, s->area[i]);
        fputc('\n', out);
    }
    fputs("# index", out);
    for (k = 0; k < nk; k++) fprintf(out, " %s", s->names[k]);
    for (k = 0; k < nk; k++) fprintf(out, " %s_norm", s->names[k]);
    fputs(" verdict status t_capture t_escape peak_fn peak_tau epsilon fn_step_max t_final t_cage\n", out);
    fputs("# verdict: 0 unresolved, 1 captured, 2 escaped, 3 caged, -1 none; status: 0 ok, -1 not run, else failed\n", out);
    for (i = 0; i < n; i++) {
        const sw_result *r = &s->res[i];
        fprintf(out, "%ld", i);
        for (k = 0; k < nk; k++) {
            fputc(' ', out);
            put_word(out, s->vals[i * nk + k]);
        }
        for (k = 0; k < nk; k++) {
            double v = s->num[i * nk + k];
            fputc(' ', out);
            if (isnan(v)) put_word(out, s->vals[i * nk + k]);
            else cli_put_num(out, s->length > 0 && strstr(s->names[k], "position") ? v / s->length : v);
        }
        fprintf(out, " %d %d", r->verdict, r->status);
        {
            /* t_cage last: scripts read the columns before it by number (plots/) */
            const double col[8] = {r->t_capture, r->t_escape, r->peak_fn, r->peak_tau, r->epsilon, r->fn_step_max,
                                   r->t_final, r->t_cage};
            for (c = 0; c < 8; c++) {
                fputc(' ', out);
                cli_put_num(out, col[c]);
            }
        }
        fputc('\n', out);
    }
}

static int table_child(void *arg)
{
    const char *path = arg;
    sw_summary s;
    char msg[2048];
    if (sw_summary_load(path, &s, msg, sizeof msg) != 0) {
        cli_error("%s", msg);
        return CLI_FAIL;
    }
    if (s.mc > 0 && s.nvar % s.mc == 0) print_cells(&s, path, stdout);
    else print_table(&s, path, stdout);
    sw_summary_free(&s);
    return CLI_OK;
}

int sw_summary_table(const char *path)
{
    char msg[1024];
    union {
        const char *c;
        void *v;
    } u;
    if (cli_regular_input(path, "sweep summary", msg, sizeof msg) != 0) {
        cli_error("%s", msg);
        return CLI_FAIL;
    }
    u.c = path;
    return cli_isolated(path, table_child, u.v);
}
