/* Internal: point/sphere distance queries in the shape frame. */
#ifndef CD_GEOMETRY_H
#define CD_GEOMETRY_H

/* Exact signed distance of point p (shape frame) to an analytic shape (type:
 * plane, sphere, box, cylinder, capsule): d (>0 outside), outward unit normal
 * n, closest surface point s. Returns 0, or -1 if not finite. */
int cd_geom_analytic(int type, const double size[3], const double p[3], double *d, double n[3], double s[3]);

/* Exact signed distance of point p (shape frame) to the convex hull given by
 * nf face triangles fv (indices into vert) with outward planes fp (n, o):
 * inside, the largest plane distance; outside, the nearest face triangle.
 * run (may be NULL: a plane per triangle): at a face's first triangle, the
 * number of consecutive triangles sharing its plane bitwise, 0 at the
 * others (cd_model.face_run); each plane's distance is computed once.
 * When some plane distance exceeds `beyond` (HUGE_VAL: never), the largest
 * one is returned instead (a lower bound of d; n that plane's normal, s the
 * foot of p on it) with status 1, and no triangle is visited.
 * Returns 0 (exact), 1 (the plane bound) or -1 if not finite. */
int cd_geom_hull(const double *vert, const int *fv, const double *fp, const int *run, int nf, const double p[3],
                 double beyond, double *d, double n[3], double s[3]);

/* libccd query of a sphere (centre p, radius r) against a shape (any type but
 * plane); d is the distance of the centre to the surface (r - depth), n the
 * normal from the shape toward the sphere, s the surface point. use_epa
 * selects GJK/EPA (allocates) instead of MPR; tol is libccd's tolerance.
 * Returns 0 when penetrating, 1 when separated (then only d > r is valid: a
 * lower-bound gap), -1 on a bad libccd answer. */
int cd_geom_ccd(int type, const double size[3], const double *vert, int nvert, const double p[3],
                double r, int use_epa, double tol, double *d, double n[3], double s[3]);

#endif
