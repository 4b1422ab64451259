/* Contact geometry validation (issue 3, test 6): a check point (sphere of
 * radius r) against every analytic shape.
 *
 * (a) Closed form: points placed at known depths/positions in each feature
 *     region (sphere in/out; box faces in/out, edge, vertex; cylinder side,
 *     caps, rims; capsule side and ends; plane): distance, normal and closest
 *     surface point from cd_shape_distance within 1e-12 (absolute; the shapes
 *     are ~0.5 m, so this is round-off of a few operations).
 * (b) libccd: on random penetrating poses (the sphere overlaps the shape),
 *     cd_shape_distance_ccd (GJK/EPA, epa_tolerance = 1e-12 set inside
 *     src/contact/geometry.c) against the analytic answer. The tolerance is
 *     measured and derived below; it is NOT 1e-9, because libccd cannot give
 *     that (see ccd_tolerance_note).
 * (c) A convex hull (CD_SHAPE_CONVEX, the 8 corners of a box) against the
 *     analytic box: through GJK/EPA (to libccd's accuracy), and through
 *     cd_shape_distance, which the right-hand side uses for hulls (exact,
 *     face planes built at finalize: 1e-12), plus a tetrahedron.
 * (d) A NaN point gives -1 (no crash) for every shape type.
 *
 * All queries are in the shape frame (cd_shape_distance takes p there), so a
 * "random pose" of the check sphere relative to the shape is a random centre
 * p; the shape's own pose on its body only changes the frame. */
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include "scene_util.h"
#include "../src/contact/geometry.h" /* cd_geom_hull: the plane bound of open slots */
#include <math.h>
#include <string.h>

#define TOL_EXACT 1e-12

/* ---- ccd_tolerance_note ----------------------------------------------------
 * What libccd's GJK/EPA (libccd 2.x, src/ccd.c, nextSupport) can deliver with
 * epa_tolerance = tol = 1e-12:
 *  - EPA stops expanding the polytope face nearest the origin when the new
 *    support point's SQUARED distance to that face is below tol (and when
 *    |w| (h(u) - |w|) < tol, also a squared length). In lengths, the answer is
 *    therefore only good to eps = sqrt(tol) = 1e-6 m wherever the Minkowski
 *    sum is curved (every sphere-vs-shape sum is: the check sphere rounds all
 *    edges and vertices, and the final face may straddle a flat face and a
 *    rounded edge). Measured max distance error over 20000 random penetrating
 *    poses per shape: box 9.8e-7, cylinder 9.9e-7, capsule 9.97e-7, hull
 *    9.95e-7 -- right at the bound. Tolerance: TOL_CCD_D = 1.2e-6.
 *  - Tightening tol does not fix it: the EPA loop has no iteration limit
 *    (max_iterations bounds only GJK); measured on the box with the same
 *    support functions, tol = 1e-14 gives 9.8e-8 but tol = 1e-16 and 1e-18
 *    did not finish 5000 queries in 60 s. So 1e-9 is out of reach.
 *  - The normal is the normal of the final polytope face. A chord of length a
 *    on a surface of curvature radius rho sags by a^2/(8 rho); with the sag
 *    bounded by eps the face normal may be off by ~a/rho = sqrt(8 eps/rho).
 *    With rho = r = 0.1 m (the rounded edges of shape + check sphere) that is
 *    8.9e-3; measured max component error 1.1e-2 (hull), 1.0e-2 (capsule),
 *    9.2e-3 (box), 6.6e-3 (cylinder). Tolerance: TOL_CCD_N = 2e-2.
 *  - The contact point is s = p - d n, so its error is bounded by
 *    |dd| + |d| |dn|: checked per point with the two tolerances above.
 *  - The sphere shape (Minkowski sum: a sphere of radius R + r) is worse: in
 *    ~0.2 % of random poses libccd returns depth exactly 0 ("touching
 *    contact" exit of simplexToPolytope*) or an error of 1e-4..2e-3 (its EPA
 *    replaces the nearest face by a tetrahedron without removing the other
 *    faces the new point sees, so the polytope can become non-convex).
 *    Those are libccd failures, not capdyn's; the test counts them, logs
 *    them and requires them to stay below 1 % of the queries. */
#define TOL_CCD_D 1.2e-6
#define TOL_CCD_N 2e-2
#define CHECK_R 0.1

/* xorshift64: deterministic random numbers (no rand()) */
static unsigned long long rng_state = 88172645463325252ULL;
static double urand(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}

static double maxdiff3(const double *a, const double *b)
{
    double m = 0;
    int i;
    for (i = 0; i < 3; i++)
        if (fabs(a[i] - b[i]) > m) m = fabs(a[i] - b[i]);
    return m;
}

/* The shapes used throughout, on one fixed body. */
enum { SH_PLANE, SH_SPHERE, SH_BOX, SH_CYL, SH_CAPS, SH_HULL, SH_N };
static const double SPHERE_R = 0.5;
static const double BOX_H[3] = {0.3, 0.4, 0.5};
static const double CYL_R = 0.3, CYL_L = 0.5;
static const double CAPS_R = 0.2, CAPS_L = 0.4;

static cd_model *shapes_model(void)
{
    cd_model *m = cd_model_create();
    cd_system_desc s = cd_system_desc_default();
    cd_error e;
    double sz[3], verts[24];
    int sys, b, i, id[SH_N];
    cr_assert(m);
    s.type = CD_BASE_FIXED;
    s.name = "shapes";
    sys = cd_model_add_system(m, &s, &e);
    cr_assert(sys >= 0, "%s", e.msg);
    b = m->sys_body_adr[sys];
    for (i = 0; i < 8; i++) {
        verts[3 * i] = (i & 1) ? BOX_H[0] : -BOX_H[0];
        verts[3 * i + 1] = (i & 2) ? BOX_H[1] : -BOX_H[1];
        verts[3 * i + 2] = (i & 4) ? BOX_H[2] : -BOX_H[2];
    }
    id[SH_PLANE] = cd_model_add_shape(m, b, CD_SHAPE_PLANE, NULL, NULL, NULL, NULL, 0, &e);
    sz[0] = SPHERE_R; sz[1] = sz[2] = 0;
    id[SH_SPHERE] = cd_model_add_shape(m, b, CD_SHAPE_SPHERE, NULL, NULL, sz, NULL, 0, &e);
    id[SH_BOX] = cd_model_add_shape(m, b, CD_SHAPE_BOX, NULL, NULL, BOX_H, NULL, 0, &e);
    sz[0] = CYL_R; sz[1] = CYL_L;
    id[SH_CYL] = cd_model_add_shape(m, b, CD_SHAPE_CYLINDER, NULL, NULL, sz, NULL, 0, &e);
    sz[0] = CAPS_R; sz[1] = CAPS_L;
    id[SH_CAPS] = cd_model_add_shape(m, b, CD_SHAPE_CAPSULE, NULL, NULL, sz, NULL, 0, &e);
    id[SH_HULL] = cd_model_add_shape(m, b, CD_SHAPE_CONVEX, NULL, NULL, NULL, verts, 8, &e);
    for (i = 0; i < SH_N; i++) cr_assert_eq(id[i], i, "shape %d: %s", i, e.msg);
    cr_assert_eq(cd_model_finalize(m, &e), CD_OK, "%s", e.msg);
    return m;
}

/* cd_shape_distance at p against the expected closed-form answer */
static void expect_exact(const cd_model *m, int shape, const char *what, double px, double py, double pz,
                         double d_exp, const double n_exp[3], const double s_exp[3])
{
    double p[3] = {px, py, pz}, d, n[3], s[3];
    int rc = cd_shape_distance(m, shape, p, CHECK_R, &d, n, s);
    cr_expect_eq(rc, 0, "%s: rc %d", what, rc);
    cr_expect_leq(fabs(d - d_exp), TOL_EXACT, "%s: d = %.17g, expected %.17g", what, d, d_exp);
    cr_expect_leq(maxdiff3(n, n_exp), TOL_EXACT, "%s: n = (%.17g %.17g %.17g), expected (%.17g %.17g %.17g)",
                  what, n[0], n[1], n[2], n_exp[0], n_exp[1], n_exp[2]);
    cr_expect_leq(maxdiff3(s, s_exp), TOL_EXACT, "%s: s = (%.17g %.17g %.17g), expected (%.17g %.17g %.17g)",
                  what, s[0], s[1], s[2], s_exp[0], s_exp[1], s_exp[2]);
}

#define V3(a, b, c) ((const double[3]){(a), (b), (c)})

Test(contact_geometry, plane_closed_form)
{
    /* half-space z <= 0: d = z, n = +z, s = (x, y, 0) */
    cd_model *m = shapes_model();
    expect_exact(m, SH_PLANE, "plane above", 0.3, -0.7, 0.25, 0.25, V3(0, 0, 1), V3(0.3, -0.7, 0));
    expect_exact(m, SH_PLANE, "plane below", 1.0, 2.0, -0.125, -0.125, V3(0, 0, 1), V3(1.0, 2.0, 0));
    cd_model_free(m);
}

Test(contact_geometry, sphere_closed_form)
{
    /* p = rho u: d = rho - R, n = u, s = R u; u = (1, -2, 2)/3 */
    cd_model *m = shapes_model();
    double u[3] = {1.0 / 3, -2.0 / 3, 2.0 / 3}, d, n[3], s[3], o[3] = {0, 0, 0};
    int i;
    const double rho[3] = {0.7, 0.45, SPHERE_R + 1e-9};
    for (i = 0; i < 3; i++)
        expect_exact(m, SH_SPHERE, i == 0 ? "sphere outside" : (i == 1 ? "sphere inside" : "sphere at 1e-9"),
                     rho[i] * u[0], rho[i] * u[1], rho[i] * u[2], rho[i] - SPHERE_R, u,
                     V3(SPHERE_R * u[0], SPHERE_R * u[1], SPHERE_R * u[2]));
    /* at the centre every direction is nearest: d = -R, any unit n, s = R n */
    cr_expect_eq(cd_shape_distance(m, SH_SPHERE, o, CHECK_R, &d, n, s), 0);
    cr_expect_leq(fabs(d + SPHERE_R), TOL_EXACT, "d = %.17g at the centre", d);
    cr_expect_leq(fabs(sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) - 1), TOL_EXACT);
    cr_expect_leq(maxdiff3(s, V3(SPHERE_R * n[0], SPHERE_R * n[1], SPHERE_R * n[2])), TOL_EXACT);
    cd_model_free(m);
}

Test(contact_geometry, box_closed_form)
{
    /* half extents (0.3, 0.4, 0.5) */
    cd_model *m = shapes_model();
    /* inside: the nearest face (depths 0.2, 0.2, 0.05 -> +z) */
    expect_exact(m, SH_BOX, "box inside +z", 0.1, -0.2, 0.45, -0.05, V3(0, 0, 1), V3(0.1, -0.2, 0.5));
    /* inside: depths 0.03, 0.3, 0.45 -> -x */
    expect_exact(m, SH_BOX, "box inside -x", -0.27, 0.1, 0.05, -0.03, V3(-1, 0, 0), V3(-0.3, 0.1, 0.05));
    /* outside the +y face */
    expect_exact(m, SH_BOX, "box outside +y", 0.1, 0.46, -0.2, 0.06, V3(0, 1, 0), V3(0.1, 0.4, -0.2));
    /* edge region (+x, -y): offset (0.03, -0.04, .) -> d = 0.05, n = (0.6, -0.8, 0) */
    expect_exact(m, SH_BOX, "box edge", 0.33, -0.44, 0.1, 0.05, V3(0.6, -0.8, 0), V3(0.3, -0.4, 0.1));
    /* vertex region: offset (0.02, 0.04, -0.04) -> d = 0.06, n = (1, 2, -2)/3 */
    expect_exact(m, SH_BOX, "box vertex", 0.32, 0.44, -0.54, 0.06, V3(1.0 / 3, 2.0 / 3, -2.0 / 3),
                 V3(0.3, 0.4, -0.5));
    cd_model_free(m);
}

Test(contact_geometry, cylinder_closed_form)
{
    /* radius 0.3, half length 0.5 along z; e_r the radial unit vector */
    cd_model *m = shapes_model();
    double c = cos(0.7), s = sin(0.7), c2 = cos(-2.3), s2 = sin(-2.3);
    /* side, outside and inside */
    expect_exact(m, SH_CYL, "cyl side out", 0.4 * c, 0.4 * s, 0.2, 0.1, V3(c, s, 0), V3(0.3 * c, 0.3 * s, 0.2));
    expect_exact(m, SH_CYL, "cyl side in", 0.25 * c2, 0.25 * s2, -0.1, -0.05, V3(c2, s2, 0),
                 V3(0.3 * c2, 0.3 * s2, -0.1));
    /* caps, outside (top) and inside (bottom; radial depth 0.2 > axial 0.03) */
    expect_exact(m, SH_CYL, "cyl cap out", 0.1 * c, 0.1 * s, 0.6, 0.1, V3(0, 0, 1), V3(0.1 * c, 0.1 * s, 0.5));
    expect_exact(m, SH_CYL, "cyl cap in", 0.1 * c2, 0.1 * s2, -0.47, -0.03, V3(0, 0, -1),
                 V3(0.1 * c2, 0.1 * s2, -0.5));
    /* rims: (dr, dz) = (0.03, 0.04) and (0.04, -0.03) -> d = 0.05 */
    expect_exact(m, SH_CYL, "cyl rim top", 0.33 * c, 0.33 * s, 0.54, 0.05, V3(0.6 * c, 0.6 * s, 0.8),
                 V3(0.3 * c, 0.3 * s, 0.5));
    expect_exact(m, SH_CYL, "cyl rim bottom", 0.34 * c2, 0.34 * s2, -0.53, 0.05, V3(0.8 * c2, 0.8 * s2, -0.6),
                 V3(0.3 * c2, 0.3 * s2, -0.5));
    cd_model_free(m);
}

Test(contact_geometry, capsule_closed_form)
{
    /* radius 0.2, axis segment z in [-0.4, 0.4] */
    cd_model *m = shapes_model();
    double c = cos(2.0), s = sin(2.0);
    const double u[3] = {2.0 / 3, -1.0 / 3, 2.0 / 3}, w[3] = {0, 0.6, -0.8};
    /* side: radial distance to the axis minus R */
    expect_exact(m, SH_CAPS, "capsule side out", 0.3 * c, 0.3 * s, 0.1, 0.1, V3(c, s, 0),
                 V3(0.2 * c, 0.2 * s, 0.1));
    expect_exact(m, SH_CAPS, "capsule side in", 0.15 * c, 0.15 * s, -0.3, -0.05, V3(c, s, 0),
                 V3(0.2 * c, 0.2 * s, -0.3));
    /* hemispherical ends: distance to the end point of the segment minus R */
    expect_exact(m, SH_CAPS, "capsule top out", 0.3 * u[0], 0.3 * u[1], 0.4 + 0.3 * u[2], 0.1, u,
                 V3(0.2 * u[0], 0.2 * u[1], 0.4 + 0.2 * u[2]));
    expect_exact(m, SH_CAPS, "capsule bottom in", 0.1 * w[0], 0.1 * w[1], -0.4 + 0.1 * w[2], -0.1, w,
                 V3(0.2 * w[0], 0.2 * w[1], -0.4 + 0.2 * w[2]));
    cd_model_free(m);
}

Test(contact_geometry, nan_point_is_rejected)
{
    /* a NaN centre (e.g. from a diverged state) must come back as -1, for the
     * analytic path and for libccd (which segfaults on NaN poses) */
    cd_model *m = shapes_model();
    double p[3] = {0.1, NAN, 0.2}, d, n[3], s[3];
    int k;
    for (k = 0; k < SH_N; k++) {
        cr_expect_eq(cd_shape_distance(m, k, p, CHECK_R, &d, n, s), -1, "shape %d", k);
        cr_expect_eq(cd_shape_distance_ccd(m, k, p, CHECK_R, &d, n, s), -1, "shape %d (ccd)", k);
    }
    p[1] = 0.0;
    p[2] = INFINITY;
    for (k = 0; k < SH_N; k++) cr_expect_eq(cd_shape_distance(m, k, p, CHECK_R, &d, n, s), -1, "shape %d, inf", k);
    cd_model_free(m);
}

/* ---- random penetrating poses against libccd -------------------------------- */
typedef struct {
    int n, bad;            /* queries, answers outside tolerance */
    double ed, en, es;     /* max errors of distance, normal (component), point (excess over bound) */
    double worst_p[3], worst_ed;
} ccd_stats;

/* Compares `ans` (through `query`) with the analytic reference shape `ref`
 * on npts random centres p whose sphere (radius CHECK_R) penetrates the
 * shape by at least 1e-3 m. */
static ccd_stats compare_random(const cd_model *m, int ref, int shape, int use_ccd, int npts,
                                const double ext[3])
{
    ccd_stats st;
    int tries = 0;
    memset(&st, 0, sizeof st);
    while (st.n < npts && tries < 100 * npts) {
        double p[3], d0, n0[3], s0[3], d1, n1[3], s1[3], ed, en, es;
        int j, rc;
        tries++;
        for (j = 0; j < 3; j++) p[j] = (2 * urand() - 1) * ext[j];
        cr_assert_eq(cd_shape_distance(m, ref, p, CHECK_R, &d0, n0, s0), 0);
        if (!(d0 < CHECK_R - 1e-3)) continue;
        st.n++;
        rc = use_ccd ? cd_shape_distance_ccd(m, shape, p, CHECK_R, &d1, n1, s1)
                     : cd_shape_distance(m, shape, p, CHECK_R, &d1, n1, s1);
        if (rc != 0) { /* a penetrating pose must not be reported separated or bad */
            st.bad++;
            continue;
        }
        ed = fabs(d1 - d0);
        en = maxdiff3(n1, n0);
        /* s = p - d n: error bounded by |dd| + |d| |dn| (componentwise) */
        es = maxdiff3(s1, s0) - (ed + fabs(d0) * en) - 1e-14;
        if (ed > st.ed) { st.ed = ed; memcpy(st.worst_p, p, sizeof p); st.worst_ed = d1 - d0; }
        if (en > st.en) st.en = en;
        if (es > st.es) st.es = es;
        if (ed > TOL_CCD_D || en > TOL_CCD_N || es > 0) st.bad++;
    }
    cr_assert_eq(st.n, npts, "could not place %d penetrating points", npts);
    return st;
}

static void expect_within(const ccd_stats *st, const char *what, int allowed_bad)
{
    cr_log_info("%s: %d poses, max |dd| %.3e (tol %.1e), max |dn| %.3e (tol %.1e), out of tolerance %d",
                what, st->n, st->ed, TOL_CCD_D, st->en, TOL_CCD_N, st->bad);
    cr_expect_leq(st->bad, allowed_bad,
                  "%s: %d of %d poses out of tolerance; worst |dd| %.3e at p = (%.17g, %.17g, %.17g), max |dn| %.3e",
                  what, st->bad, st->n, st->ed, st->worst_p[0], st->worst_p[1], st->worst_p[2], st->en);
}

Test(contact_geometry, analytic_matches_libccd_epa)
{
    /* See ccd_tolerance_note for the tolerances (derived from libccd's EPA
     * stopping rule, then measured). 2000 poses per shape. */
    cd_model *m = shapes_model();
    const double ext_s[3] = {0.65, 0.65, 0.65}, ext_b[3] = {0.45, 0.55, 0.65};
    const double ext_c[3] = {0.45, 0.45, 0.65}, ext_k[3] = {0.35, 0.35, 0.75};
    ccd_stats st;
    rng_state = 88172645463325252ULL;
    st = compare_random(m, SH_BOX, SH_BOX, 1, 2000, ext_b);
    expect_within(&st, "box (EPA)", 0);
    st = compare_random(m, SH_CYL, SH_CYL, 1, 2000, ext_c);
    expect_within(&st, "cylinder (EPA)", 0);
    st = compare_random(m, SH_CAPS, SH_CAPS, 1, 2000, ext_k);
    expect_within(&st, "capsule (EPA)", 0);
    /* libccd's own failures on the sphere (see the note): at most 1 % */
    st = compare_random(m, SH_SPHERE, SH_SPHERE, 1, 2000, ext_s);
    expect_within(&st, "sphere (EPA)", st.n / 100);
    /* cr_log_warn would make Criterion exit 1 although every test passed */
    if (st.bad) cr_log_info("sphere: libccd GJK/EPA wrong on %d of %d poses (depth 0 or 1e-4..1e-3 errors)", st.bad, st.n);
    cd_model_free(m);
}

Test(contact_geometry, convex_hull_epa_matches_box)
{
    /* The hull of the box's 8 corners is the box: through GJK/EPA it gives the
     * analytic box answer within the EPA tolerances (ccd_tolerance_note). */
    cd_model *m = shapes_model();
    const double ext_b[3] = {0.45, 0.55, 0.65};
    ccd_stats st;
    rng_state = 0x9E3779B97F4A7C15ULL;
    st = compare_random(m, SH_BOX, SH_HULL, 1, 2000, ext_b);
    expect_within(&st, "hull (EPA) vs box", 0);
    cd_model_free(m);
}

Test(contact_geometry, convex_hull_distance_matches_box)
{
    /* cd_shape_distance on a hull is what the right-hand side uses for
     * CD_SHAPE_CONVEX contacts. (With libccd's MPR, 767 of these 2000 poses
     * were wrong by up to 0.38 m: its depth is along the centre ray.) For
     * penetrating poses it must agree with the analytic box at least as well
     * as GJK/EPA does (same tolerances; the exact test is below). On the principal axes (the ray
     * from the hull's centre through p hits a face squarely) any method must
     * be exact: checked to 1e-9. */
    cd_model *m = shapes_model();
    const double ext_b[3] = {0.45, 0.55, 0.65};
    double p[3] = {0, 0, 0.55}, d, n[3], s[3];
    ccd_stats st;
    cr_expect_eq(cd_shape_distance(m, SH_HULL, p, CHECK_R, &d, n, s), 0);
    cr_expect_leq(fabs(d - 0.05), 1e-9, "on-axis hull d = %.17g, expected 0.05", d);
    cr_expect_leq(maxdiff3(n, V3(0, 0, 1)), 1e-9);
    rng_state = 0xD1B54A32D192ED03ULL;
    st = compare_random(m, SH_BOX, SH_HULL, 0, 2000, ext_b);
    expect_within(&st, "hull (cd_shape_distance) vs box", 0);
    cd_model_free(m);
}

Test(contact_geometry, convex_hull_is_exact_like_the_box)
{
    /* The hull distance (face planes inside, nearest face triangle outside)
     * is exact: against the analytic box it agrees to 1e-12 on random points
     * inside and outside, apart from points within 1e-6 of an inside tie
     * between two faces (medial planes), where both answers are right but
     * may name different faces. Also a tetrahedron, whose closed form is easy:
     * the point (0.1, 0.1, 0.1) lies 0.1 inside the faces x = 0, y = 0, z = 0
     * and (1 - 0.3)/sqrt(3) inside the slanted face: d = -0.1. */
    cd_model *m = shapes_model();
    int i, checked = 0;
    rng_state = 0x2545F4914F6CDD1DULL;
    for (i = 0; i < 4000; i++) {
        double p[3], db, dh, nb[3], nh[3], sb[3], sh[3], gap[3];
        int k;
        for (k = 0; k < 3; k++) p[k] = (2.0 * urand() - 1.0) * 1.6 * BOX_H[k];
        /* skip near-ties inside: the two smallest face distances within 1e-6 */
        for (k = 0; k < 3; k++) gap[k] = BOX_H[k] - fabs(p[k]);
        if (gap[0] > 0 && gap[1] > 0 && gap[2] > 0) {
            double a = gap[0], b = gap[1], c = gap[2], lo = a < b ? a : b, mid;
            lo = lo < c ? lo : c;
            mid = (a == lo) ? (b < c ? b : c) : ((b == lo) ? (a < c ? a : c) : (a < b ? a : b));
            if (mid - lo < 1e-6) continue;
        }
        cr_assert_eq(cd_shape_distance(m, SH_BOX, p, CHECK_R, &db, nb, sb), 0);
        cr_assert_eq(cd_shape_distance(m, SH_HULL, p, CHECK_R, &dh, nh, sh), 0);
        cr_expect_leq(fabs(db - dh), 1e-12, "p = (%g %g %g): box %.17g hull %.17g", p[0], p[1], p[2], db, dh);
        cr_expect_leq(maxdiff3(nb, nh), 1e-12, "p = (%g %g %g): normals differ", p[0], p[1], p[2]);
        cr_expect_leq(maxdiff3(sb, sh), 1e-12, "p = (%g %g %g): surface points differ", p[0], p[1], p[2]);
        checked++;
    }
    cr_expect_gt(checked, 3900);
    cd_model_free(m);
    {
        cd_model *t = cd_model_create();
        cd_system_desc s = cd_system_desc_default();
        cd_error e;
        double v[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}, p[3] = {0.1, 0.1, 0.1}, q[3] = {1, 1, 1};
        double d, n[3], sp[3];
        int sh;
        s.type = CD_BASE_FIXED;
        cd_model_add_system(t, &s, &e);
        sh = cd_model_add_shape(t, 0, CD_SHAPE_CONVEX, NULL, NULL, NULL, v, 4, &e);
        cr_assert(sh == 0, "%s", e.msg);
        cr_assert_eq(cd_model_finalize(t, &e), CD_OK, "%s", e.msg);
        cr_expect_eq(t->shape_face_num[0], 4, "a tetrahedron has 4 faces");
        cr_assert_eq(cd_shape_distance(t, 0, p, 0, &d, n, sp), 0);
        cr_expect_leq(fabs(d + 0.1), 1e-15, "d = %.17g", d);
        /* (1,1,1) is outside the slanted face x + y + z = 1: d = 2/sqrt(3) */
        cr_assert_eq(cd_shape_distance(t, 0, q, 0, &d, n, sp), 0);
        cr_expect_leq(fabs(d - 2.0 / sqrt(3.0)), 1e-15, "d = %.17g", d);
        cr_expect_leq(fabs(n[0] - 1.0 / sqrt(3.0)), 1e-15);
        cd_model_free(t);
    }
}

/* the face triangles of hull shape 0 of a one-shape model built from v */
static cd_model *hull_model(const double *v, int nv)
{
    cd_model *t = cd_model_create();
    cd_system_desc s = cd_system_desc_default();
    cd_error e;
    s.type = CD_BASE_FIXED;
    cd_model_add_system(t, &s, &e);
    cr_assert(cd_model_add_shape(t, 0, CD_SHAPE_CONVEX, NULL, NULL, NULL, v, nv, &e) == 0, "%s", e.msg);
    cr_assert_eq(cd_model_finalize(t, &e), CD_OK, "%s", e.msg);
    return t;
}

/* number of face planes by face_run (its runs must tile the triangles, each
 * run's planes bitwise equal); -1 if they do not */
static int hull_planes(const cd_model *t)
{
    int f = 0, np = 0, nf = t->shape_face_num[0], fa = t->shape_face_adr[0];
    while (f < nf) {
        int r = t->face_run[fa + f], j;
        if (r < 1 || f + r > nf) return -1;
        for (j = f + 1; j < f + r; j++)
            if (t->face_run[fa + j] != 0 ||
                memcmp(t->face_plane + 4 * (fa + j), t->face_plane + 4 * (fa + f), 4 * sizeof(double)))
                return -1;
        f += r;
        np++;
    }
    return np;
}

/* total area of the face triangles; counts those not wound outward (by
 * their stored plane) or of zero area */
static double hull_area(const cd_model *t, int *bad)
{
    double area = 0;
    int f;
    *bad = 0;
    for (f = 0; f < t->shape_face_num[0]; f++) {
        const int *fv = t->face_vert + 3 * (t->shape_face_adr[0] + f);
        const double *a = t->vert + 3 * fv[0], *b = t->vert + 3 * fv[1], *c = t->vert + 3 * fv[2];
        const double *pl = t->face_plane + 4 * (t->shape_face_adr[0] + f);
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double x[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        double nx = x[0] * pl[0] + x[1] * pl[1] + x[2] * pl[2];
        if (!(nx > 1e-12)) (*bad)++;
        area += 0.5 * sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    }
    return area;
}

Test(contact_geometry, hull_faces_tile_the_surface_once)
{
    /* The face triangles found at finalize cover the hull's surface exactly
     * once, wound outward: their areas add up to the surface area (closed
     * form, to 1e-12 relative) and a flat face of k corners gives k - 2
     * triangles, whatever other vertices lie on it (edge midpoints, face
     * centres add none). Cases: a cube, the same cube with every edge
     * midpoint and face centre added, and the lopsided pentagonal prism of
     * scenarios/soft_wrap.toml (5 rectangles of 2 triangles, 2 pentagons of 3:
     * 16), each face plane once (face_run: 6 and 7). Every coplanar triple
     * of the prism would give 40 overlapping triangles, and the query time
     * grows with their number. */
    double cube[3 * 26], prism[30], area, pent = 0, perim = 0, prism_area;
    int nc = 0, i, j, k, bad;
    cd_model *t;
    for (i = -1; i <= 1; i++)
        for (j = -1; j <= 1; j++)
            for (k = -1; k <= 1; k++) {
                if (!i && !j && !k) continue;
                cube[3 * nc] = 0.1 * i; cube[3 * nc + 1] = 0.1 * j; cube[3 * nc + 2] = 0.1 * k;
                nc++;
            }
    /* the 8 corners first (|i| = |j| = |k| = 1) */
    {
        double corners[24];
        int m = 0;
        for (i = 0; i < nc; i++)
            if (cube[3 * i] != 0 && cube[3 * i + 1] != 0 && cube[3 * i + 2] != 0) {
                memcpy(corners + 3 * m, cube + 3 * i, 3 * sizeof(double));
                m++;
            }
        cr_assert_eq(m, 8);
        t = hull_model(corners, 8);
        area = hull_area(t, &bad);
        cr_expect_eq(t->shape_face_num[0], 12, "a cube: %d triangles, expected 12", t->shape_face_num[0]);
        cr_expect_eq(hull_planes(t), 6, "a cube: %d face planes by face_run, expected 6", hull_planes(t));
        cr_expect_eq(bad, 0, "%d triangles not wound outward", bad);
        cr_expect_leq(fabs(area - 6 * 0.04) / 0.24, 1e-12, "cube area %.17g, expected 0.24", area);
        cd_model_free(t);
    }
    t = hull_model(cube, nc);
    area = hull_area(t, &bad);
    cr_expect_eq(t->shape_face_num[0], 12, "a cube with 18 extra boundary vertices: %d triangles, expected 12",
                 t->shape_face_num[0]);
    cr_expect_eq(bad, 0, "%d triangles not wound outward or of zero area", bad);
    cr_expect_leq(fabs(area - 0.24) / 0.24, 1e-12, "cube area %.17g, expected 0.24", area);
    cd_model_free(t);
    {
        static const double xy[10] = {-0.04375, -0.025, 0.0375, -0.0375, 0.05, 0.01875, 0.00625, 0.05, -0.0375, 0.0375};
        for (i = 0; i < 5; i++) {
            int n = (i + 1) % 5;
            double dx = xy[2 * n] - xy[2 * i], dy = xy[2 * n + 1] - xy[2 * i + 1];
            pent += 0.5 * (xy[2 * i] * xy[2 * n + 1] - xy[2 * n] * xy[2 * i + 1]);
            perim += sqrt(dx * dx + dy * dy);
            prism[3 * i] = prism[3 * i + 15] = xy[2 * i];
            prism[3 * i + 1] = prism[3 * i + 16] = xy[2 * i + 1];
            prism[3 * i + 2] = -0.03;
            prism[3 * i + 17] = 0.03;
        }
        prism_area = 2 * fabs(pent) + perim * 0.06;
        t = hull_model(prism, 10);
        area = hull_area(t, &bad);
        cr_expect_eq(t->shape_face_num[0], 16, "the soft_wrap prism: %d triangles, expected 16", t->shape_face_num[0]);
        cr_expect_eq(hull_planes(t), 7, "the prism: %d face planes by face_run, expected 7", hull_planes(t));
        cr_expect_eq(bad, 0, "%d triangles not wound outward", bad);
        cr_expect_leq(fabs(area - prism_area) / prism_area, 1e-12, "prism area %.17g, expected %.17g", area, prism_area);
        cd_model_free(t);
    }
}

/* ---- the hull query's pruning and the broad phase of open slots ---------- */

/* nearest point of triangle abc to p (by regions: vertices, edges, face) */
static void tri_closest(const double p[3], const double a[3], const double b[3], const double c[3], double q[3])
{
    double ab[3], ac[3], ap[3], bp[3], cp[3], d1, d2, d3, d4, d5, d6, va, vb, vc, v, w, den;
    int k;
    for (k = 0; k < 3; k++) { ab[k] = b[k] - a[k]; ac[k] = c[k] - a[k]; ap[k] = p[k] - a[k]; bp[k] = p[k] - b[k]; cp[k] = p[k] - c[k]; }
#define DOT3(x, y) ((x)[0] * (y)[0] + (x)[1] * (y)[1] + (x)[2] * (y)[2])
    d1 = DOT3(ab, ap); d2 = DOT3(ac, ap);
    if (d1 <= 0 && d2 <= 0) { memcpy(q, a, 3 * sizeof(double)); return; }
    d3 = DOT3(ab, bp); d4 = DOT3(ac, bp);
    if (d3 >= 0 && d4 <= d3) { memcpy(q, b, 3 * sizeof(double)); return; }
    vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) { v = d1 / (d1 - d3); for (k = 0; k < 3; k++) q[k] = a[k] + v * ab[k]; return; }
    d5 = DOT3(ab, cp); d6 = DOT3(ac, cp);
    if (d6 >= 0 && d5 <= d6) { memcpy(q, c, 3 * sizeof(double)); return; }
    vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) { w = d2 / (d2 - d6); for (k = 0; k < 3; k++) q[k] = a[k] + w * ac[k]; return; }
    va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        for (k = 0; k < 3; k++) q[k] = b[k] + w * (c[k] - b[k]);
        return;
    }
    den = 1.0 / (va + vb + vc);
    v = vb * den; w = vc * den;
    for (k = 0; k < 3; k++) q[k] = a[k] + ab[k] * v + ac[k] * w;
#undef DOT3
}

/* A finalized model of one fixed system holding the hull of 300 random
 * points on the ellipsoid of semi-axes 0.3, 0.2, 0.12 m (hundreds of faces),
 * drawn from seed; *sh its shape. */
static cd_model *ellipsoid_hull(unsigned long long seed, int *sh)
{
    cd_model *m = cd_model_create();
    cd_system_desc s = cd_system_desc_default();
    cd_error e;
    double verts[3 * 300];
    int sys, i, k;
    s.type = CD_BASE_FIXED;
    s.name = "hull";
    sys = cd_model_add_system(m, &s, &e);
    rng_state = seed;
    for (i = 0; i < 300; i++) {
        double u[3], n;
        do {
            for (k = 0; k < 3; k++) u[k] = 2.0 * urand() - 1.0;
            n = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        } while (n < 0.1 || n > 1.0);
        verts[3 * i] = 0.3 * u[0] / n; verts[3 * i + 1] = 0.2 * u[1] / n; verts[3 * i + 2] = 0.12 * u[2] / n;
    }
    *sh = cd_model_add_shape(m, m->sys_body_adr[sys], CD_SHAPE_CONVEX, NULL, NULL, NULL, verts, 300, &e);
    cr_assert(*sh >= 0, "%s", e.msg);
    cr_assert_eq(cd_model_finalize(m, &e), CD_OK, "%s", e.msg);
    return m;
}

Test(contact_geometry, hull_query_outside_equals_the_scan_over_every_face)
{
    /* A hull of 300 random points on an ellipsoid (hundreds of faces): for
     * 3000 random outside points the query, which only looks at faces that
     * face p and stops at faces no nearer than its best, must give the
     * distance of the brute-force minimum over every face triangle, to 1e-12. */
    double worst = 0;
    int sh, i, k, nout = 0;
    cd_model *m = ellipsoid_hull(0x853C49E6748FEA9BULL, &sh);
    cr_log_info("hull: %d faces", m->shape_face_num[sh]);
    for (i = 0; i < 3000; i++) {
        double p[3], d, n[3], sp[3], best = HUGE_VAL;
        int f;
        for (k = 0; k < 3; k++) p[k] = (2.0 * urand() - 1.0) * 0.5;
        cr_assert_eq(cd_shape_distance(m, sh, p, 0.0, &d, n, sp), 0);
        if (d <= 0) continue;
        nout++;
        for (f = 0; f < m->shape_face_num[sh]; f++) {
            const int *fv = m->face_vert + 3 * (m->shape_face_adr[sh] + f);
            double q[3], dd;
            tri_closest(p, m->vert + 3 * fv[0], m->vert + 3 * fv[1], m->vert + 3 * fv[2], q);
            dd = sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
            if (dd < best) best = dd;
        }
        if (fabs(d - best) > worst) worst = fabs(d - best);
    }
    cr_log_info("%d outside points, largest difference to the full scan %.3g m", nout, worst);
    cr_expect_gt(nout, 1000, "most sample points are outside the hull");
    cr_expect_leq(worst, 1e-12, "pruned query vs full scan: %.3g m", worst);
    cd_model_free(m);
}

Test(contact_geometry, hull_plane_bound_is_a_lower_bound_beyond_the_margin)
{
    /* An open slot's hull query stops at the face planes when one of them is
     * farther than r + 1e-6 (cd_geom_hull's `beyond`): it reports the largest
     * plane distance, which no point of the hull can beat (the hull lies
     * behind each plane). On 4000 random points around a 300-vertex hull,
     * for three thresholds: a bounded answer is above the threshold and at
     * most the exact distance (1e-15), its point lies on its plane (1e-15);
     * an exact answer is bit for bit the unbounded query's. */
    double worst_plane = 0;
    static const double beyond[3] = {1e-3, 1e-2, 5e-2};
    int sh, i, k, b, nbound = 0, nexact = 0, bad = 0;
    cd_model *m = ellipsoid_hull(0x2545F4914F6CDD1DULL, &sh);
    for (i = 0; i < 4000; i++) {
        const int fa = m->shape_face_adr[sh], nf = m->shape_face_num[sh];
        static const double box[3] = {0.36, 0.26, 0.18}; /* the hull's semi-axes + 6 cm */
        double p[3], dx, nx[3], sx[3];
        for (k = 0; k < 3; k++) p[k] = (2.0 * urand() - 1.0) * box[k];
        cr_assert_eq(cd_geom_hull(m->vert, m->face_vert + 3 * fa, m->face_plane + 4 * fa, m->face_run + fa, nf, p,
                                  HUGE_VAL, &dx, nx, sx), 0);
        for (b = 0; b < 3; b++) {
            double db, nb[3], sb[3];
            int st = cd_geom_hull(m->vert, m->face_vert + 3 * fa, m->face_plane + 4 * fa, m->face_run + fa, nf, p,
                                  beyond[b], &db, nb, sb);
            if (st == 1) {
                double off = fabs(nb[0] * sb[0] + nb[1] * sb[1] + nb[2] * sb[2] -
                                  (nb[0] * p[0] + nb[1] * p[1] + nb[2] * p[2] - db));
                nbound++;
                if (!(db > beyond[b]) || db > dx + 1e-15) bad++;
                if (off > worst_plane) worst_plane = off;
            } else if (st == 0) {
                nexact++;
                if (db != dx || memcmp(nb, nx, sizeof nb) || memcmp(sb, sx, sizeof sb)) bad++;
            } else {
                bad++;
            }
        }
    }
    cr_log_info("%d bounded and %d exact answers, largest off-plane %.3g m", nbound, nexact, worst_plane);
    cr_expect_gt(nbound, 1000, "the bound is taken for far points");
    cr_expect_gt(nexact, 1000, "near and inside points get the exact query");
    cr_expect_eq(bad, 0, "%d answers break the bound or differ from the exact query", bad);
    cr_expect_leq(worst_plane, 1e-15, "the bound's point is on its plane: %.3g", worst_plane);
    cd_model_free(m);
}

Test(contact_geometry, broad_phase_keeps_open_slots_open_and_onsets_exact)
{
    /* A ball (check sphere r = 0.05) flies at 1 m/s along -x toward a box
     * hull (half extents 0.3, 0.4, 0.5; bounding sphere sqrt(0.5) = 0.707)
     * from x = 3: while it is outside the bounding sphere the slot's x is the
     * gap to that sphere (culled: no hull query), never above -1e-6 and never
     * below the true x; the onset is at (3 - 0.3 - 0.05) / 1 = 2.65 s to
     * 1e-9 s, located through the exact query once the ball is inside. */
    cd_model *m = cd_model_create();
    cd_error e;
    cd_data *d;
    double verts[24], pos[3] = {3.0, 0, 0}, vel[3] = {-1.0, 0, 0}, zero[3] = {0, 0, 0};
    int ground, ball, sh, i, lid;
    cd_contact_law law = cd_contact_law_default();
    ground = add_system(m, "ground", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    for (i = 0; i < 8; i++) {
        verts[3 * i] = (i & 1) ? BOX_H[0] : -BOX_H[0];
        verts[3 * i + 1] = (i & 2) ? BOX_H[1] : -BOX_H[1];
        verts[3 * i + 2] = (i & 4) ? BOX_H[2] : -BOX_H[2];
    }
    sh = cd_model_add_shape(m, m->sys_body_adr[ground], CD_SHAPE_CONVEX, NULL, NULL, NULL, verts, 8, &e);
    cr_assert(sh >= 0, "%s", e.msg);
    ball = add_system(m, "ball", CD_BASE_FREE, 1.0, 1e-3, pos, vel, NULL);
    cr_assert(cd_model_add_checkpoint(m, m->sys_body_adr[ball], zero, 0.05, &e) >= 0, "%s", e.msg);
    law.K = 1e4; law.D = 50; law.mu_s = law.mu_k = 0;
    lid = cd_model_add_law(m, &law, &e);
    cr_assert(lid >= 0, "%s", e.msg);
    cr_assert(cd_model_add_pair(m, ball, -1, sh, lid, &e) >= 0, "%s", e.msg);
    m->gravity[0] = m->gravity[1] = m->gravity[2] = 0;
    cr_assert_eq(cd_model_finalize(m, &e), CD_OK, "%s", e.msg);
    d = cd_data_create(m, 0, &e);
    cr_assert(d, "%s", e.msg);
    for (i = 1; i <= 26; i++) { /* to t = 2.6 s: still open */
        double p[3], dist, n[3], s[3], xt;
        cr_assert_eq(cd_sim_advance(m, d, 0.1 * i, NULL, NULL, &e), CD_OK, "%s", e.msg);
        cr_assert_eq(d->slot_mode[0], CD_MODE_OPEN, "t = %g", d->t);
        p[0] = cd_state_of(m, d, ball).pos[0]; p[1] = p[2] = 0;
        cr_assert_eq(cd_shape_distance(m, sh, p, 0.05, &dist, n, s), 0);
        xt = 0.05 - dist;
        cr_expect_leq(d->slot_x[0], -1e-6, "t = %g: x %.17g", d->t, d->slot_x[0]);
        cr_expect_geq(d->slot_x[0], xt - 1e-15, "t = %g: x %.17g below the true %.17g", d->t, d->slot_x[0], xt);
        if (p[0] - 0.05 > sqrt(0.5) + 1e-6 + 1e-3)
            cr_expect_gt(d->slot_x[0], xt + 1e-3, "t = %g: culled (x is the gap to the bounding sphere)", d->t);
    }
    cr_assert_eq(cd_sim_advance(m, d, 2.7, NULL, NULL, &e), CD_OK, "%s", e.msg);
    cr_assert_geq(d->ev_count, 1);
    cr_expect_eq(cd_data_event(d, 0)->kind, CD_EV_ONSET);
    cr_expect_leq(fabs(cd_data_event(d, 0)->t - 2.65), 1e-9, "onset at %.15g s", cd_data_event(d, 0)->t);
    cd_data_free(d);
    cd_model_free(m);
}
