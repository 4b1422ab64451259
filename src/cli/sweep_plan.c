/* capdyn sweep: the plan (docs/sweep.md, "Designs"): the --vary specs, the
 * variants of a grid (C order, the first key slowest) or of a Latin
 * hypercube, each variant's --set list, and the region areas of a grid. */
#define _POSIX_C_SOURCE 200809L
#include "sweep.h"
#include "capdyn/verdict.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

char *sw_dup_str(const char *s, size_t n)
{
    char *d = malloc(n + 1);
    if (d) {
        memcpy(d, s, n);
        d[n] = 0;
    }
    return d;
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
        cli_fmt_num(buf, v);
        return;
    }
    dec = 6 - (int)floor(log10(step));
    if (dec < 0) dec = 0;
    if (dec > 20) {
        cli_fmt_num(buf, v);
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
            if (!(k->vals[k->nval++] = sw_dup_str(start, (size_t)(p - start)))) return -1;
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
    k->key = sw_dup_str(arg, (size_t)(eq - arg));
    k->spec = sw_dup_str(eq + 1, strlen(eq + 1));
    if (!k->key || !k->spec) return -1;
    /* a range: two or three numbers separated by ':' */
    c1 = strchr(k->spec, ':');
    c2 = c1 ? strchr(c1 + 1, ':') : NULL;
    if (c1 && !strchr(k->spec, ',') && !strchr(k->spec, '"') && (!c2 || !strchr(c2 + 1, ':'))) {
        char *a = sw_dup_str(k->spec, (size_t)(c1 - k->spec));
        char *b = c2 ? sw_dup_str(c1 + 1, (size_t)(c2 - c1 - 1)) : sw_dup_str(c1 + 1, strlen(c1 + 1));
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
        if (!(k->vals[k->nval++] = sw_dup_str(buf, strlen(buf)))) return -1;
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
    int nv_ = p->nvary;
    if (!p->lhs) {
        /* the size first: no key's values are made for a grid too large */
        double nv = 1;
        for (k = 0; k < nv_; k++) nv *= (double)(p->key[k].is_range ? p->key[k].n : p->key[k].nval);
        p->ncell = (long)nv;
        if (p->mc > 0) nv *= (double)p->mc;
        if (nv > (double)SW_MAX_VARIANTS) {
            char b[CLI_NUM];
            snprintf(msg, len, "the grid has %s variants, more than %ld", cli_fmt_num(b, nv), SW_MAX_VARIANTS);
            return -1;
        }
        p->nvar = (long)nv;
        for (k = 0; k < nv_; k++)
            if (p->key[k].is_range && grid_values(&p->key[k]) != 0) return -1;
    } else
        p->nvar = p->ncell = p->lhs_n;
    p->val = calloc((size_t)(p->nvar * p->nkey + 1), sizeof(char *));
    if (!p->val) return -1;
    if (!p->lhs) {
        long m = p->mc > 0 ? p->mc : 1;
        for (i = 0; i < p->nvar; i++) {
            long r = i / m; /* the cell */
            for (k = nv_ - 1; k >= 0; k--) {
                const sw_key *K = &p->key[k];
                const char *v = K->vals[r % K->nval];
                r /= K->nval;
                if (!(p->val[i * p->nkey + k] = sw_dup_str(v, strlen(v)))) return -1;
            }
            /* the dispersed keys: variant i's own stream (sweep_mc.c) */
            if (p->nkey > nv_ && sw_disp_draw(&p->key[nv_], p->nkey - nv_, p->seed, i, &p->val[i * p->nkey + nv_]) != 0)
                return -1;
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
                    cli_fmt_num(buf, K->a + (K->b - K->a) * u);
                    v = buf;
                } else {
                    long j = (long)(u * (double)K->nval);
                    v = K->vals[j < K->nval ? j : K->nval - 1];
                }
                if (!(p->val[i * p->nkey + k] = sw_dup_str(v, strlen(v)))) {
                    free(perm);
                    return -1;
                }
            }
        }
        free(perm);
    }
    return 0;
}

void sw_plan_free(sw_plan *p)
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
    if (p->lhs || p->mc > 0) return 0; /* --mc: the probability per cell instead (sw_mc_cells) */
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

int sw_plan_make(sw_plan *p, const char *const *vary, int nvary, long lhs, unsigned long long seed)
{
    return sw_plan_make_mc(p, vary, nvary, lhs, seed, NULL, 0, 0);
}

int sw_plan_make_mc(sw_plan *p, const char *const *vary, int nvary, long lhs, unsigned long long seed,
                    const char *const *disp, int ndisp, long mc)
{
    char msg[2048];
    int k, j;
    memset(p, 0, sizeof *p);
    p->lhs = lhs > 0;
    p->lhs_n = lhs;
    p->seed = seed;
    p->mc = mc;
    for (k = 0; k < nvary + ndisp; k++) {
        msg[0] = 0;
        if ((k < nvary ? parse_vary(&p->key[p->nkey], vary[k], p->lhs, msg, sizeof msg)
                       : sw_disp_parse(&p->key[p->nkey], disp[k - nvary], msg, sizeof msg)) != 0) {
            p->nkey++;
            sw_plan_free(p);
            return msg[0] ? cli_usage("sweep", "%s", msg) : (cli_error("out of memory"), CLI_FAIL);
        }
        p->nkey++;
        if (k < nvary) p->nvary = p->nkey;
        for (j = 0; j < k; j++)
            if (!strcmp(p->key[j].key, p->key[k].key)) {
                sw_plan_free(p);
                return cli_usage("sweep", "%s %s: the key is given twice", k < nvary ? "--vary" : "--disperse",
                                 k < nvary ? vary[k] : disp[k - nvary]);
            }
    }
    msg[0] = 0;
    if (make_plan(p, msg, sizeof msg) != 0) {
        cli_error("%s", msg[0] ? msg : "out of memory");
        sw_plan_free(p);
        return CLI_FAIL;
    }
    return CLI_OK;
}

char **sw_overrides(const char *const *sets, int nsets, const sw_plan *p, long idx)
{
    char **ov = calloc((size_t)(nsets + p->nkey + 1), sizeof *ov);
    int k;
    if (!ov) return NULL;
    for (k = 0; k < nsets; k++)
        if (!(ov[k] = sw_dup_str(sets[k], strlen(sets[k])))) goto fail;
    for (k = 0; k < p->nkey; k++) {
        const char *v = p->val[idx * p->nkey + k];
        if (!(ov[nsets + k] = malloc(strlen(p->key[k].key) + strlen(v) + 2))) goto fail;
        sprintf(ov[nsets + k], "%s=%s", p->key[k].key, v);
    }
    return ov;
fail:
    sw_overrides_free(ov);
    return NULL;
}

void sw_overrides_free(char **ov)
{
    char **q;
    if (!ov) return;
    for (q = ov; *q; q++) free(*q);
    free(ov);
}
