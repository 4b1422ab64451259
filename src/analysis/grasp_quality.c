/* Ferrari-Canny grasp quality (epsilon, L1 variant) of a contact set.
 * Definition, normalisation and limits: docs/grasp-quality.md.
 * Reference: C. Ferrari, J. Canny, "Planning optimal grasps", ICRA 1992.
 *
 * Trade-off: the convex hull comes from Qhull's reentrant library (qhT on
 * the stack, no global state) rather than our own code; Qhull's errors
 * longjmp back into qh_new_qhull, which returns an exit code, and its text
 * goes to a memory stream that we read for the message, never to stdout or
 * stderr. */
#define _POSIX_C_SOURCE 200809L /* open_memstream */
#include "capdyn/analysis.h"

#include <libqhull_r/qhull_ra.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define seterr cd_error_set

/* The 6-D hull grows steeply with the number of cone edges: four contacts
 * take a few ms at m = 8, about 1 s at m = 32 and 10 s at m = 64 (`make
 * bench-grasp`); a 256-edge run once ended in a Qhull wide-merge error on the
 * cocircular cone edges. 64 is plenty: at m = 8 epsilon is
 * already within 3.3 % of the exact cone's (docs/grasp-quality.md). */
enum { CONE_EDGES_MAX = 64 };
static const double PI = 3.14159265358979323846;
/* accepted ratio between a given rho and the largest lever arm */
static const double RHO_RANGE = 1e6;

cd_grasp_options cd_grasp_options_default(void)
{
    cd_grasp_options o;
    memset(&o, 0, sizeof o);
    o.mode = CD_GRASP_SPATIAL;
    o.plane_normal[2] = 1.0;
    o.rho = 0.0;
    o.cone_edges = 8;
    return o;
}

static double dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static double norm3(const double *a) { return sqrt(dot3(a, a)); }
static void cross3(const double *a, const double *b, double *r)
{
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
}
static int finite3(const double *a) { return isfinite(a[0]) && isfinite(a[1]) && isfinite(a[2]); }

/* a unit vector perpendicular to the unit vector z: the coordinate axis least
 * aligned with z, its z component removed */
static void perp_unit(const double *z, double *e)
{
    int k = 0, i;
    double s;
    for (i = 1; i < 3; i++)
        if (fabs(z[i]) < fabs(z[k])) k = i;
    for (i = 0; i < 3; i++) e[i] = (i == k) - z[k] * z[i];
    s = norm3(e);
    for (i = 0; i < 3; i++) e[i] /= s;
}

/* tolerance below which a direction counts as zero (relative to unit length) */
static const double TINY = 1e-9;

/* Checks every input; on success fills the unit plane normal z (planar mode). */
static cd_status check_input(const cd_grasp_contact *ct, int n, const double c[3], const cd_grasp_options *o,
                             double *z, cd_error *err)
{
    int i;
    if (n < 1) return seterr(err, CD_EINVAL, "grasp quality: n = %d contacts, expected at least 1", n), CD_EINVAL;
    if (!ct || !c)
        return seterr(err, CD_EINVAL, "grasp quality: %s is NULL", !ct ? "contacts" : "reference point c"), CD_EINVAL;
    if (!finite3(c)) return seterr(err, CD_EINVAL, "grasp quality: reference point c is not finite"), CD_EINVAL;
    if (o->mode != CD_GRASP_SPATIAL && o->mode != CD_GRASP_PLANAR)
        return seterr(err, CD_EINVAL, "grasp quality: mode = %d, expected CD_GRASP_SPATIAL (0) or CD_GRASP_PLANAR (1)",
                      (int)o->mode), CD_EINVAL;
    if (!isfinite(o->rho) || o->rho < 0.0)
        return seterr(err, CD_EINVAL, "grasp quality: rho = %g, expected a finite value >= 0 (0 = automatic)", o->rho),
               CD_EINVAL;
    if (o->mode == CD_GRASP_SPATIAL && (o->cone_edges < 3 || o->cone_edges > CONE_EDGES_MAX))
        return seterr(err, CD_EINVAL, "grasp quality: cone_edges = %d, expected 3..%d", o->cone_edges, CONE_EDGES_MAX),
               CD_EINVAL;
    if (o->mode == CD_GRASP_PLANAR) {
        double s = norm3(o->plane_normal);
        if (!finite3(o->plane_normal) || !(s > 0.0))
            return seterr(err, CD_EINVAL, "grasp quality: plane_normal = (%g, %g, %g), expected a finite non-zero vector",
                          o->plane_normal[0], o->plane_normal[1], o->plane_normal[2]), CD_EINVAL;
        for (i = 0; i < 3; i++) z[i] = o->plane_normal[i] / s;
    }
    for (i = 0; i < n; i++) {
        const cd_grasp_contact *k = &ct[i];
        double sn = norm3(k->n);
        if (!finite3(k->p)) return seterr(err, CD_EINVAL, "grasp quality: contact %d: point p is not finite", i), CD_EINVAL;
        if (!finite3(k->n) || !(sn > 0.0))
            return seterr(err, CD_EINVAL, "grasp quality: contact %d: normal n = (%g, %g, %g), expected a finite non-zero vector",
                          i, k->n[0], k->n[1], k->n[2]), CD_EINVAL;
        if (!isfinite(k->mu) || k->mu < 0.0)
            return seterr(err, CD_EINVAL, "grasp quality: contact %d: mu = %g, expected a finite value >= 0", i, k->mu),
                   CD_EINVAL;
        if (!finite3(k->t)) return seterr(err, CD_EINVAL, "grasp quality: contact %d: tangent t is not finite", i), CD_EINVAL;
        if (o->mode == CD_GRASP_PLANAR) {
            double in = fabs(dot3(k->n, z)) / sn;
            if (sqrt(fmax(0.0, 1.0 - in * in)) < TINY)
                return seterr(err, CD_EINVAL, "grasp quality: contact %d: normal is perpendicular to the grasp plane", i),
                       CD_EINVAL;
        } else if (norm3(k->t) > 0.0) {
            double ct_ = dot3(k->n, k->t) / (sn * norm3(k->t));
            if (sqrt(fmax(0.0, 1.0 - ct_ * ct_)) < TINY)
                return seterr(err, CD_EINVAL, "grasp quality: contact %d: tangent t is parallel to the normal", i), CD_EINVAL;
        }
    }
    return CD_OK;
}

/* Fills w (dim x nwrench, row per wrench) with the primitive wrenches; see
 * the header for the formula. Planar coordinates: (f.e1, f.e2, tau.z/rho). */
static void build_wrenches(const cd_grasp_contact *ct, int n, const double c[3], const cd_grasp_options *o,
                           const double *z, double rho, double *w)
{
    const int planar = o->mode == CD_GRASP_PLANAR;
    const int m = planar ? 2 : o->cone_edges;
    double e1[3] = {0, 0, 0}, e2[3] = {0, 0, 0}; /* set when planar */
    int i, j, a, row = 0;
    if (planar) {
        perp_unit(z, e1);
        cross3(z, e1, e2);
    }
    for (i = 0; i < n; i++) {
        const cd_grasp_contact *k = &ct[i];
        double r[3], nn[3], t1[3], t2[3], s;
        for (a = 0; a < 3; a++) r[a] = (k->p[a] - c[a]) / rho; /* lever arm in units of rho */
        if (planar) {
            /* in-plane coordinates: r = (r.e1, r.e2), n projected and normalised, t = z x n */
            double rx = dot3(r, e1), ry = dot3(r, e2), nx = dot3(k->n, e1), ny = dot3(k->n, e2);
            s = hypot(nx, ny);
            nx /= s;
            ny /= s;
            for (j = 0; j < (k->mu > 0.0 ? m : 1); j++) {
                double sg = k->mu > 0.0 ? (j == 0 ? 1.0 : -1.0) : 0.0;
                double fx = nx - sg * k->mu * ny, fy = ny + sg * k->mu * nx;
                double *wr = w + 3 * row++;
                wr[0] = fx;
                wr[1] = fy;
                wr[2] = rx * fy - ry * fx;
            }
            continue;
        }
        s = norm3(k->n);
        for (a = 0; a < 3; a++) nn[a] = k->n[a] / s;
        if (norm3(k->t) > 0.0) {
            double tn = dot3(k->t, nn);
            for (a = 0; a < 3; a++) t1[a] = k->t[a] - tn * nn[a];
            s = norm3(t1);
            for (a = 0; a < 3; a++) t1[a] /= s;
        } else {
            perp_unit(nn, t1);
        }
        cross3(nn, t1, t2);
        for (j = 0; j < (k->mu > 0.0 ? m : 1); j++) {
            /* f_ij = n + mu (cos th_j t1 + sin th_j t2), th_j = 2 pi j / m */
            double th = 2.0 * PI * j / m, cs = cos(th), sn = sin(th), f[3], tau[3];
            double *wr = w + 6 * row++;
            for (a = 0; a < 3; a++) f[a] = nn[a] + k->mu * (cs * t1[a] + sn * t2[a]);
            cross3(r, f, tau);
            for (a = 0; a < 3; a++) {
                wr[a] = f[a];
                wr[3 + a] = tau[a];
            }
        }
    }
}

/* the first line of Qhull's error text (it starts "QH6154 ..."), trimmed */
static void first_line(const char *text, char *out, size_t cap)
{
    size_t len = 0;
    const char *s = text ? text : "";
    while (*s == '\n' || *s == ' ') s++;
    while (s[len] && s[len] != '\n' && len + 1 < cap) len++;
    memcpy(out, s, len);
    out[len] = '\0';
}

cd_status cd_grasp_quality_eval(const cd_grasp_contact *ct, int n, const double c[3], const cd_grasp_options *opt,
                                cd_grasp_quality *q, cd_error *err)
{
    cd_grasp_options o = opt ? *opt : cd_grasp_options_default();
    double z[3] = {0.0, 0.0, 1.0}, rho, rmax = 0.0, wmax = 0.0, dmin = HUGE_VAL, tol = 0.0;
    double *w;
    int i, a, dim, nw = 0, exitcode, curlong, totlong, nfacet = 0;
    cd_status st;
    char *errtext = NULL, line[400];
    size_t errlen = 0;
    FILE *ferr;
    qhT qh_qh;
    qhT *qh = &qh_qh;
    facetT *facet;

    if (!q) return seterr(err, CD_EINVAL, "grasp quality: result pointer q is NULL"), CD_EINVAL;
    memset(q, 0, sizeof *q);
    st = check_input(ct, n, c, &o, z, err);
    if (st != CD_OK) return st;
    dim = o.mode == CD_GRASP_PLANAR ? 3 : 6;
    q->dim = dim;

    /* torque scale: given, else the largest lever arm (in-plane in planar mode) */
    for (i = 0; i < n; i++) {
        double r[3], zr = 0.0;
        for (a = 0; a < 3; a++) r[a] = ct[i].p[a] - c[a];
        if (o.mode == CD_GRASP_PLANAR) zr = dot3(r, z);
        for (a = 0; a < 3; a++) r[a] -= zr * z[a];
        rmax = fmax(rmax, norm3(r));
    }
    if (!isfinite(rmax))
        return seterr(err, CD_EINVAL, "grasp quality: the lever arms |p - c| overflow (contacts too far from c)"),
               CD_EINVAL;
    /* A rho far from the lever arms makes the wrench set a needle or a pancake
     * in wrench space: Qhull then sees it as flat (a false "no closure"; a
     * 12-contact cube grasp with rho = 1e-20 m does that). Refuse it. */
    if (o.rho > 0.0 && rmax > 0.0 && (rmax > RHO_RANGE * o.rho || rmax * RHO_RANGE < o.rho))
        return seterr(err, CD_EINVAL,
                      "grasp quality: rho = %g m is out of scale with the lever arms (max |p - c| = %g m): expected "
                      "within a factor %g of it (or 0 = automatic)", o.rho, rmax, RHO_RANGE), CD_EINVAL;
    rho = o.rho > 0.0 ? o.rho : rmax > 0.0 ? rmax : 1.0;
    q->rho = rho;
    for (i = 0; i < n; i++) nw += ct[i].mu > 0.0 ? (o.mode == CD_GRASP_PLANAR ? 2 : o.cone_edges) : 1;
    q->nwrench = nw;
    /* fewer than dim+1 points span no dim-simplex: no interior, no closure */
    if (nw < dim + 1) return CD_OK;

    w = malloc(sizeof *w * (size_t)dim * (size_t)nw);
    if (!w) return seterr(err, CD_ENOMEM, "grasp quality: cannot allocate %d wrenches", nw), CD_ENOMEM;
    build_wrenches(ct, n, c, &o, z, rho, w);
    for (i = 0; i < nw * dim; i += dim) {
        double s = 0.0;
        for (a = 0; a < dim; a++) s += w[i + a] * w[i + a];
        wmax = fmax(wmax, sqrt(s));
    }

    /* Qhull's text goes to a memory stream (or nowhere), never to a terminal */
    ferr = open_memstream(&errtext, &errlen);
    if (!ferr) ferr = fopen("/dev/null", "w");
    if (!ferr) {
        free(w);
        return seterr(err, CD_ENOMEM, "grasp quality: cannot open a stream for Qhull's messages"), CD_ENOMEM;
    }
    qh_zero(qh, ferr);
    /* plain hull, default merging (C-0, Qx in 5-D and up): merged facets keep a
     * hyperplane that bounds every input point within Qhull's round-off */
    exitcode = qh_new_qhull(qh, dim, nw, w, False, (char *)"qhull", NULL, ferr);
    if (exitcode == qh_ERRnone) {
        FORALLfacets {
            /* outward unit normal, offset: distance of the origin = -offset */
            dmin = fmin(dmin, -facet->offset);
            nfacet++;
        }
        /* the origin counts as inside only if clear of every facet by more
         * than Qhull's distance round-off (and 1e-12 of the largest wrench) */
        tol = fmax(qh->DISTround, 1e-12 * wmax);
    }
    qh_freeqhull(qh, !qh_ALL);
    qh_memfreeshort(qh, &curlong, &totlong);
    fclose(ferr);
    first_line(errtext, line, sizeof line);
    free(errtext);
    free(w);

    if (exitcode == qh_ERRsingular) return CD_OK; /* flat wrench set: no interior, no closure */
    if (exitcode != qh_ERRnone)
        return seterr(err, CD_ENUMERIC, "grasp quality: Qhull failed (exit code %d) on %d wrenches in %d-D: %s", exitcode,
                      nw, dim, line[0] ? line : "no message"), CD_ENUMERIC;
    if (curlong || totlong)
        return seterr(err, CD_ENUMERIC, "grasp quality: Qhull did not free %d bytes in %d blocks", totlong, curlong),
               CD_ENUMERIC;
    q->nfacet = nfacet;
    if (nfacet > 0 && dmin > tol) {
        q->epsilon = dmin;
        q->force_closure = 1;
    }
    return CD_OK;
}
