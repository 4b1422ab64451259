/* Distance of a check point (a sphere: centre p, radius r) to a shape.
 *
 * Analytic shapes give an exact signed distance of the centre (>0 outside),
 * the outward unit normal and the closest surface point, all in the shape
 * frame. Convex hulls are exact too, from face planes built at finalize.
 *
 * Why not libccd in the right-hand side (measured in tests/test_contact_geometry.c
 * and tracked upstream): MPR allocates nothing but its depth is the depth
 * along the ray from the shape's centre, not the minimum (0.38 m wrong for a
 * deep point in a box hull, 48 deg off in the normal); GJK/EPA finds the
 * minimum but allocates per query, stops on a *squared* tolerance (1e-12
 * gives 1e-6 m), has no iteration bound in EPA, returns a NaN normal for
 * touching boxes (libccd #25) and a false depth 0 on ~0.2 % of sphere poses.
 * libccd (GJK/EPA, bounded, every answer checked) stays the independent
 * cross-check of every shape: cd_shape_distance_ccd. */
#include "capdyn/sim.h"
#include "../math/cd_math.h"
#include "geometry.h"

#include <ccd/ccd.h>
#include <ccd/vec3.h>

/* ---- analytic signed distances, shape frame ------------------------------- */

static void plane_dist(const double p[3], double *d, double n[3], double s[3])
{
    *d = p[2];
    cd_v3_set(n, 0, 0, 1);
    cd_v3_set(s, p[0], p[1], 0);
}

static void sphere_dist(double R, const double p[3], double *d, double n[3], double s[3])
{
    double r = cd_v3_norm(p);
    if (r > 1e-300) cd_v3_scale(n, p, 1.0 / r); else cd_v3_set(n, 0, 0, 1);
    *d = r - R;
    cd_v3_scale(s, n, R);
}

/* Box with half extents h: outside, the closest point is the clamped point;
 * inside, the nearest face (ties go to the lowest axis index). */
static void box_dist(const double h[3], const double p[3], double *d, double n[3], double s[3])
{
    double q[3], c[3], o;
    int i, inside = 1;
    for (i = 0; i < 3; i++) {
        c[i] = p[i] < -h[i] ? -h[i] : (p[i] > h[i] ? h[i] : p[i]);
        if (c[i] != p[i]) inside = 0;
    }
    if (!inside) {
        cd_v3_sub(q, p, c);
        o = cd_v3_norm(q);
        *d = o;
        cd_v3_scale(n, q, 1.0 / o);
        cd_v3_copy(s, c);
        return;
    }
    {
        int best = 0;
        double bd = h[0] - fabs(p[0]);
        for (i = 1; i < 3; i++)
            if (h[i] - fabs(p[i]) < bd) { bd = h[i] - fabs(p[i]); best = i; }
        *d = -bd;
        cd_v3_zero(n);
        n[best] = p[best] >= 0 ? 1.0 : -1.0;
        cd_v3_copy(s, p);
        s[best] = n[best] * h[best];
    }
}

/* Finite cylinder along z (radius R, half length L): a 2-D box problem in
 * (rho, z) where rho is the radial distance. */
static void cylinder_dist(double R, double L, const double p[3], double *d, double n[3], double s[3])
{
    double rho = sqrt(p[0] * p[0] + p[1] * p[1]), er[3];
    double dr = rho - R, dz = fabs(p[2]) - L, sz = p[2] >= 0 ? 1.0 : -1.0;
    if (rho > 1e-300) cd_v3_set(er, p[0] / rho, p[1] / rho, 0); else cd_v3_set(er, 1, 0, 0);
    if (dr > 0 && dz > 0) { /* nearest the rim */
        double o = sqrt(dr * dr + dz * dz);
        *d = o;
        cd_v3_set(n, er[0] * dr / o, er[1] * dr / o, sz * dz / o);
        cd_v3_set(s, er[0] * R, er[1] * R, sz * L);
    } else if (dr > dz) { /* side: outside radially (dz <= 0), or inside and nearer the side */
        *d = dr;
        cd_v3_copy(n, er);
        cd_v3_set(s, er[0] * R, er[1] * R, p[2]);
    } else { /* cap: outside axially (dr <= 0), or inside and nearer the cap */
        *d = dz;
        cd_v3_set(n, 0, 0, sz);
        cd_v3_set(s, p[0], p[1], sz * L);
    }
}

/* Capsule: segment from (0,0,-L) to (0,0,L) swept by a sphere of radius R. */
static void capsule_dist(double R, double L, const double p[3], double *d, double n[3], double s[3])
{
    double a[3] = {0, 0, 0}, q[3];
    a[2] = p[2] > L ? L : (p[2] < -L ? -L : p[2]);
    cd_v3_sub(q, p, a);
    sphere_dist(R, q, d, n, s);
    cd_v3_add(s, s, a);
}

int cd_geom_analytic(int type, const double size[3], const double p[3], double *d, double n[3], double s[3])
{
    switch (type) {
    case CD_SHAPE_PLANE: plane_dist(p, d, n, s); break;
    case CD_SHAPE_SPHERE: sphere_dist(size[0], p, d, n, s); break;
    case CD_SHAPE_BOX: box_dist(size, p, d, n, s); break;
    case CD_SHAPE_CYLINDER: cylinder_dist(size[0], size[1], p, d, n, s); break;
    case CD_SHAPE_CAPSULE: capsule_dist(size[0], size[1], p, d, n, s); break;
    default: return -1;
    }
    return (isfinite(*d) && cd_v3_isfinite(n) && cd_v3_isfinite(s)) ? 0 : -1;
}

/* ---- convex hulls: exact, from the face planes built at finalize ---------- */

/* Closest point to p on triangle (a, b, c): the Voronoi-region walk of
 * Ericson, Real-Time Collision Detection, sec. 5.1.5. */
static void closest_on_triangle(const double p[3], const double a[3], const double b[3], const double c[3],
                                double q[3])
{
    double ab[3], ac[3], ap[3], bp[3], cp[3], d1, d2, d3, d4, d5, d6, va, vb, vc, v, w, den;
    cd_v3_sub(ab, b, a);
    cd_v3_sub(ac, c, a);
    cd_v3_sub(ap, p, a);
    d1 = cd_v3_dot(ab, ap);
    d2 = cd_v3_dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) { cd_v3_copy(q, a); return; }
    cd_v3_sub(bp, p, b);
    d3 = cd_v3_dot(ab, bp);
    d4 = cd_v3_dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) { cd_v3_copy(q, b); return; }
    vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        v = d1 / (d1 - d3);
        cd_v3_copy(q, a); cd_v3_axpy(q, v, ab);
        return;
    }
    cd_v3_sub(cp, p, c);
    d5 = cd_v3_dot(ab, cp);
    d6 = cd_v3_dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) { cd_v3_copy(q, c); return; }
    vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        w = d2 / (d2 - d6);
        cd_v3_copy(q, a); cd_v3_axpy(q, w, ac);
        return;
    }
    va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        double bc[3];
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        cd_v3_sub(bc, c, b);
        cd_v3_copy(q, b); cd_v3_axpy(q, w, bc);
        return;
    }
    den = 1.0 / (va + vb + vc);
    v = vb * den;
    w = vc * den;
    cd_v3_copy(q, a); cd_v3_axpy(q, v, ab); cd_v3_axpy(q, w, ac);
}

int cd_geom_hull(const double *vert, const int *fv, const double *fp, const int *run, int nf, const double p[3],
                 double beyond, double *d, double n[3], double s[3])
{
    enum { HULL_H_CACHE = 64 };
    double hc[HULL_H_CACHE]; /* the plane distance of run k (the k-th plane) */
    int f, k, r, best = 0;
    double hmax = -HUGE_VAL;
    if (!cd_v3_isfinite(p)) return -1;
    /* inside (or on) the hull: the signed distance is the largest plane
     * distance, one per face plane (run: its triangles share it bitwise) */
    for (f = 0, k = 0; f < nf; f += r, k++) {
        double h = cd_v3_dot(fp + 4 * f, p) - fp[4 * f + 3];
        r = run && run[f] > 0 ? run[f] : 1;
        if (k < HULL_H_CACHE) hc[k] = h;
        if (h > hmax) { hmax = h; best = f; }
    }
    if (hmax > beyond) {
        /* farther than asked from some face plane: its distance is a lower
         * bound of the true one (the hull lies behind every plane) */
        *d = hmax;
        cd_v3_copy(n, fp + 4 * best);
        cd_v3_copy(s, p);
        cd_v3_axpy(s, -hmax, n);
        return (isfinite(*d) && cd_v3_isfinite(s)) ? 1 : -1;
    }
    if (hmax <= 0) {
        *d = hmax;
        cd_v3_copy(n, fp + 4 * best);
        cd_v3_copy(s, p);
        cd_v3_axpy(s, -hmax, n);
        return 0;
    }
    /* outside: the nearest point over the face triangles. Only faces whose
     * plane p is in front of (h > 0) can hold it (p - q lies in the normal
     * cone at q, so some face through q has n.(p - q) > 0, i.e. h > 0), and a
     * face is no nearer than its plane (distance >= h): start from the face
     * of largest h and skip every face with h^2 >= the best squared distance.
     * The hull lies behind every face plane, so no point of it is nearer than
     * hmax: once the best squared distance is at most hmax^2 (p projects into
     * a face of largest h, the common case of a point facing a side) no face
     * can do better and the scan stops. Exact: the same minimum as the scan
     * over every face. */
    {
        double dmin, q[3], t[3];
        const int *b3 = fv + 3 * best;
        closest_on_triangle(p, vert + 3 * b3[0], vert + 3 * b3[1], vert + 3 * b3[2], q);
        cd_v3_sub(t, p, q);
        dmin = cd_v3_dot(t, t);
        cd_v3_copy(s, q);
        for (f = 0, k = 0; f < nf && dmin > hmax * hmax; f += r, k++) {
            double h = k < HULL_H_CACHE ? hc[k] : cd_v3_dot(fp + 4 * f, p) - fp[4 * f + 3];
            int j;
            r = run && run[f] > 0 ? run[f] : 1;
            if (h <= 0 || h * h >= dmin) continue; /* no triangle of this plane can be nearer */
            for (j = f; j < f + r; j++) {
                double dd;
                if (j == best) continue;
                closest_on_triangle(p, vert + 3 * fv[3 * j], vert + 3 * fv[3 * j + 1], vert + 3 * fv[3 * j + 2], q);
                cd_v3_sub(t, p, q);
                dd = cd_v3_dot(t, t);
                if (dd < dmin) { dmin = dd; cd_v3_copy(s, q); }
            }
        }
        *d = sqrt(dmin);
        cd_v3_sub(n, p, s);
        cd_v3_scale(n, n, 1.0 / *d);
    }
    return (isfinite(*d) && cd_v3_isfinite(n)) ? 0 : -1;
}

/* ---- libccd: support functions in the shape frame ------------------------- */
typedef struct {
    int type;
    const double *size;
    const double *vert;
    int nvert;
    double centre[3];
    double radius;   /* for the check-point sphere */
} ccd_obj;

static void support(const void *obj, const ccd_vec3_t *dir, ccd_vec3_t *out)
{
    const ccd_obj *o = (const ccd_obj *)obj;
    double u[3] = {dir->v[0], dir->v[1], dir->v[2]}, r[3] = {0, 0, 0}, nu;
    int i;
    nu = cd_v3_norm(u);
    if (nu > 0) cd_v3_scale(u, u, 1.0 / nu); else cd_v3_set(u, 1, 0, 0);
    switch (o->type) {
    case -1: /* check-point sphere */
        cd_v3_scale(r, u, o->radius);
        cd_v3_add(r, r, o->centre);
        break;
    case CD_SHAPE_SPHERE:
        cd_v3_scale(r, u, o->size[0]);
        break;
    case CD_SHAPE_BOX:
        for (i = 0; i < 3; i++) r[i] = u[i] >= 0 ? o->size[i] : -o->size[i];
        break;
    case CD_SHAPE_CYLINDER: {
        double rho = sqrt(u[0] * u[0] + u[1] * u[1]);
        if (rho > 0) { r[0] = o->size[0] * u[0] / rho; r[1] = o->size[0] * u[1] / rho; }
        r[2] = u[2] >= 0 ? o->size[1] : -o->size[1];
        break;
    }
    case CD_SHAPE_CAPSULE:
        cd_v3_scale(r, u, o->size[0]);
        r[2] += u[2] >= 0 ? o->size[1] : -o->size[1];
        break;
    case CD_SHAPE_CONVEX: {
        double best = -HUGE_VAL;
        for (i = 0; i < o->nvert; i++) {
            double v = cd_v3_dot(o->vert + 3 * i, u);
            if (v > best) { best = v; cd_v3_copy(r, o->vert + 3 * i); }
        }
        break;
    }
    default:
        break;
    }
    ccdVec3Set(out, r[0], r[1], r[2]);
}

static void centre(const void *obj, ccd_vec3_t *c)
{
    const ccd_obj *o = (const ccd_obj *)obj;
    int i;
    if (o->type == -1) { ccdVec3Set(c, o->centre[0], o->centre[1], o->centre[2]); return; }
    if (o->type == CD_SHAPE_CONVEX) {
        double a[3] = {0, 0, 0};
        for (i = 0; i < o->nvert; i++) cd_v3_add(a, a, o->vert + 3 * i);
        ccdVec3Set(c, a[0] / o->nvert, a[1] / o->nvert, a[2] / o->nvert);
        return;
    }
    ccdVec3Set(c, 0, 0, 0);
}

static void ccd_setup(ccd_t *c, double tol)
{
    CCD_INIT(c);
    c->support1 = support;
    c->support2 = support;
    c->center1 = centre;
    c->center2 = centre;
    c->max_iterations = 200;    /* libccd's default is unbounded */
    c->mpr_tolerance = tol;
    c->epa_tolerance = tol;
    c->dist_tolerance = tol;
}

/* A lower bound of the gap between the sphere and the shape along the line
 * from the shape's centre to the sphere's: positive => certainly separated. */
static double support_gap(const ccd_obj *sh, const double p[3], double r)
{
    ccd_vec3_t dir, out, c;
    double u[3], cc[3];
    centre(sh, &c);
    cd_v3_set(cc, c.v[0], c.v[1], c.v[2]);
    cd_v3_sub(u, p, cc);
    if (cd_v3_normalize(u) == 0) return -r;
    ccdVec3Set(&dir, u[0], u[1], u[2]);
    support(sh, &dir, &out);
    return cd_v3_dot(u, p) - r - (out.v[0] * u[0] + out.v[1] * u[1] + out.v[2] * u[2]);
}

int cd_geom_ccd(int type, const double size[3], const double *vert, int nvert, const double p[3],
                double r, int use_epa, double tol, double *d, double n[3], double s[3])
{
    ccd_obj sh, sp;
    ccd_t c;
    ccd_real_t depth;
    ccd_vec3_t dir, pos;
    int res;
    double nn;
    if (!cd_v3_isfinite(p) || !isfinite(r)) return -1; /* libccd segfaults on NaN poses */
    sh.type = type; sh.size = size; sh.vert = vert; sh.nvert = nvert; sh.radius = 0;
    cd_v3_zero(sh.centre);
    sp.type = -1; sp.size = NULL; sp.vert = NULL; sp.nvert = 0; sp.radius = r;
    cd_v3_copy(sp.centre, p);
    ccd_setup(&c, tol);
    res = use_epa ? ccdGJKPenetration(&sh, &sp, &c, &depth, &dir, &pos)
                  : ccdMPRPenetration(&sh, &sp, &c, &depth, &dir, &pos);
    if (res != 0) { /* separated (or libccd gave up): report a positive lower bound */
        double g = support_gap(&sh, p, r);
        *d = r + (g > 1e-12 ? g : 1e-12);
        return 1;
    }
    cd_v3_set(n, dir.v[0], dir.v[1], dir.v[2]);
    nn = cd_v3_norm(n);
    if (!isfinite(depth) || !(fabs(nn - 1.0) < 1e-6) || depth < 0) return -1;
    cd_v3_scale(n, n, 1.0 / nn);
    /* the centre lies at depth below the sphere's touching position */
    *d = r - depth;
    /* closest shape surface point to the sphere centre along n */
    cd_v3_copy(s, p);
    cd_v3_axpy(s, -*d, n);
    return 0;
}
