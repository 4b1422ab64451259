/* Distance of a check point (a sphere: centre p, radius r) to a shape.
 *
 * Analytic shapes give an exact signed distance of the centre (>0 outside),
 * the outward unit normal and the closest surface point, all in the shape
 * frame. Convex hulls (and, for cross-checking, every bounded primitive) go
 * through libccd. libccd traps, measured and tracked upstream: GJK/EPA returns
 * a NaN normal for touching boxes (issue #25) and allocates per query; MPR
 * allocates nothing but its depth is the depth along the portal found from
 * the two centres, exact for a sphere against a flat face or another sphere,
 * approximate elsewhere. The rhs therefore uses MPR with a bounded iteration
 * count and checks every answer (finite depth, unit normal); a bad answer is
 * reported (-1) and becomes a logged event, never silent data. */
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
