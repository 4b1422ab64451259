/* Ferrari-Canny epsilon (src/analysis/grasp_quality.c, docs/grasp-quality.md)
 * against hand-computed hulls, plus invariance, monotonicity in mu, the
 * linearised cone's bounds, degenerate sets and every input error.
 *
 * Notation: wrenches are w = (f, tau / rho); in planar mode (fx, fy, tau_z/rho)
 * with tau_z = x fy - y fx (r = (x, y) from the reference point c). */
#include <criterion/criterion.h>
#include <capdyn/analysis.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

static cd_grasp_contact contact(double px, double py, double pz, double nx, double ny, double nz, double mu)
{
    cd_grasp_contact k;
    memset(&k, 0, sizeof k);
    k.p[0] = px, k.p[1] = py, k.p[2] = pz;
    k.n[0] = nx, k.n[1] = ny, k.n[2] = nz;
    k.mu = mu;
    return k;
}

static cd_grasp_quality eval_ok(const cd_grasp_contact *k, int n, const double c[3], const cd_grasp_options *o)
{
    cd_grasp_quality q;
    cd_error e = {CD_OK, ""};
    cd_status st = cd_grasp_quality_eval(k, n, c, o, &q, &e);
    cr_assert_eq(st, CD_OK, "status %d: %s", (int)st, e.msg);
    return q;
}

static void rot_axis(const double u0[3], double th, double R[9]);
static void move_grasp(const double R[9], const double x[3], cd_grasp_contact *k, int n, double c[3]);

static cd_grasp_options planar(void)
{
    cd_grasp_options o = cd_grasp_options_default();
    o.mode = CD_GRASP_PLANAR;
    return o;
}

/* ---- (a1) planar, frictionless: four contacts on a unit square ------------ */
/* Square of side 1 centred at c; one contact per side, offset s = 1/4 from the
 * side's centre line, alternating so the torques do not all share a sign:
 *   p0 = c + ( 1/2,  s), n0 = (-1, 0): tau = -y fx = +s  -> w0 = (-1, 0, +sg)
 *   p1 = c + ( s,  1/2), n1 = (0, -1): tau =  x fy = -s  -> w1 = (0, -1, -sg)
 *   p2 = c + (-1/2, -s), n2 = ( 1, 0): tau = -y fx = +s  -> w2 = ( 1, 0, +sg)
 *   p3 = c + (-s, -1/2), n3 = (0,  1): tau =  x fy = -s  -> w3 = (0,  1, -sg)
 * with sg = s / rho. The hull is the tetrahedron w0..w3; w0+w1+w2+w3 = 0, so
 * the origin is its centroid (force closure). Face {w0, w1, w2}: normal
 * (w2-w0) x (w1-w0) = (2,0,0) x (1,-1,-2sg) = (0, 4sg, -2), i.e. unit
 * (0, 2sg, -1)/sqrt(1+4sg^2); its value at w0 is -sg/sqrt(1+4sg^2). The
 * 90-degree symmetry (rotate the plane, flip the torque sign) maps every face
 * to this one, so epsilon = sg / sqrt(1 + 4 sg^2).
 * Default rho = |p_i - c| = sqrt(1/4 + 1/16) = sqrt(5)/4: sg^2 = 1/5,
 * epsilon = sqrt(1/5)/sqrt(9/5) = 1/3 exactly. With rho = 1: sg = 1/4,
 * epsilon = (1/4)/sqrt(5/4) = 1/(2 sqrt 5). */
static void square_grasp(const double c[3], cd_grasp_contact k[4])
{
    const double a = 0.5, s = 0.25;
    /* the contacts sit 0.3 above the plane through c: planar mode projects */
    k[0] = contact(c[0] + a, c[1] + s, c[2] + 0.3, -1, 0, 0, 0.0);
    k[1] = contact(c[0] + s, c[1] + a, c[2] + 0.3, 0, -1, 0, 0.0);
    k[2] = contact(c[0] - a, c[1] - s, c[2] + 0.3, 1, 0, 0, 0.0);
    k[3] = contact(c[0] - s, c[1] - a, c[2] + 0.3, 0, 1, 0, 0.0);
}

Test(grasp_quality, planar_frictionless_square_hand_value)
{
    const double c[3] = {0.3, -0.2, 0.7};
    cd_grasp_contact k[4];
    cd_grasp_options o = planar();
    cd_grasp_quality q;
    square_grasp(c, k);
    q = eval_ok(k, 4, c, &o);
    cr_expect_eq(q.force_closure, 1);
    cr_expect_eq(q.dim, 3);
    cr_expect_eq(q.nwrench, 4);
    cr_expect_eq(q.nfacet, 4, "the hull is a tetrahedron, got %d facets", q.nfacet);
    cr_expect(fabs(q.rho - sqrt(5.0) / 4.0) <= 1e-15, "rho %.17g", q.rho);
    cr_expect(fabs(q.epsilon - 1.0 / 3.0) <= 1e-9, "epsilon %.17g, expected 1/3", q.epsilon);
    o.rho = 1.0;
    q = eval_ok(k, 4, c, &o);
    cr_expect(fabs(q.epsilon - 1.0 / (2.0 * sqrt(5.0))) <= 1e-9, "epsilon %.17g, expected 1/(2 sqrt 5)", q.epsilon);
    /* the aligned grasp (all offsets +s: a pinwheel) has tau = +s for every
     * contact: no wrench resists a negative torque, no closure */
    k[1].p[0] = c[0] - 0.25;
    k[3].p[0] = c[0] + 0.25;
    q = eval_ok(k, 4, c, &o);
    cr_expect_eq(q.force_closure, 0);
    cr_expect_eq(q.epsilon, 0.0);
}

/* ---- (a2) planar, frictional: three contacts at 120 degrees on a disc ------ */
/* Disc of radius R centred at c = 0; contacts at angles phi_k = 2 pi k / 3 with
 * radial inward normals n_k; t_k = z x n_k. The lever arm r = -R n is parallel
 * to n, so tau(n +- mu t) = +-mu R (n x t)_z = +-mu R, and with the default
 * rho = R the six wrenches are (n_k +- mu t_k, +-mu): two equilateral triangles
 * of circumradius r0 = sqrt(1+mu^2) in the planes tau = +mu and tau = -mu,
 * twisted against each other by 2 alpha, alpha = atan(mu).
 * Facets: the two triangles (distance mu) and six side triangles, each holding
 * one triangle's edge and the other triangle's vertex most extreme along the
 * edge's outward direction u (valid for alpha < 60 deg, mu < sqrt 3). The
 * edge is horizontal and perpendicular to u, so the facet's normal lies in
 * span(u, tau): in the (s = .u, tau) section the edge is the point
 * (r0/2, -mu) (cos 60 deg = 1/2) and the vertex (s1, +mu),
 * s1 = r0 cos(60 deg - 2 alpha) = ((1 - mu^2)/2 + sqrt3 mu)/r0. The distance of
 * the origin from the line through them is
 *   mu (r0/2 + s1) / sqrt((s1 - r0/2)^2 + 4 mu^2)
 * with r0/2 + s1 = (1 + sqrt3 mu)/r0 and s1 - r0/2 = mu (sqrt3 - mu)/r0:
 *   D(mu) = (1 + sqrt3 mu) / sqrt(7 - 2 sqrt3 mu + 5 mu^2).
 * epsilon = min(mu, D(mu)); D < mu from mu ~ 0.95 on. Checks: mu = 0.5
 * -> 0.5 (D = 0.731); mu = 1.2 -> D = 0.97145... */
static double disc_epsilon(double mu)
{
    double d = (1.0 + sqrt(3.0) * mu) / sqrt(7.0 - 2.0 * sqrt(3.0) * mu + 5.0 * mu * mu);
    return fmin(mu, d);
}

static void disc_grasp(double R, double mu, cd_grasp_contact k[3])
{
    int i;
    for (i = 0; i < 3; i++) {
        double ph = 2.0 * acos(-1.0) * i / 3.0;
        k[i] = contact(R * cos(ph), R * sin(ph), 0.0, -cos(ph), -sin(ph), 0.0, mu);
    }
}

Test(grasp_quality, planar_disc_120deg_hand_value)
{
    const double c[3] = {0, 0, 0}, mus[] = {0.5, 1.0, 1.2, 1.6};
    cd_grasp_contact k[3];
    cd_grasp_options o = planar();
    unsigned i;
    for (i = 0; i < sizeof mus / sizeof mus[0]; i++) {
        cd_grasp_quality q;
        disc_grasp(0.2, mus[i], k);
        q = eval_ok(k, 3, c, &o);
        cr_expect_eq(q.force_closure, 1, "mu %g", mus[i]);
        cr_expect_eq(q.nwrench, 6);
        cr_expect(fabs(q.rho - 0.2) <= 1e-15);
        cr_expect(fabs(q.epsilon - disc_epsilon(mus[i])) <= 1e-9, "mu %g: epsilon %.17g, hand %.17g", mus[i], q.epsilon,
                  disc_epsilon(mus[i]));
    }
    /* frictionless: three wrenches in 3-D span no volume */
    disc_grasp(0.2, 0.0, k);
    cr_expect_eq(eval_ok(k, 3, c, &o).force_closure, 0);
}

/* ---- (a3) planar antipodal pair with friction ------------------------------- */
/* Contacts at (+-R, 0), normals -+x, rho = R: wrenches
 * A = (-1, mu, mu), B = (-1, -mu, -mu), C = (1, mu, -mu), D = (1, -mu, mu),
 * a tetrahedron with A+B+C+D = 0. Face {A, B, C}: (B-A) x (C-A) =
 * (0,-2mu,-2mu) x (2,0,-2mu) = (4mu^2, -4mu, 4mu), unit (mu,-1,1)/sqrt(2+mu^2),
 * value at A -mu/sqrt(2+mu^2); the faces ABD, ACD, BCD give the same by the
 * same computation. epsilon = mu / sqrt(2 + mu^2); mu = 1/2 -> 1/3. */
Test(grasp_quality, planar_antipodal_frictional_hand_value)
{
    const double c[3] = {1, 2, 3}, mus[] = {0.5, 0.2, 2.0};
    cd_grasp_options o = planar();
    unsigned i;
    for (i = 0; i < sizeof mus / sizeof mus[0]; i++) {
        double mu = mus[i], want = mu / sqrt(2.0 + mu * mu);
        cd_grasp_contact k[2] = {contact(1.7, 2, 3, -1, 0, 0, mu), contact(0.3, 2, 3, 1, 0, 0, mu)};
        cd_grasp_quality q = eval_ok(k, 2, c, &o);
        cr_expect_eq(q.force_closure, 1);
        cr_expect(fabs(q.epsilon - want) <= 1e-9, "mu %g: epsilon %.17g, expected %.17g", mu, q.epsilon, want);
    }
}

/* ---- (a4) 3-D, frictionless: twelve contacts on a cube ---------------------- */
/* Cube of half-width a centred at c = 0; on the face of axis i and sign g the
 * contacts p = g a e_i + k s e_{i+2} (k = +-1, indices mod 3), n = -g e_i.
 * r x n: face +x, p = (a, 0, k s), n = -e1 gives (0, -k s, 0); face -x gives
 * (0, k s, 0); cyclically the wrenches are (+-e_i, +-sg e_{i+1}), all four sign
 * pairs, sg = s/rho. They lie in three mutually orthogonal planes
 * (f1, tau2), (f2, tau3), (f3, tau1), in each the rectangle with vertices
 * (+-1, +-sg). The hull of such a union is the free sum of the rectangles:
 * its facets are the hyperplanes sum_i c_i . x_i = 1 with each c_i the
 * normal vector of a rectangle edge, (+-1, 0) or (0, +-1/sg) (4^3 = 64
 * facets), at distance 1/|c| from the origin. For sg < 1 the nearest take
 * (0, 1/sg) in all three planes: epsilon = sg / sqrt(3); for sg > 1 the
 * (+-1, 0): epsilon = 1 / sqrt(3).
 * Default rho = sqrt(a^2 + s^2); a = 1/2, s = 1/4: sg^2 = 1/5,
 * epsilon = 1/sqrt(15). With rho = 1: sg = 1/4, epsilon = 1/(4 sqrt 3). */
static void cube_grasp(cd_grasp_contact k[12])
{
    const double a = 0.5, s = 0.25;
    int i, g, j, n = 0;
    for (i = 0; i < 3; i++)
        for (g = -1; g <= 1; g += 2)
            for (j = -1; j <= 1; j += 2) {
                memset(&k[n], 0, sizeof k[n]);
                k[n].p[i] = g * a;
                k[n].p[(i + 2) % 3] = j * s;
                k[n].n[i] = -g;
                n++;
            }
}

Test(grasp_quality, spatial_frictionless_cube_hand_value)
{
    const double axis[3] = {0.6, 0.1, -0.5}, x[3] = {-3, 0.5, 8};
    double c[3] = {0, 0, 0}, R[9];
    cd_grasp_contact k[12];
    cd_grasp_options o = cd_grasp_options_default();
    cd_grasp_quality q;
    cube_grasp(k);
    q = eval_ok(k, 12, c, &o);
    cr_expect_eq(q.force_closure, 1);
    cr_expect_eq(q.dim, 6);
    cr_expect_eq(q.nwrench, 12);
    cr_expect_eq(q.nfacet, 64, "free sum of three rectangles: 64 facets, got %d", q.nfacet);
    cr_expect(fabs(q.epsilon - 1.0 / sqrt(15.0)) <= 1e-9, "epsilon %.17g, expected 1/sqrt(15)", q.epsilon);
    /* (c) exact invariance: frictionless wrenches rotate rigidly in R^6 */
    rot_axis(axis, -1.3, R);
    move_grasp(R, x, k, 12, c);
    q = eval_ok(k, 12, c, &o);
    cr_expect(fabs(q.epsilon - 1.0 / sqrt(15.0)) <= 1e-9, "moved: epsilon %.17g", q.epsilon);
    o.rho = 1.0;
    q = eval_ok(k, 12, c, &o);
    cr_expect(fabs(q.epsilon - 1.0 / (4.0 * sqrt(3.0))) <= 1e-9, "rho 1: epsilon %.17g, expected 1/(4 sqrt 3)", q.epsilon);
    /* sg >= 1 (torques weigh more than forces): the nearest facets take
     * (+-1, 0) in every plane, epsilon = 1/sqrt(3); rho = 1 mm gives sg = 250.
     * At the other end of the accepted rho range (1e6 lever arms) the tiny
     * epsilon sg/sqrt3 keeps its relative accuracy. */
    o.rho = 1e-3;
    q = eval_ok(k, 12, c, &o);
    cr_expect(fabs(q.epsilon - 1.0 / sqrt(3.0)) <= 1e-9, "rho 1 mm: epsilon %.17g, expected 1/sqrt(3)", q.epsilon);
    o.rho = 5e5;
    q = eval_ok(k, 12, c, &o);
    cr_expect(fabs(q.epsilon / (0.25 / 5e5 / sqrt(3.0)) - 1.0) <= 1e-9, "rho 5e5 m: epsilon %.17g", q.epsilon);
    o.rho = 1.0;
    /* without the two contacts on the +z face (the last two, pushing -z) no
     * wrench has f3 < 0: no closure */
    q = eval_ok(k, 10, c, &o);
    cr_expect_eq(q.force_closure, 0);
    cr_expect_eq(q.epsilon, 0.0);
}

/* ---- (b) no force closure ---------------------------------------------------- */
Test(grasp_quality, antipodal_3d_is_not_closure)
{
    const double c[3] = {0, 0, 0};
    cd_grasp_contact k[2] = {contact(0.1, 0, 0, -1, 0, 0, 0.0), contact(-0.1, 0, 0, 1, 0, 0, 0.0)};
    cd_grasp_quality q = eval_ok(k, 2, c, NULL);
    /* frictionless: two wrenches, no 6-D volume (Qhull not even called) */
    cr_expect_eq(q.force_closure, 0);
    cr_expect_eq(q.epsilon, 0.0);
    cr_expect_eq(q.nwrench, 2);
    cr_expect_eq(q.dim, 6);
    /* with friction: 16 wrenches, but every torque is r x f with r along x,
     * so no wrench has a torque about x: a flat (5-D) set. Qhull reports it
     * singular, which is the physical answer "no closure", not an error. */
    k[0].mu = k[1].mu = 0.8;
    q = eval_ok(k, 2, c, NULL);
    cr_expect_eq(q.nwrench, 16);
    cr_expect_eq(q.force_closure, 0);
    cr_expect_eq(q.epsilon, 0.0);
    cr_expect_eq(q.nfacet, 0);
}

/* full-dimensional hull that does not contain the origin: every contact
 * pushes with a positive x component */
Test(grasp_quality, origin_outside_hull_is_not_closure)
{
    const double c[3] = {0, 0, 0};
    cd_grasp_contact k[3] = {contact(-1, 0, 0, 1, 0, 0, 0.3), contact(0, 1, 0, 1, -1, 0, 0.3),
                             contact(0, -1, 0, 1, 1, 0, 0.3)};
    cd_grasp_options o = planar();
    cd_grasp_quality q = eval_ok(k, 3, c, &o);
    cr_expect_gt(q.nfacet, 0, "a full hull was built");
    cr_expect_eq(q.force_closure, 0);
    cr_expect_eq(q.epsilon, 0.0);
}

/* ---- (c) invariance under a rigid motion of the whole grasp ---------------- */
static void rot_apply(const double R[9], const double *v, double *out)
{
    int i;
    for (i = 0; i < 3; i++) out[i] = R[3 * i] * v[0] + R[3 * i + 1] * v[1] + R[3 * i + 2] * v[2];
}

/* rotation by angle th about the unit axis u (Rodrigues) */
static void rot_axis(const double u0[3], double th, double R[9])
{
    double s = sqrt(u0[0] * u0[0] + u0[1] * u0[1] + u0[2] * u0[2]), u[3], c = cos(th), sn = sin(th);
    int i, j;
    for (i = 0; i < 3; i++) u[i] = u0[i] / s;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) R[3 * i + j] = (1 - c) * u[i] * u[j] + (i == j ? c : 0.0);
    R[1] -= sn * u[2], R[2] += sn * u[1];
    R[3] += sn * u[2], R[5] -= sn * u[0];
    R[6] -= sn * u[1], R[7] += sn * u[0];
}

static void move_grasp(const double R[9], const double x[3], cd_grasp_contact *k, int n, double c[3])
{
    int i, a;
    double v[3];
    for (i = 0; i < n; i++) {
        rot_apply(R, k[i].p, v);
        for (a = 0; a < 3; a++) k[i].p[a] = v[a] + x[a];
        rot_apply(R, k[i].n, v);
        memcpy(k[i].n, v, sizeof v);
        rot_apply(R, k[i].t, v);
        memcpy(k[i].t, v, sizeof v);
    }
    rot_apply(R, c, v);
    for (a = 0; a < 3; a++) c[a] = v[a] + x[a];
}

/* four frictional contacts on a sphere of radius 0.15 at the vertices of a
 * regular tetrahedron, normals through the centre, tangents given */
static void tetra_grasp(double mu, cd_grasp_contact k[4], int with_tangents)
{
    static const double v[4][3] = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
    const double r = 0.15 / sqrt(3.0);
    int i;
    for (i = 0; i < 4; i++) {
        k[i] = contact(r * v[i][0], r * v[i][1], r * v[i][2], -v[i][0], -v[i][1], -v[i][2], mu);
        if (with_tangents) k[i].t[0] = v[i][1], k[i].t[1] = -v[i][0], k[i].t[2] = 0.0;
    }
}

Test(grasp_quality, rigid_motion_invariance)
{
    const double axis[3] = {0.3, -0.8, 0.52}, x[3] = {4.0, -7.5, 12.25};
    double R[9], c[3] = {0, 0, 0}, c2[3];
    cd_grasp_contact k[4], k2[4];
    cd_grasp_options o = cd_grasp_options_default();
    cd_grasp_quality q0, q1;
    rot_axis(axis, 2.1, R);
    /* 3-D, frictional, tangents moved with the grasp */
    tetra_grasp(0.4, k, 1);
    q0 = eval_ok(k, 4, c, &o);
    cr_assert_eq(q0.force_closure, 1, "the tetrahedral grasp with mu 0.4 is force closure");
    memcpy(k2, k, sizeof k);
    memcpy(c2, c, sizeof c);
    move_grasp(R, x, k2, 4, c2);
    q1 = eval_ok(k2, 4, c2, &o);
    cr_expect(fabs(q1.epsilon - q0.epsilon) <= 1e-12, "3-D: %.17g vs %.17g", q1.epsilon, q0.epsilon);
    /* planar: the square grasp with the plane itself rotated and moved */
    o = planar();
    square_grasp(c, k);
    q0 = eval_ok(k, 4, c, &o);
    memcpy(c2, c, sizeof c);
    move_grasp(R, x, k, 4, c2);
    rot_apply(R, o.plane_normal, c);
    memcpy(o.plane_normal, c, sizeof c);
    q1 = eval_ok(k, 4, c2, &o);
    cr_expect(fabs(q1.epsilon - q0.epsilon) <= 1e-12, "planar: %.17g vs %.17g", q1.epsilon, q0.epsilon);
    cr_expect(fabs(q1.epsilon - 1.0 / 3.0) <= 1e-9);
}

/* ---- linearised cone: bounds, and the roll of automatic tangents ----------- */
/* The m-edge polygon of radius mu contains the circle of radius mu cos(pi/m);
 * with th_j = 2 pi j/m the 8 edges are a subset of the 16 edges. Hence
 *   eps_16(mu cos(pi/8)) <= eps_8(mu) <= eps_16(mu),
 * and for any roll of the cone about n (automatic tangents after rotating the
 * grasp) eps_8 stays within eps_16(mu cos(pi/8)) .. eps_16(mu / cos(pi/16)).
 * (16, not more: the 6-D hull grows steeply with m, docs/grasp-quality.md.) */
Test(grasp_quality, cone_linearisation_bounds)
{
    const double mu = 0.4, pi = acos(-1.0), c[3] = {0, 0, 0}, axis[3] = {-0.2, 0.9, 0.4}, x[3] = {1, 2, 3};
    double e8, e16, lo, hi, R[9], c2[3];
    cd_grasp_contact k[4];
    cd_grasp_options o = cd_grasp_options_default();
    tetra_grasp(mu, k, 1);
    e8 = eval_ok(k, 4, c, &o).epsilon;
    o.cone_edges = 16;
    e16 = eval_ok(k, 4, c, &o).epsilon;
    tetra_grasp(mu * cos(pi / 8), k, 1);
    lo = eval_ok(k, 4, c, &o).epsilon;
    tetra_grasp(mu / cos(pi / 16), k, 1);
    hi = eval_ok(k, 4, c, &o).epsilon;
    cr_expect(lo <= e8 + 1e-12 && e8 <= e16 + 1e-12, "%.17g <= %.17g <= %.17g", lo, e8, e16);
    cr_expect(lo < e8 && e8 < e16, "the bounds are not trivially met: %.17g %.17g %.17g", lo, e8, e16);
    /* automatic tangents: rotate the grasp, the cone rolls, epsilon moves but
     * stays inside the exact-cone bounds */
    o.cone_edges = 8;
    tetra_grasp(mu, k, 0);
    memcpy(c2, c, sizeof c);
    rot_axis(axis, 0.7, R);
    move_grasp(R, x, k, 4, c2);
    e8 = eval_ok(k, 4, c2, &o).epsilon;
    cr_expect(lo <= e8 + 1e-12 && e8 <= hi + 1e-12, "%.17g <= %.17g <= %.17g", lo, e8, hi);
}

/* ---- (d) epsilon grows with mu ------------------------------------------------ */
Test(grasp_quality, epsilon_grows_with_mu)
{
    const double c[3] = {0, 0, 0};
    cd_grasp_contact k[4];
    cd_grasp_options o = planar();
    double prev = 0.0, mu;
    int i;
    /* planar disc: strictly increasing, and on the hand formula everywhere */
    for (i = 1; i <= 34; i++) {
        double e;
        mu = 0.05 * i;
        disc_grasp(0.2, mu, k);
        e = eval_ok(k, 3, c, &o).epsilon;
        cr_expect_gt(e, prev, "mu %g: %.17g after %.17g", mu, e, prev);
        cr_expect(fabs(e - disc_epsilon(mu)) <= 1e-9, "mu %g: %.17g vs hand %.17g", mu, e, disc_epsilon(mu));
        prev = e;
    }
    /* 3-D tetrahedral grasp: the smaller cone's edges are convex combinations
     * of n (the mean of the edges) and the larger cone's, so never decreasing */
    o = cd_grasp_options_default();
    prev = 0.0;
    for (i = 1; i <= 10; i++) {
        double e;
        tetra_grasp(0.1 * i, k, 1);
        e = eval_ok(k, 4, c, &o).epsilon;
        cr_expect_gt(e, prev, "3-D mu %g: %.17g after %.17g", 0.1 * i, e, prev);
        prev = e;
    }
}

/* ---- (e) bad input --------------------------------------------------------- */
static void expect_einval(const cd_grasp_contact *k, int n, const double *c, const cd_grasp_options *o,
                          const char *msg)
{
    cd_grasp_quality q;
    cd_error e = {CD_OK, ""};
    cd_status st;
    q.epsilon = 7.0;
    q.force_closure = 1;
    st = cd_grasp_quality_eval(k, n, c, o, &q, &e);
    cr_expect_eq(st, CD_EINVAL, "status %d for '%s'", (int)st, msg);
    cr_expect_eq(e.status, CD_EINVAL);
    cr_expect_str_eq(e.msg, msg);
    cr_expect(q.epsilon == 0.0 && q.force_closure == 0, "the result is cleared on error");
}

Test(grasp_quality, bad_input_rejected_with_message)
{
    const double c[3] = {0, 0, 0}, cnan[3] = {0, NAN, 0};
    cd_grasp_contact k[4], b[4];
    cd_grasp_options o = cd_grasp_options_default(), p;
    cd_error e;
    square_grasp(c, k);
    expect_einval(k, 0, c, &o, "grasp quality: n = 0 contacts, expected at least 1");
    expect_einval(NULL, 4, c, &o, "grasp quality: contacts is NULL");
    expect_einval(k, 4, NULL, &o, "grasp quality: reference point c is NULL");
    expect_einval(k, 4, cnan, &o, "grasp quality: reference point c is not finite");
    memcpy(b, k, sizeof k);
    b[2].n[0] = 0.0;
    expect_einval(b, 4, c, &o, "grasp quality: contact 2: normal n = (0, 0, 0), expected a finite non-zero vector");
    memcpy(b, k, sizeof k);
    b[1].p[2] = INFINITY;
    expect_einval(b, 4, c, &o, "grasp quality: contact 1: point p is not finite");
    memcpy(b, k, sizeof k);
    b[3].mu = -0.1;
    expect_einval(b, 4, c, &o, "grasp quality: contact 3: mu = -0.1, expected a finite value >= 0");
    memcpy(b, k, sizeof k);
    b[0].t[0] = -2.0; /* n0 = (-1, 0, 0) */
    expect_einval(b, 4, c, &o, "grasp quality: contact 0: tangent t is parallel to the normal");
    p = o;
    p.rho = -1.0;
    expect_einval(k, 4, c, &p, "grasp quality: rho = -1, expected a finite value >= 0 (0 = automatic)");
    p = o;
    p.rho = 1e-20; /* the cube grasp would look flat to Qhull: a false "no closure" */
    expect_einval(k, 4, c, &p, "grasp quality: rho = 1e-20 m is out of scale with the lever arms (max |p - c| = "
                               "0.634429 m): expected within a factor 1e+06 of it (or 0 = automatic)");
    memcpy(b, k, sizeof k);
    b[0].p[0] = 1.5e308, b[2].p[0] = -1.5e308;
    expect_einval(b, 4, c, &o, "grasp quality: the lever arms |p - c| overflow (contacts too far from c)");
    p = o;
    p.cone_edges = 2;
    expect_einval(k, 4, c, &p, "grasp quality: cone_edges = 2, expected 3..64");
    p = o;
    p.mode = (cd_grasp_mode)7;
    expect_einval(k, 4, c, &p, "grasp quality: mode = 7, expected CD_GRASP_SPATIAL (0) or CD_GRASP_PLANAR (1)");
    p = planar();
    p.plane_normal[0] = p.plane_normal[1] = p.plane_normal[2] = 0.0;
    expect_einval(k, 4, c, &p, "grasp quality: plane_normal = (0, 0, 0), expected a finite non-zero vector");
    p = planar();
    memcpy(b, k, sizeof k);
    b[1].n[0] = b[1].n[1] = 0.0, b[1].n[2] = 1.0;
    expect_einval(b, 4, c, &p, "grasp quality: contact 1: normal is perpendicular to the grasp plane");
    cr_expect_eq(cd_grasp_quality_eval(k, 4, c, &o, NULL, &e), CD_EINVAL);
    cr_expect_str_eq(e.msg, "grasp quality: result pointer q is NULL");
}

/* ---- Qhull never writes to the terminal -------------------------------------- */
/* stdout and stderr are pointed at a file while Qhull runs on a full hull and
 * on a flat (singular) set; the file must stay empty. */
Test(grasp_quality, qhull_is_silent)
{
    const double c[3] = {0, 0, 0};
    char path[] = "/tmp/capdyn_gq_XXXXXX";
    int fd = mkstemp(path), out, err;
    cd_grasp_contact k[4], flat[2] = {contact(0.1, 0, 0, -1, 0, 0, 0.8), contact(-0.1, 0, 0, 1, 0, 0, 0.8)};
    cd_grasp_quality q1, q2;
    off_t size;
    cr_assert(fd >= 0);
    tetra_grasp(0.5, k, 0);
    fflush(stdout);
    fflush(stderr);
    out = dup(1);
    err = dup(2);
    dup2(fd, 1);
    dup2(fd, 2);
    q1 = eval_ok(k, 4, c, NULL);
    q2 = eval_ok(flat, 2, c, NULL);
    fflush(stdout);
    fflush(stderr);
    dup2(out, 1);
    dup2(err, 2);
    close(out);
    close(err);
    size = lseek(fd, 0, SEEK_END);
    close(fd);
    unlink(path);
    cr_expect_eq(q1.force_closure, 1);
    cr_expect_eq(q2.force_closure, 0);
    cr_expect_eq(size, 0, "Qhull wrote %ld bytes to stdout/stderr", (long)size);
}
