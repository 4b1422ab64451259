/* capdyn sweep --mc: the dispersions of a Monte Carlo sweep (docs/sweep.md,
 * "Monte Carlo"): parsing KEY=DIST, drawing each variant's values from its
 * own GSL stream, and the per-cell capture probability with its Wilson
 * interval and the figures of merit's means and percentiles. */
#define _POSIX_C_SOURCE 200809L
#include "sweep.h"
#include "capdyn/verdict.h"

#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>
#include <gsl/gsl_sort.h>
#include <gsl/gsl_statistics_double.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PI_ 3.14159265358979323846
#define DEG (PI_ / 180.0)

static const struct {
    const char *name;
    int dist, nmin, nmax;
    const char *form;
} dists[] = {
    {"normal", SW_DIST_NORMAL, 2, 4, "normal(MEAN,SD) or normal(MEAN,SD,LO,HI)"},
    {"uniform", SW_DIST_UNIFORM, 2, 2, "uniform(LO,HI)"},
    {"cone", SW_DIST_CONE, 4, 4, "cone(X,Y,Z,HALF_ANGLE_DEG)"},
    {"rotation", SW_DIST_ROTATION, 5, 5, "rotation(W,X,Y,Z,ANGLE_DEG)"},
    {"inertia", SW_DIST_INERTIA, 4, 4, "inertia(A,B,C,REL_SD)"},
};
#define NDIST (sizeof dists / sizeof dists[0])


static int bad(char *msg, size_t len, const char *arg, const char *what)
{
    size_t i;
    int w = snprintf(msg, len, "--disperse %s: %s; expected one of", arg, what);
    for (i = 0; i < NDIST && w > 0 && (size_t)w < len; i++)
        w += snprintf(msg + w, len - (size_t)w, "%s %s", i ? "," : "", dists[i].form);
    return -1;
}

int sw_disp_parse(sw_key *k, const char *arg, char *msg, size_t len)
{
    const char *eq = strchr(arg, '='), *op, *cp, *s;
    size_t i, nl;
    char name[32], tmp[64];
    memset(k, 0, sizeof *k);
    if (!eq || eq == arg || !eq[1]) return bad(msg, len, arg, "expected KEY=DIST");
    op = strchr(eq, '(');
    cp = op ? strchr(op, ')') : NULL;
    if (!op || !cp || cp[1]) return bad(msg, len, arg, "expected DIST(PARAMETERS)");
    nl = (size_t)(op - eq - 1);
    if (nl >= sizeof name) nl = sizeof name - 1;
    memcpy(name, eq + 1, nl);
    name[nl] = 0;
    for (i = 0; i < NDIST; i++)
        if (!strcmp(name, dists[i].name)) break;
    if (i == NDIST) {
        char w[96];
        snprintf(w, sizeof w, "unknown distribution '%s'", name);
        return bad(msg, len, arg, w);
    }
    k->dist = dists[i].dist;
    for (s = op + 1; s < cp;) { /* the numbers */
        const char *c = memchr(s, ',', (size_t)(cp - s));
        size_t n = (size_t)((c ? c : cp) - s);
        if (k->nprm == 8 || n == 0 || n >= sizeof tmp) return bad(msg, len, arg, "a bad parameter list");
        memcpy(tmp, s, n);
        tmp[n] = 0;
        if (cli_number(tmp, &k->prm[k->nprm]) != 0 || !isfinite(k->prm[k->nprm])) {
            char w[128];
            snprintf(w, sizeof w, "'%s' is not a finite number", tmp);
            return bad(msg, len, arg, w);
        }
        k->nprm++;
        s = c ? c + 1 : cp;
    }
    if (k->nprm < dists[i].nmin || k->nprm > dists[i].nmax || k->nprm == 3) {
        char w[96];
        snprintf(w, sizeof w, "%s takes %d%s parameters, not %d", name, dists[i].nmin,
                 dists[i].nmax > dists[i].nmin ? " or 4" : "", k->nprm);
        return bad(msg, len, arg, w);
    }
    switch (k->dist) {
    case SW_DIST_NORMAL:
        if (!(k->prm[1] >= 0)) return bad(msg, len, arg, "the standard deviation SD must be >= 0");
        if (k->nprm == 4 && !(k->prm[2] <= k->prm[0] && k->prm[0] <= k->prm[3]))
            return bad(msg, len, arg, "the bounds must hold the mean: LO <= MEAN <= HI");
        break;
    case SW_DIST_UNIFORM:
        if (!(k->prm[0] <= k->prm[1])) return bad(msg, len, arg, "LO must not exceed HI");
        break;
    case SW_DIST_CONE:
        if (!(k->prm[0] * k->prm[0] + k->prm[1] * k->prm[1] + k->prm[2] * k->prm[2] > 0))
            return bad(msg, len, arg, "the axis must not be zero");
        if (!(k->prm[3] >= 0 && k->prm[3] <= 180)) return bad(msg, len, arg, "the half angle must be in [0, 180] deg");
        break;
    case SW_DIST_ROTATION: {
        double q = sqrt(k->prm[0] * k->prm[0] + k->prm[1] * k->prm[1] + k->prm[2] * k->prm[2] + k->prm[3] * k->prm[3]);
        if (!(fabs(q - 1) < 1e-6)) return bad(msg, len, arg, "the quaternion W,X,Y,Z must have norm 1 (within 1e-6)");
        if (!(k->prm[4] >= 0 && k->prm[4] <= 180)) return bad(msg, len, arg, "the angle must be in [0, 180] deg");
        break;
    }
    case SW_DIST_INERTIA: {
        const double *m = k->prm;
        if (!(m[0] > 0 && m[1] > 0 && m[2] > 0) || m[0] + m[1] < m[2] || m[1] + m[2] < m[0] || m[0] + m[2] < m[1])
            return bad(msg, len, arg, "the moments A,B,C must be positive and obey A+B>=C, B+C>=A, A+C>=B");
        if (!(m[3] >= 0 && m[3] < 0.5)) return bad(msg, len, arg, "the relative SD must be in [0, 0.5)");
        break;
    }
    }
    k->key = sw_dup_str(arg, (size_t)(eq - arg));
    k->spec = sw_dup_str(eq + 1, strlen(eq + 1));
    return k->key && k->spec ? 0 : -1;
}

/* a unit vector uniform on the sphere */
static void unit(gsl_rng *r, double *u)
{
    gsl_ran_dir_3d(r, &u[0], &u[1], &u[2]);
}

void sw_disp_one(const sw_key *k, void *rv, char *buf, size_t len, double *x)
{
    gsl_rng *r = rv;
    const double *m = k->prm;
    switch (k->dist) {
    case SW_DIST_NORMAL: {
        double v;
        int tries = 0;
        /* truncation by rejection (at most 1e6 tries: then the nearer bound) */
        do v = m[0] + gsl_ran_gaussian(r, m[1]);
        while (k->nprm == 4 && (v < m[2] || v > m[3]) && ++tries < 1000000);
        if (k->nprm == 4) v = v < m[2] ? m[2] : v > m[3] ? m[3] : v;
        x[0] = v;
        snprintf(buf, len, "%.17g", v);
        return;
    }
    case SW_DIST_UNIFORM:
        x[0] = m[0] + (m[1] - m[0]) * gsl_rng_uniform(r);
        snprintf(buf, len, "%.17g", x[0]);
        return;
    case SW_DIST_CONE: {
        /* uniform on the spherical cap: cos(theta) uniform in [cos a, 1] */
        double n = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]), a[3] = {m[0] / n, m[1] / n, m[2] / n};
        double ct = 1 - (1 - cos(m[3] * DEG)) * gsl_rng_uniform(r), st = sqrt(fmax(0, 1 - ct * ct));
        double ph = 2 * PI_ * gsl_rng_uniform(r), e1[3], e2[3], t[3] = {1, 0, 0};
        int i;
        if (fabs(a[0]) > 0.9) t[0] = 0, t[1] = 1;
        e1[0] = a[1] * t[2] - a[2] * t[1], e1[1] = a[2] * t[0] - a[0] * t[2], e1[2] = a[0] * t[1] - a[1] * t[0];
        {
            double l = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
            for (i = 0; i < 3; i++) e1[i] /= l;
        }
        e2[0] = a[1] * e1[2] - a[2] * e1[1], e2[1] = a[2] * e1[0] - a[0] * e1[2], e2[2] = a[0] * e1[1] - a[1] * e1[0];
        for (i = 0; i < 3; i++) x[i] = n * (ct * a[i] + st * (cos(ph) * e1[i] + sin(ph) * e2[i]));
        snprintf(buf, len, "[%.17g, %.17g, %.17g]", x[0], x[1], x[2]);
        return;
    }
    case SW_DIST_ROTATION: {
        /* q = dq * q0, dq a rotation about a uniform axis by an angle
         * uniform in [0, ANGLE] */
        double u[3], th = m[4] * DEG * gsl_rng_uniform(r), c = cos(th / 2), s = sin(th / 2);
        double d[4], w0 = m[0], x0 = m[1], y0 = m[2], z0 = m[3];
        unit(r, u);
        d[0] = c, d[1] = s * u[0], d[2] = s * u[1], d[3] = s * u[2];
        x[0] = d[0] * w0 - d[1] * x0 - d[2] * y0 - d[3] * z0;
        x[1] = d[0] * x0 + d[1] * w0 + d[2] * z0 - d[3] * y0;
        x[2] = d[0] * y0 - d[1] * z0 + d[2] * w0 + d[3] * x0;
        x[3] = d[0] * z0 + d[1] * y0 - d[2] * x0 + d[3] * w0;
        snprintf(buf, len, "[%.17g, %.17g, %.17g, %.17g]", x[0], x[1], x[2], x[3]);
        return;
    }
    case SW_DIST_INERTIA: {
        /* each principal moment normal(I, rel_sd I), redrawn together until
         * all are positive and obey the triangle inequalities (a physical
         * body); at most 1e6 tries, then the nominal moments */
        int tries = 0, i, ok;
        do {
            for (i = 0; i < 3; i++) x[i] = m[i] * (1 + gsl_ran_gaussian(r, m[3]));
            ok = x[0] > 0 && x[1] > 0 && x[2] > 0 && x[0] + x[1] >= x[2] && x[1] + x[2] >= x[0] && x[0] + x[2] >= x[1];
        } while (!ok && ++tries < 1000000);
        if (!ok)
            for (i = 0; i < 3; i++) x[i] = m[i];
        snprintf(buf, len, "[%.17g, %.17g, %.17g]", x[0], x[1], x[2]);
        return;
    }
    }
    buf[0] = 0;
}

/* splitmix64 (the seed of a variant's stream from (seed, idx) alone) */
static unsigned long long mix(unsigned long long z)
{
    z += 0x9E3779B97F4A7C15ULL;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

int sw_disp_draw(const sw_key *key, int nkey, unsigned long long seed, long idx, char **out)
{
    gsl_rng *r = gsl_rng_alloc(gsl_rng_mt19937);
    char buf[160];
    double x[4];
    int k;
    if (!r) return -1;
    /* mt19937 takes a 32-bit seed (0 means its default 4357) */
    gsl_rng_set(r, (unsigned long)(mix(mix(seed) ^ (unsigned long long)idx) & 0xffffffffULL));
    for (k = 0; k < nkey; k++) {
        sw_disp_one(&key[k], r, buf, sizeof buf, x);
        if (!(out[k] = sw_dup_str(buf, strlen(buf)))) {
            gsl_rng_free(r);
            return -1;
        }
    }
    gsl_rng_free(r);
    return 0;
}

void sw_wilson(long k, long n, double *lo, double *hi)
{
    const double z = 1.959963984540054;
    double p, d, c, h;
    if (n <= 0) {
        *lo = 0, *hi = 1;
        return;
    }
    p = (double)k / (double)n;
    d = 1 + z * z / (double)n;
    c = (p + z * z / (2.0 * (double)n)) / d;
    h = z * sqrt(p * (1 - p) / (double)n + z * z / (4.0 * (double)n * (double)n)) / d;
    *lo = k == 0 || c - h < 0 ? 0 : c - h; /* exact ends: 0 of n, n of n */
    *hi = k == n || c + h > 1 ? 1 : c + h;
}

/* mean and 10/50/90 % quantiles (GSL, linear interpolation) of v[n]
 * sorted in place; NaN if n = 0 */
static void stats(double *v, size_t n, double *mean, double *p10, double *p50, double *p90)
{
    if (n == 0) {
        *mean = *p10 = *p50 = *p90 = NAN;
        return;
    }
    gsl_sort(v, 1, n);
    *mean = gsl_stats_mean(v, 1, n);
    *p10 = gsl_stats_quantile_from_sorted_data(v, 1, n, 0.1);
    *p50 = gsl_stats_quantile_from_sorted_data(v, 1, n, 0.5);
    *p90 = gsl_stats_quantile_from_sorted_data(v, 1, n, 0.9);
}

int sw_mc_cells(const sw_plan *p, const sw_result *res, sw_cell *cell)
{
    long c, j, m = p->mc > 0 ? p->mc : 1, ncell = p->mc > 0 ? p->ncell : p->nvar;
    double *t = malloc(sizeof(double) * (size_t)m * 3 + 8), *f = t + m, *e = f + m;
    if (!t) return -1;
    for (c = 0; c < ncell; c++) {
        sw_cell *C = &cell[c];
        size_t nt = 0, nf = 0, ne = 0;
        memset(C, 0, sizeof *C);
        for (j = 0; j < m; j++) {
            const sw_result *r = &res[c * m + j];
            if (r->status == SW_NOT_RUN) continue;
            C->n++;
            if (r->status != 0) {
                C->nfail++; /* a failed run counts as not captured */
                continue;
            }
            if (r->verdict >= 0 && r->verdict < 8) C->nverdict[r->verdict]++;
            if (r->verdict == CD_VERDICT_CAPTURED) {
                C->ncap++;
                if (isfinite(r->t_capture)) t[nt++] = r->t_capture;
            }
            if (isfinite(r->peak_fn)) f[nf++] = r->peak_fn;
            if (isfinite(r->epsilon)) e[ne++] = r->epsilon;
        }
        C->p = C->n ? (double)C->ncap / (double)C->n : NAN;
        sw_wilson(C->ncap, C->n, &C->lo, &C->hi);
        stats(t, nt, &C->t_mean, &C->t_p10, &C->t_p50, &C->t_p90);
        stats(f, nf, &C->f_mean, &C->f_p10, &C->f_p50, &C->f_p90);
        stats(e, ne, &C->e_mean, &C->e_p10, &C->e_p50, &C->e_p90);
    }
    free(t);
    return 0;
}
