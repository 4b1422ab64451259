/* Model builder validation (src/model/model.c): every rejection rule is
 * provoked on purpose and its error report checked (status CD_EINVAL, a
 * message naming the offending object and the broken rule), a rejected call
 * leaves the model unchanged, and the accepted borderline cases pass.
 * Also: lifetime no-ops, name lookups, state layout and the slot table.
 *
 * The expected messages are those of the builder's documented contract
 * (include/capdyn/model.h: "err naming the body"); the substrings checked are
 * the object's name and the rule, not the full wording. */
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

static void diag3(double I[9], double a, double b, double c)
{
    memset(I, 0, 9 * sizeof(double));
    I[0] = a; I[4] = b; I[8] = c;
}

/* ret must be -1 (or CD_EINVAL for status-returning calls: pass is_status)
 * with e->status CD_EINVAL and a message containing both needles. */
static void check_reject(int ret, int is_status, const cd_error *e, const char *what, const char *n1,
                         const char *n2)
{
    if (is_status)
        cr_expect(ret == CD_EINVAL, "%s: accepted (status %d)", what, ret);
    else
        cr_expect(ret == -1, "%s: accepted (id %d)", what, ret);
    cr_expect(e->status == CD_EINVAL, "%s: status %d (%s)", what, e->status, e->msg);
    if (n1) cr_expect(strstr(e->msg, n1) != NULL, "%s: message \"%s\" lacks \"%s\"", what, e->msg, n1);
    if (n2) cr_expect(strstr(e->msg, n2) != NULL, "%s: message \"%s\" lacks \"%s\"", what, e->msg, n2);
}

static void clear(cd_error *e)
{
    e->status = CD_OK;
    e->msg[0] = 0;
}

/* A model with one free system "sat" (body 0) and links "shoulder" (1) and
 * "elbow" (2); the caller adds what it tests. */
static cd_model *base_model(void)
{
    cd_model *m = cd_model_create();
    cd_system_desc s = cd_system_desc_default();
    cd_link_desc l = cd_link_desc_default();
    cd_error e;
    cr_assert(m != NULL);
    s.name = "sat";
    s.mass = 10;
    cr_assert(cd_model_add_system(m, &s, &e) == 0, "%s", e.msg);
    l.name = "shoulder";
    l.parent = 0;
    l.pos[0] = 0.5;
    cr_assert(cd_model_add_link(m, 0, &l, &e) == 1, "%s", e.msg);
    l.name = "elbow";
    l.parent = 1;
    cr_assert(cd_model_add_link(m, 0, &l, &e) == 2, "%s", e.msg);
    return m;
}

/* ---- systems ------------------------------------------------------------- */
Test(model, system_rejections)
{
    cd_model *m = cd_model_create();
    cd_system_desc s;
    cd_error e;
    double R[9], c = cos(0.4), sn = sin(0.4);
    int i;
    const double bad_mass[4] = {0.0, -1.0, NAN, INFINITY};

    clear(&e);
    check_reject(cd_model_add_system(m, NULL, &e), 0, &e, "NULL system", "NULL", NULL);

    s = cd_system_desc_default();
    s.name = "sat";
    s.type = (cd_base_type)7;
    clear(&e);
    check_reject(cd_model_add_system(m, &s, &e), 0, &e, "base type", "'sat'", "free or fixed");

    for (i = 0; i < 4; i++) {
        s = cd_system_desc_default();
        s.name = "sat";
        s.mass = bad_mass[i];
        clear(&e);
        check_reject(cd_model_add_system(m, &s, &e), 0, &e, "base mass", "'sat'", "mass");
    }

    s = cd_system_desc_default();
    s.name = "sat";
    s.inertia[4] = NAN;
    clear(&e);
    check_reject(cd_model_add_system(m, &s, &e), 0, &e, "NaN inertia", "'sat'", "non-finite");

    s = cd_system_desc_default();
    s.name = "sat";
    s.inertia[1] = 0.1; /* I_xy != I_yx */
    clear(&e);
    check_reject(cd_model_add_system(m, &s, &e), 0, &e, "asymmetric inertia", "'sat'", "not symmetric");

    s = cd_system_desc_default();
    s.name = "sat";
    diag3(s.inertia, 1, -1, 1);
    clear(&e);
    check_reject(cd_model_add_system(m, &s, &e), 0, &e, "indefinite inertia", "'sat'", "positive definite");

    s = cd_system_desc_default();
    s.name = "sat";
    diag3(s.inertia, 1, 0, 1); /* singular: a rod-like limit is not a rigid body with a proper inertia */
    clear(&e);
    check_reject(cd_model_add_system(m, &s, &e), 0, &e, "singular inertia", "'sat'", "positive definite");

    s = cd_system_desc_default();
    s.name = "sat";
    diag3(s.inertia, 1, 1, 3); /* 1 + 1 < 3: no mass distribution has these moments */
    clear(&e);
    check_reject(cd_model_add_system(m, &s, &e), 0, &e, "triangle inequality", "'sat'", "triangle");

    /* the same principal moments, rotated about x: the eigenvalue path */
    {
        double D[9], T[9];
        int a, b, k;
        diag3(D, 1, 1, 3);
        R[0] = 1; R[1] = 0; R[2] = 0; R[3] = 0; R[4] = c; R[5] = -sn; R[6] = 0; R[7] = sn; R[8] = c;
        for (a = 0; a < 3; a++)
            for (b = 0; b < 3; b++) {
                T[3 * a + b] = 0;
                for (k = 0; k < 3; k++) T[3 * a + b] += R[3 * a + k] * D[3 * k + k] * R[3 * b + k];
            }
        T[3] = T[1]; T[6] = T[2]; T[7] = T[5];
        s = cd_system_desc_default();
        s.name = "sat";
        memcpy(s.inertia, T, sizeof T);
        clear(&e);
        check_reject(cd_model_add_system(m, &s, &e), 0, &e, "rotated triangle violation", "'sat'", "triangle");
    }

    s = cd_system_desc_default();
    s.name = "sat";
    s.pos[2] = NAN;
    clear(&e);
    check_reject(cd_model_add_system(m, &s, &e), 0, &e, "NaN position", "'sat'", "non-finite");
    s = cd_system_desc_default();
    s.name = "sat";
    s.angvel[0] = INFINITY;
    clear(&e);
    check_reject(cd_model_add_system(m, &s, &e), 0, &e, "inf angular velocity", "'sat'", "non-finite");
    s = cd_system_desc_default();
    s.name = "sat";
    s.quat[0] = 0;
    clear(&e);
    check_reject(cd_model_add_system(m, &s, &e), 0, &e, "zero quaternion", "'sat'", "quaternion");
    s = cd_system_desc_default();
    s.name = "sat";
    s.mass = 1e-320; /* subnormal: 1/m is inf */
    clear(&e);
    check_reject(cd_model_add_system(m, &s, &e), 0, &e, "subnormal mass", "'sat'", "mass");

    /* nothing was added by the rejected calls */
    cr_expect(m->nsys == 0 && m->nbody == 0, "rejected systems left %d systems, %d bodies", m->nsys, m->nbody);

    /* borderline but valid: a thin disc (I_z = I_x + I_y exactly) and a
     * non-unit quaternion, which is normalised on add */
    s = cd_system_desc_default();
    s.name = "disc";
    diag3(s.inertia, 1, 1, 2);
    s.quat[0] = 2.0;
    clear(&e);
    cr_expect(cd_model_add_system(m, &s, &e) == 0, "thin disc rejected: %s", e.msg);
    cr_expect(fabs(m->sys_quat0[0] - 1.0) < 1e-15, "quaternion stored as %g", m->sys_quat0[0]);
    /* a quaternion whose squared norm overflows (or underflows) is
     * normalised all the same: (1, 0, 1, 0) / sqrt 2 within an ulp or two */
    {
        const double big[2] = {1e200, 1e-200};
        int k, i;
        for (k = 0; k < 2; k++) {
            char nm[16];
            snprintf(nm, sizeof nm, "q%d", k);
            s = cd_system_desc_default();
            s.name = nm;
            s.quat[0] = s.quat[2] = big[k];
            s.quat[1] = s.quat[3] = 0;
            clear(&e);
            cr_assert(cd_model_add_system(m, &s, &e) >= 0, "quaternion %g rejected: %s", big[k], e.msg);
            for (i = 0; i < 4; i++)
                cr_expect(fabs(m->sys_quat0[4 * (m->nsys - 1) + i] - (i % 2 ? 0.0 : sqrt(0.5))) < 4e-16,
                          "quaternion (%g, 0, %g, 0): component %d stored as %.17g", big[k], big[k], i,
                          m->sys_quat0[4 * (m->nsys - 1) + i]);
        }
    }
    cd_model_free(m);
}

/* ---- links --------------------------------------------------------------- */
Test(model, link_rejections)
{
    cd_model *m = base_model();
    cd_link_desc l;
    cd_error e;
    int nb = m->nbody, i;
    const double bad_mass[3] = {-1.0, 0.0, NAN};

#define LINK(field_stmt)                    \
    do {                                    \
        l = cd_link_desc_default();         \
        l.name = "wrist";                   \
        l.parent = 2;                       \
        field_stmt;                         \
        clear(&e);                          \
    } while (0)

    clear(&e);
    check_reject(cd_model_add_link(m, 0, NULL, &e), 0, &e, "NULL link", "NULL", NULL);

    LINK((void)0);
    check_reject(cd_model_add_link(m, 3, &l, &e), 0, &e, "no such system", "'wrist'", "no system 3");
    LINK((void)0);
    check_reject(cd_model_add_link(m, -1, &l, &e), 0, &e, "negative system", "'wrist'", "no system");

    LINK(l.parent = -1);
    check_reject(cd_model_add_link(m, 0, &l, &e), 0, &e, "parent -1", "'wrist'", "parent -1");
    LINK(l.parent = 3); /* not yet existing (parents come before children) */
    check_reject(cd_model_add_link(m, 0, &l, &e), 0, &e, "parent not yet added", "'wrist'", "parent 3");

    LINK(l.type = CD_JOINT_BASE);
    check_reject(cd_model_add_link(m, 0, &l, &e), 0, &e, "joint type", "'wrist'", "revolute or prismatic");

    for (i = 0; i < 3; i++) {
        LINK(l.mass = bad_mass[i]);
        check_reject(cd_model_add_link(m, 0, &l, &e), 0, &e, "link mass", "'wrist'", "mass");
    }
    LINK(diag3(l.inertia, 0.1, 0.1, 0.3));
    check_reject(cd_model_add_link(m, 0, &l, &e), 0, &e, "link triangle", "'wrist'", "triangle");
    LINK(diag3(l.inertia, -0.1, 0.1, 0.1));
    check_reject(cd_model_add_link(m, 0, &l, &e), 0, &e, "link not PD", "'wrist'", "positive definite");
    LINK(l.inertia[5] = 0.01);
    check_reject(cd_model_add_link(m, 0, &l, &e), 0, &e, "link asymmetric", "'wrist'", "symmetric");
    LINK(l.inertia[0] = INFINITY);
    check_reject(cd_model_add_link(m, 0, &l, &e), 0, &e, "link inf inertia", "'wrist'", "non-finite");

    LINK(l.pos[1] = NAN);
    check_reject(cd_model_add_link(m, 0, &l, &e), 0, &e, "NaN joint origin", "'wrist'", "non-finite");
    LINK(l.com[0] = INFINITY);
    check_reject(cd_model_add_link(m, 0, &l, &e), 0, &e, "inf CoM", "'wrist'", "non-finite");
    LINK(l.axis[2] = NAN);
    check_reject(cd_model_add_link(m, 0, &l, &e), 0, &e, "NaN axis", "'wrist'", "non-finite");
    LINK(l.q0 = NAN);
    check_reject(cd_model_add_link(m, 0, &l, &e), 0, &e, "NaN q0", "'wrist'", "non-finite");
    LINK(l.qd0 = -INFINITY);
    check_reject(cd_model_add_link(m, 0, &l, &e), 0, &e, "inf qd0", "'wrist'", "non-finite");

    /* rotations: scaled, reflected, slightly sheared (beyond the 1e-9 tolerance) */
    LINK(l.rot[0] = l.rot[4] = l.rot[8] = 2.0);
    check_reject(cd_model_add_link(m, 0, &l, &e), 0, &e, "scaled rotation", "'wrist'", "rotation");
    LINK(l.rot[8] = -1.0);
    check_reject(cd_model_add_link(m, 0, &l, &e), 0, &e, "reflection", "'wrist'", "rotation");
    LINK(l.rot[1] = 1e-6);
    check_reject(cd_model_add_link(m, 0, &l, &e), 0, &e, "sheared rotation", "'wrist'", "rotation");
    LINK(l.rot[0] = NAN);
    check_reject(cd_model_add_link(m, 0, &l, &e), 0, &e, "NaN rotation", "'wrist'", NULL);

    LINK(l.axis[0] = l.axis[1] = l.axis[2] = 0.0);
    check_reject(cd_model_add_link(m, 0, &l, &e), 0, &e, "zero axis", "'wrist'", "axis is zero");

    cr_expect(m->nbody == nb && m->sys_nbody[0] == nb, "rejected links changed the model (%d bodies)", m->nbody);

    /* accepted: rotation off by 1e-12 (round-off of a typed matrix), a
     * non-unit axis (normalised on add) */
    LINK(l.rot[1] = 1e-12; l.axis[2] = 3.0);
    cr_expect(cd_model_add_link(m, 0, &l, &e) == nb, "round-off rotation rejected: %s", e.msg);
    cr_expect(fabs(m->body_axis[3 * nb + 2] - 1.0) < 1e-15, "axis stored as %g", m->body_axis[3 * nb + 2]);

    /* links go to the most recently added system only, and parents must be
     * bodies of that system */
    {
        cd_system_desc s = cd_system_desc_default();
        s.name = "target";
        cr_assert(cd_model_add_system(m, &s, &e) == 1, "%s", e.msg);
        LINK((void)0); /* parent 2 belongs to "sat" */
        check_reject(cd_model_add_link(m, 1, &l, &e), 0, &e, "parent in another system", "'wrist'", "'target'");
        LINK(l.parent = 0);
        check_reject(cd_model_add_link(m, 0, &l, &e), 0, &e, "not the latest system", "'wrist'",
                     "most recently added");
    }
#undef LINK
    cd_model_free(m);
}

/* ---- check points and shapes ---------------------------------------------- */
Test(model, checkpoint_and_shape_rejections)
{
    cd_model *m = base_model();
    cd_error e;
    double p[3] = {0.1, 0, 0}, pn[3] = {0, NAN, 0}, sz[3] = {0.1, 0.2, 0.3}, R[9], v[12];
    int ncp, nsh;

    clear(&e);
    check_reject(cd_model_add_checkpoint(m, 7, p, 0.01, &e), 0, &e, "check point body", "no body 7", NULL);
    clear(&e);
    check_reject(cd_model_add_checkpoint(m, -1, p, 0.01, &e), 0, &e, "check point body -1", "no body", NULL);
    clear(&e);
    check_reject(cd_model_add_checkpoint(m, 2, p, -0.01, &e), 0, &e, "negative radius", "'elbow'", "radius");
    clear(&e);
    check_reject(cd_model_add_checkpoint(m, 2, p, NAN, &e), 0, &e, "NaN radius", "'elbow'", "radius");
    clear(&e);
    check_reject(cd_model_add_checkpoint(m, 2, pn, 0.01, &e), 0, &e, "NaN position", "'elbow'", "finite");
    clear(&e);
    check_reject(cd_model_add_checkpoint(m, 2, NULL, 0.01, &e), 0, &e, "NULL position", "'elbow'", NULL);
    cr_expect(m->ncp == 0);
    clear(&e);
    ncp = cd_model_add_checkpoint(m, 2, p, 0.0, &e); /* radius 0: a point */
    cr_expect(ncp == 0, "point check point rejected: %s", e.msg);

    clear(&e);
    check_reject(cd_model_add_shape(m, 9, CD_SHAPE_SPHERE, NULL, NULL, sz, NULL, 0, &e), 0, &e, "shape body",
                 "no body 9", NULL);
    clear(&e);
    check_reject(cd_model_add_shape(m, 1, (cd_shape_type)42, NULL, NULL, sz, NULL, 0, &e), 0, &e, "shape type",
                 "unknown type 42", NULL);
    clear(&e);
    check_reject(cd_model_add_shape(m, 1, CD_SHAPE_BOX, pn, NULL, sz, NULL, 0, &e), 0, &e, "NaN shape position",
                 "'shoulder'", "box");
    diag3(R, 1, 1, -1);
    clear(&e);
    check_reject(cd_model_add_shape(m, 1, CD_SHAPE_BOX, NULL, R, sz, NULL, 0, &e), 0, &e, "reflected shape",
                 "'shoulder'", "rotation");
    {
        double s0[3] = {0, 1, 1}, sneg[3] = {0.1, -0.2, 0.1}, snan[3] = {NAN, 1, 1};
        clear(&e);
        check_reject(cd_model_add_shape(m, 1, CD_SHAPE_SPHERE, NULL, NULL, s0, NULL, 0, &e), 0, &e,
                     "sphere radius 0", "sphere on body 'shoulder'", "radius");
        clear(&e);
        check_reject(cd_model_add_shape(m, 1, CD_SHAPE_SPHERE, NULL, NULL, NULL, NULL, 0, &e), 0, &e,
                     "sphere without size", "sphere", "radius");
        clear(&e);
        check_reject(cd_model_add_shape(m, 1, CD_SHAPE_BOX, NULL, NULL, sneg, NULL, 0, &e), 0, &e,
                     "box half extent < 0", "box on body 'shoulder'", "half extents");
        clear(&e);
        check_reject(cd_model_add_shape(m, 1, CD_SHAPE_CYLINDER, NULL, NULL, s0, NULL, 0, &e), 0, &e,
                     "cylinder radius 0", "cylinder on body 'shoulder'", "radius");
        clear(&e);
        check_reject(cd_model_add_shape(m, 1, CD_SHAPE_CAPSULE, NULL, NULL, sneg, NULL, 0, &e), 0, &e,
                     "capsule half length < 0", "capsule on body 'shoulder'", "half length");
        clear(&e);
        check_reject(cd_model_add_shape(m, 1, CD_SHAPE_SPHERE, NULL, NULL, snan, NULL, 0, &e), 0, &e,
                     "NaN size", "'shoulder'", NULL);
    }
    memset(v, 0, sizeof v);
    v[3] = 1; v[7] = 1; v[11] = 1; /* a tetrahedron's 4 vertices */
    clear(&e);
    check_reject(cd_model_add_shape(m, 1, CD_SHAPE_CONVEX, NULL, NULL, NULL, v, 3, &e), 0, &e,
                 "convex with 3 vertices", "convex shape on body 'shoulder'", ">= 4");
    clear(&e);
    check_reject(cd_model_add_shape(m, 1, CD_SHAPE_CONVEX, NULL, NULL, NULL, NULL, 4, &e), 0, &e,
                 "convex without vertices", "convex shape on body 'shoulder'", NULL);
    v[4] = NAN;
    clear(&e);
    check_reject(cd_model_add_shape(m, 1, CD_SHAPE_CONVEX, NULL, NULL, NULL, v, 4, &e), 0, &e,
                 "convex with a NaN vertex", "convex shape on body 'shoulder'", "finite");
    v[4] = 0;
    cr_expect(m->nshape == 0 && m->nvert == 0, "rejected shapes were stored");
    clear(&e);
    nsh = cd_model_add_shape(m, 1, CD_SHAPE_CONVEX, NULL, NULL, NULL, v, 4, &e);
    cr_expect(nsh == 0 && m->nvert == 4, "tetrahedron rejected: %s", e.msg);
    clear(&e);
    cr_expect(cd_model_add_shape(m, 0, CD_SHAPE_PLANE, NULL, NULL, NULL, NULL, 0, &e) == 1,
              "plane without size rejected: %s", e.msg);
    cd_model_free(m);
}

/* ---- contact laws and pairs ----------------------------------------------- */
Test(model, contact_law_rejections)
{
    cd_model *m = cd_model_create();
    cd_contact_law L;
    cd_error e;
    clear(&e);
    check_reject(cd_model_add_law(m, NULL, &e), 0, &e, "NULL law", "NULL", NULL);
#define LAW(stmt, what, needle)                                             \
    do {                                                                    \
        L = cd_contact_law_default();                                       \
        stmt;                                                               \
        clear(&e);                                                          \
        check_reject(cd_model_add_law(m, &L, &e), 0, &e, what, needle, NULL); \
    } while (0)
    LAW(L.K = 0, "K = 0", "K must be > 0");
    LAW(L.K = -1e5, "K < 0", "K must be > 0");
    LAW(L.K = INFINITY, "K inf", "K must be > 0");
    LAW(L.D = -1, "D < 0", "D must be >= 0");
    LAW(L.D = NAN, "D NaN", "D must be >= 0");
    LAW(L.p = 0.5, "p < 1", "p must be >= 1");
    LAW(L.q = 0, "q = 0", "q must be > 0");
    LAW(L.Kt = 0, "K_t = 0", "K_t must be > 0");
    LAW(L.Dt = -2, "D_t < 0", "D_t must be >= 0");
    LAW(L.mu_s = -0.1, "mu_max < 0", "mu_max must be >= 0");
    LAW(L.mu_s = NAN, "mu_max NaN", "mu_max");
    LAW((L.mu_s = 0.4, L.mu_k = 0.5), "mu > mu_max", "mu must be in [0, mu_max");
    LAW(L.mu_k = -0.1, "mu < 0", "mu must be in");
    LAW(L.mu_k = NAN, "mu NaN", "mu must be in");
#undef LAW
    cr_expect(m->nlaw == 0);
    /* valid: frictionless, undamped, Hertz exponent */
    L = cd_contact_law_default();
    L.mu_s = L.mu_k = 0;
    L.D = L.Dt = 0;
    L.p = 1.5;
    clear(&e);
    cr_expect(cd_model_add_law(m, &L, &e) == 0, "valid law rejected: %s", e.msg);
    /* the paper's rule: K = k_ratio k_soft, D = 2 zeta sqrt(K m) */
    L = cd_contact_law_from_rule(1e3, 50, 2.0, 1.0, 0.3);
    cr_expect(fabs(L.K - 5e4) < 1e-9 && fabs(L.D - 2.0 * sqrt(5e4 * 2.0)) < 1e-9 && L.mu_s == 0.3 &&
                  L.mu_k == 0.3 && L.p == 1 && L.q == 1,
              "rule: K %g D %g", L.K, L.D);
    cd_model_free(m);
}

Test(model, pair_rejections)
{
    cd_model *m = base_model(); /* system 0 "sat": bodies 0..2 */
    cd_system_desc s = cd_system_desc_default();
    cd_contact_law L = cd_contact_law_default();
    cd_error e;
    double p[3] = {0, 0, 0}, r[3] = {0.2, 0, 0};
    int sh_own, sh_other, law;
    s.name = "target";
    cr_assert(cd_model_add_system(m, &s, &e) == 1, "%s", e.msg); /* body 3 */
    cr_assert(cd_model_add_checkpoint(m, 2, p, 0.01, &e) == 0, "%s", e.msg);
    sh_own = cd_model_add_shape(m, 1, CD_SHAPE_SPHERE, NULL, NULL, r, NULL, 0, &e);
    sh_other = cd_model_add_shape(m, 3, CD_SHAPE_SPHERE, NULL, NULL, r, NULL, 0, &e);
    law = cd_model_add_law(m, &L, &e);
    cr_assert(sh_own == 0 && sh_other == 1 && law == 0);

    clear(&e);
    check_reject(cd_model_add_pair(m, 5, -1, sh_other, law, &e), 0, &e, "no system", "no system 5", NULL);
    clear(&e);
    check_reject(cd_model_add_pair(m, 0, 3, sh_other, law, &e), 0, &e, "body of another system", "body 3",
                 "'sat'");
    clear(&e);
    check_reject(cd_model_add_pair(m, 0, 99, sh_other, law, &e), 0, &e, "no body", "body 99", "'sat'");
    clear(&e);
    check_reject(cd_model_add_pair(m, 0, -1, 7, law, &e), 0, &e, "no shape", "no shape 7", NULL);
    clear(&e);
    check_reject(cd_model_add_pair(m, 0, 1, sh_own, law, &e), 0, &e, "same-body contact", "its own shape",
                 "'shoulder'");
    clear(&e);
    check_reject(cd_model_add_pair(m, 0, 2, sh_other, 3, &e), 0, &e, "no law", "no contact law 3", NULL);
    cr_expect(m->npair == 0);
    clear(&e);
    cr_expect(cd_model_add_pair(m, 0, 2, sh_other, law, &e) == 0, "valid pair rejected: %s", e.msg);
    /* inside one system: the elbow's check point against the shoulder's own
     * shape is jointed to it, so the system-wide pair makes no slot for it */
    cr_expect(cd_model_add_pair(m, 0, -1, sh_own, law, &e) == 1, "intra-system pair rejected: %s", e.msg);
    cr_assert(cd_model_finalize(m, &e) == CD_OK, "%s", e.msg);
    cr_expect_eq(m->nslot, 1, "only the elbow-vs-target slot: %d", m->nslot);
    cr_expect_eq(m->slot_shape[0], sh_other);
    cd_model_free(m);
}

Test(model, intra_system_pair_between_non_adjacent_links)
{
    /* base - a1 - a2 and base - b1 (two fingers of one hand): the check
     * points of a2 and of a1 against b1's shape are slots (a1 and b1 are
     * siblings, not jointed to each other); b1's own check point is not. */
    cd_model *m = cd_model_create();
    cd_system_desc s = cd_system_desc_default();
    cd_link_desc l = cd_link_desc_default();
    cd_contact_law L = cd_contact_law_default();
    cd_error e;
    double p[3] = {0, 0, 0}, r[3] = {0.01, 0, 0};
    int a1, a2, b1, sh, law;
    s.name = "hand";
    cr_assert(cd_model_add_system(m, &s, &e) == 0);
    l.parent = 0; l.name = "a1"; a1 = cd_model_add_link(m, 0, &l, &e);
    l.parent = a1; l.name = "a2"; a2 = cd_model_add_link(m, 0, &l, &e);
    l.parent = 0; l.name = "b1"; b1 = cd_model_add_link(m, 0, &l, &e);
    cd_model_add_checkpoint(m, a1, p, 0.01, &e);
    cd_model_add_checkpoint(m, a2, p, 0.01, &e);
    cd_model_add_checkpoint(m, b1, p, 0.01, &e);
    sh = cd_model_add_shape(m, b1, CD_SHAPE_SPHERE, NULL, NULL, r, NULL, 0, &e);
    law = cd_model_add_law(m, &L, &e);
    cr_assert(cd_model_add_pair(m, 0, -1, sh, law, &e) == 0, "%s", e.msg);
    cr_assert(cd_model_finalize(m, &e) == CD_OK, "%s", e.msg);
    cr_expect_eq(m->nslot, 2);
    cr_expect_eq(m->cp_body[m->slot_cp[0]], a1);
    cr_expect_eq(m->cp_body[m->slot_cp[1]], a2);
    cd_model_free(m);
}

/* ---- actuators ------------------------------------------------------------ */
Test(model, actuator_rejections)
{
    cd_model *m = base_model();
    cd_actuator a;
    cd_error e;
    double tt[3] = {0, 1, 1}, tv[3] = {0, 1, 2}, tnan[3] = {0, NAN, 2};
    memset(&a, 0, sizeof a);
    a.type = CD_ACT_CONSTANT;
    clear(&e);
    check_reject(cd_model_set_actuator(m, 0, &a, &e), 1, &e, "actuator on a base", "body 0", "not a joint body");
    clear(&e);
    check_reject(cd_model_set_actuator(m, 9, &a, &e), 1, &e, "actuator on no body", "body 9", NULL);
    clear(&e);
    check_reject(cd_model_set_actuator(m, 2, NULL, &e), 1, &e, "NULL actuator", "'elbow'", "unknown type");
    a.type = (cd_act_type)17;
    clear(&e);
    check_reject(cd_model_set_actuator(m, 2, &a, &e), 1, &e, "actuator type", "'elbow'", "unknown type");
    a.type = CD_ACT_PD;
    a.kp = NAN;
    clear(&e);
    check_reject(cd_model_set_actuator(m, 2, &a, &e), 1, &e, "NaN gain", "'elbow'", "non-finite");
    a.kp = 1;
    a.qref = INFINITY;
    clear(&e);
    check_reject(cd_model_set_actuator(m, 2, &a, &e), 1, &e, "inf set-point", "'elbow'", "non-finite");
    memset(&a, 0, sizeof a);
    a.type = CD_ACT_TABLE;
    clear(&e);
    check_reject(cd_model_set_actuator(m, 2, &a, &e), 1, &e, "empty table", "'elbow'", "at least one");
    a.tbl_t = tt;
    a.tbl_v = tv;
    a.ntbl = 3; /* t = 0, 1, 1: not strictly increasing at row 2 */
    clear(&e);
    check_reject(cd_model_set_actuator(m, 2, &a, &e), 1, &e, "repeated table time", "'elbow'", "row 2");
    a.ntbl = 2;
    a.tbl_v = tnan; /* value NaN at row 1 */
    clear(&e);
    check_reject(cd_model_set_actuator(m, 2, &a, &e), 1, &e, "NaN table value", "'elbow'", "row 1");
    cr_expect(m->ntbl == 0, "rejected tables were stored (%d rows)", m->ntbl);
    /* a valid table is copied: editing the caller's arrays afterwards has no effect */
    a.tbl_v = tv;
    clear(&e);
    cr_expect(cd_model_set_actuator(m, 2, &a, &e) == CD_OK, "valid table rejected: %s", e.msg);
    tv[1] = 99;
    cr_expect(m->ntbl == 2 && m->tbl_v[m->act_tbl_adr[m->body_act[2]] + 1] == 1.0, "table not copied");
    cd_model_free(m);
}

/* ---- finalize, and the model after it --------------------------------------- */
Test(model, finalize_rejections)
{
    cd_model *m = cd_model_create();
    cd_error e;
    clear(&e);
    check_reject(cd_model_finalize(m, &e), 1, &e, "empty model", "no system", NULL);
    cd_model_free(m);

#define OPT(stmt, what, needle)                                          \
    do {                                                                 \
        m = base_model();                                                \
        stmt;                                                            \
        clear(&e);                                                       \
        check_reject(cd_model_finalize(m, &e), 1, &e, what, needle, NULL); \
        cr_expect(!m->finalized, "%s: model marked finalized", what);    \
        cd_model_free(m);                                                \
    } while (0)
    OPT(m->gravity[1] = NAN, "NaN gravity", "gravity");
    OPT(m->opt.stepper = (cd_stepper)99, "stepper", "stepper");
    OPT((m->opt.rtol = 0, m->opt.atol = 0), "zero tolerances", "tolerances");
    OPT(m->opt.rtol = -1e-9, "negative rtol", "tolerances");
    OPT(m->opt.h_init = 0, "h_init 0", "out of range");
    OPT(m->opt.h_max = -1, "h_max < 0", "out of range");
    OPT(m->opt.h_fixed = 0, "h_fixed 0", "out of range");
    OPT(m->opt.max_steps = 0, "max_steps 0", "out of range");
    OPT(m->opt.event_tol = 0, "event_tol 0", "out of range");
    OPT(m->opt.v_reg = 0, "v_reg 0", "out of range");
    OPT(m->opt.fd_eps = NAN, "fd_eps NaN", "out of range");
#undef OPT

    /* a rejected finalize can be corrected and repeated */
    m = base_model();
    m->opt.max_steps = 0;
    clear(&e);
    cr_expect(cd_model_finalize(m, &e) == CD_EINVAL);
    m->opt.max_steps = 1000;
    clear(&e);
    cr_expect(cd_model_finalize(m, &e) == CD_OK && m->finalized, "second finalize: %s", e.msg);
    cd_model_free(m);
}

Test(model, edits_after_finalize_are_rejected)
{
    cd_model *m = base_model();
    cd_system_desc s = cd_system_desc_default();
    cd_link_desc l = cd_link_desc_default();
    cd_contact_law L = cd_contact_law_default();
    cd_actuator a;
    cd_error e;
    double p[3] = {0, 0, 0}, r[3] = {0.1, 0, 0};
    int nbody;
    cr_assert(cd_model_add_shape(m, 0, CD_SHAPE_SPHERE, NULL, NULL, r, NULL, 0, &e) == 0, "%s", e.msg);
    clear(&e);
    cr_assert(cd_model_finalize(m, &e) == CD_OK, "%s", e.msg);
    nbody = m->nbody;
    /* finalize is idempotent */
    cr_expect(cd_model_finalize(m, &e) == CD_OK);

    l.parent = 2;
    memset(&a, 0, sizeof a);
    clear(&e);
    check_reject(cd_model_add_system(m, &s, &e), 0, &e, "add_system", "finalized", NULL);
    clear(&e);
    check_reject(cd_model_add_link(m, 0, &l, &e), 0, &e, "add_link", "finalized", NULL);
    clear(&e);
    check_reject(cd_model_add_checkpoint(m, 1, p, 0.01, &e), 0, &e, "add_checkpoint", "finalized", NULL);
    clear(&e);
    check_reject(cd_model_add_shape(m, 1, CD_SHAPE_SPHERE, NULL, NULL, r, NULL, 0, &e), 0, &e, "add_shape",
                 "finalized", NULL);
    clear(&e);
    check_reject(cd_model_add_law(m, &L, &e), 0, &e, "add_law", "finalized", NULL);
    clear(&e);
    check_reject(cd_model_add_pair(m, 0, -1, 0, 0, &e), 0, &e, "add_pair", "finalized", NULL);
    clear(&e);
    check_reject(cd_model_set_actuator(m, 1, &a, &e), 1, &e, "set_actuator", "finalized", NULL);
    cr_expect(m->nbody == nbody && m->ncp == 0 && m->nshape == 1 && m->nlaw == 0);
    cd_model_free(m);

    /* NULL model: reported, not dereferenced */
    clear(&e);
    check_reject(cd_model_add_system(NULL, &s, &e), 0, &e, "NULL model", "NULL", NULL);
    clear(&e);
    check_reject(cd_model_finalize(NULL, &e), 1, &e, "finalize NULL", "NULL", NULL);
    /* err may be NULL */
    cr_expect(cd_model_add_link(NULL, 0, &l, NULL) == -1);
}

/* ---- lifetimes --------------------------------------------------------------- */
Test(model, lifetime_no_ops_and_unfinalized_data)
{
    cd_model *m;
    cd_error e;
    cd_model_free(NULL); /* must be no-ops (free(NULL) style) */
    cd_data_free(NULL);
    m = base_model();
    clear(&e);
    cr_expect(cd_data_create(m, 0, &e) == NULL, "data created from an unfinalized model");
    cr_expect(e.status == CD_EINVAL && strstr(e.msg, "finalized") != NULL, "%s", e.msg);
    clear(&e);
    cr_expect(cd_data_create(NULL, 0, &e) == NULL && e.status == CD_EINVAL);
    cd_model_free(m);
}

/* ---- lookups ------------------------------------------------------------------- */
Test(model, body_and_system_lookup)
{
    cd_model *m = base_model(); /* sat: sat(0) shoulder(1) elbow(2) */
    cd_system_desc s = cd_system_desc_default();
    cd_link_desc l = cd_link_desc_default();
    cd_error e;
    s.name = "target";
    cr_assert(cd_model_add_system(m, &s, &e) == 1, "%s", e.msg); /* body 3 "target" */
    l.name = "elbow";                                              /* same name, other system */
    l.parent = 3;
    cr_assert(cd_model_add_link(m, 1, &l, &e) == 4, "%s", e.msg);
    l.name = NULL;                                                 /* unnamed link */
    cr_assert(cd_model_add_link(m, 1, &l, &e) == 5, "%s", e.msg);

    cr_expect(cd_model_system_id(m, "sat") == 0);
    cr_expect(cd_model_system_id(m, "target") == 1);
    cr_expect(cd_model_system_id(m, "nothing") == -1);
    cr_expect(cd_model_system_id(m, NULL) == -1);

    cr_expect(cd_model_body_id(m, "sat/elbow") == 2);
    cr_expect(cd_model_body_id(m, "target/elbow") == 4);
    cr_expect(cd_model_body_id(m, "shoulder") == 1, "unique name");
    cr_expect(cd_model_body_id(m, "sat/sat") == 0, "the base carries the system's name");
    cr_expect(cd_model_body_id(m, "elbow") == -1, "ambiguous name must not resolve");
    cr_expect(cd_model_body_id(m, "wrist") == -1);
    cr_expect(cd_model_body_id(m, "nosys/elbow") == -1);
    cr_expect(cd_model_body_id(m, "sat/wrist") == -1);
    cr_expect(cd_model_body_id(m, "sat/shoulder/x") == -1);
    cr_expect(cd_model_body_id(m, NULL) == -1);
    cr_expect(cd_model_body_id(NULL, "sat") == -1);
    cd_model_free(m);
}

/* ---- layout ---------------------------------------------------------------- */
Test(model, state_layout_and_slot_table)
{
    /* free "sat" with 2 joints, fixed "stand" with 3 joints, free "target"
     * with none: y = [7+2+6+2 | 3+3 | 7+6] + 3 per slot (docs/dynamics.md) */
    cd_model *m = base_model();
    cd_system_desc s = cd_system_desc_default();
    cd_link_desc l = cd_link_desc_default();
    cd_contact_law L = cd_contact_law_default();
    cd_error e;
    cd_data *d;
    double p[3] = {0, 0, 0}, r[3] = {0.1, 0, 0};
    int j, sh, law;
    s.name = "stand";
    s.type = CD_BASE_FIXED;
    cr_assert(cd_model_add_system(m, &s, &e) == 1, "%s", e.msg); /* body 3 */
    for (j = 0; j < 3; j++) {
        l.parent = 3 + j;
        l.type = j == 1 ? CD_JOINT_PRISMATIC : CD_JOINT_REVOLUTE;
        l.q0 = 0.1 * (j + 1);
        l.qd0 = -0.2 * (j + 1);
        cr_assert(cd_model_add_link(m, 1, &l, &e) == 4 + j, "%s", e.msg);
    }
    s.name = "target";
    s.type = CD_BASE_FREE;
    s.pos[0] = 1; s.pos[1] = 2; s.pos[2] = 3;
    s.vel[0] = 0.5;
    s.angvel[2] = 0.25;
    cr_assert(cd_model_add_system(m, &s, &e) == 2, "%s", e.msg); /* body 7 */
    sh = cd_model_add_shape(m, 7, CD_SHAPE_SPHERE, NULL, NULL, r, NULL, 0, &e);
    law = cd_model_add_law(m, &L, &e);
    cr_assert(cd_model_add_checkpoint(m, 1, p, 0.0, &e) == 0);
    cr_assert(cd_model_add_checkpoint(m, 2, p, 0.0, &e) == 1);
    cr_assert(cd_model_add_checkpoint(m, 6, p, 0.0, &e) == 2);
    /* all of "sat" vs the target sphere, then elbow again (no duplicate slot),
     * then "stand" vs the target sphere */
    cr_assert(cd_model_add_pair(m, 0, -1, sh, law, &e) == 0, "%s", e.msg);
    cr_assert(cd_model_add_pair(m, 0, 2, sh, law, &e) == 1, "%s", e.msg);
    cr_assert(cd_model_add_pair(m, 1, -1, sh, law, &e) == 2, "%s", e.msg);
    clear(&e);
    cr_assert(cd_model_finalize(m, &e) == CD_OK, "%s", e.msg);

    cr_expect(m->sys_ndof[0] == 8 && m->sys_ndof[1] == 3 && m->sys_ndof[2] == 6);
    cr_expect(m->nv == 17, "nv %d", m->nv);
    cr_expect(m->sys_v_adr[0] == 0 && m->sys_v_adr[1] == 8 && m->sys_v_adr[2] == 11);
    cr_expect(m->sys_y_adr[0] == 0 && m->sys_y_adr[1] == 17 && m->sys_y_adr[2] == 23);
    cr_expect(m->body_dof[0] == -1 && m->body_dof[1] == 6 && m->body_dof[2] == 7 && m->body_dof[4] == 8 &&
                  m->body_dof[6] == 10 && m->body_dof[7] == -1,
              "joint dofs");
    cr_expect(m->nslot == 3, "slots %d (duplicates must merge)", m->nslot);
    cr_expect(m->ny_slot_adr == 36 && m->ny == 36 + 9, "ny %d, slot block at %d", m->ny, m->ny_slot_adr);

    d = cd_data_create(m, 0, &e);
    cr_assert(d != NULL, "%s", e.msg);
    {
        cd_sys_state a = cd_state_of(m, d, 0), b = cd_state_of(m, d, 1), c = cd_state_of(m, d, 2);
        cr_expect(a.pos == d->y && a.quat == d->y + 3 && a.q == d->y + 7 && a.vel == d->y + 9 &&
                  a.angvel == d->y + 12 && a.qd == d->y + 15 && a.njoint == 2);
        cr_expect(b.pos == NULL && b.quat == NULL && b.vel == NULL && b.angvel == NULL && b.q == d->y + 17 &&
                  b.qd == d->y + 20 && b.njoint == 3);
        cr_expect(c.pos == d->y + 23 && c.quat == d->y + 26 && c.vel == d->y + 30 && c.angvel == d->y + 33 &&
                  c.njoint == 0);
        /* initial state from the descriptions */
        cr_expect(c.pos[0] == 1 && c.pos[2] == 3 && c.quat[0] == 1 && c.vel[0] == 0.5 && c.angvel[2] == 0.25);
        cr_expect(fabs(b.q[1] - 0.2) < 1e-15 && fabs(b.qd[2] + 0.6) < 1e-15);
        cr_expect(fabs(cd_joint_q(m, d, 5) - 0.2) < 1e-15 && cd_joint_q(m, d, 3) == 0.0);
    }
    cd_data_free(d);
    cd_model_free(m);
}

/* ---- names ---------------------------------------------------------------------- */
Test(model, names_and_defaults)
{
    int i;
    cd_options o = cd_options_default();
    for (i = 0; i < CD_STEP_NTYPES; i++)
        cr_expect(cd_stepper_from_name(cd_stepper_name((cd_stepper)i)) == i, "stepper %d", i);
    for (i = 0; i < CD_SHAPE_NTYPES; i++)
        cr_expect(cd_shape_type_from_name(cd_shape_type_name((cd_shape_type)i)) == i, "shape %d", i);
    cr_expect(cd_stepper_from_name("euler") == -1 && cd_stepper_from_name(NULL) == -1);
    cr_expect(strcmp(cd_stepper_name(CD_STEP_RK8PD), "rk8pd") == 0);
    for (i = CD_OK; i <= CD_EINTERRUPT; i++)
        cr_expect(strlen(cd_status_string((cd_status)i)) > 0 && strcmp(cd_status_string((cd_status)i), "unknown status") != 0);
    cr_expect(strcmp(cd_version(), CD_VERSION_STRING) == 0);
    /* the defaults documented in include/capdyn/model.h */
    cr_expect(o.stepper == CD_STEP_AUTO && o.jacobian == CD_JAC_MODEL && o.rtol == 1e-9 && o.atol == 1e-12 && o.h_init == 1e-5 &&
              o.h_max == 1e-2 && o.h_min == 1e-14 && o.h_fixed == 1e-5 && o.max_steps == 100000000L &&
              o.event_tol == 1e-10 && o.dwell == 1e-7 && o.v_reg == 1e-6 && o.fd_eps == 1e-7);
}

Test(model, flat_convex_hull_is_rejected)
{
    /* Four coplanar vertices span no volume: every vertex triple would pass
     * the one-side test and the "hull" would act as a half-space. */
    cd_model *m = cd_model_create();
    cd_system_desc s = cd_system_desc_default();
    cd_error e;
    double sq[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    s.name = "plate";
    s.type = CD_BASE_FIXED;
    cr_assert(cd_model_add_system(m, &s, &e) == 0);
    cr_assert(cd_model_add_shape(m, 0, CD_SHAPE_CONVEX, NULL, NULL, NULL, sq, 4, &e) == 0, "%s", e.msg);
    clear(&e);
    cr_expect_eq(cd_model_finalize(m, &e), CD_EINVAL);
    cr_expect(strstr(e.msg, "no volume") != NULL && strstr(e.msg, "'plate'") != NULL, "message: %s", e.msg);
    cd_model_free(m);
}

Test(model, options_edited_after_finalize_are_checked_at_data_creation)
{
    /* m->opt may be edited after finalize (it is how runs are configured);
     * a negative tolerance would make GSL abort inside cd_data_create. */
    cd_model *m = cd_model_create();
    cd_system_desc s = cd_system_desc_default();
    cd_error e;
    cr_assert(cd_model_add_system(m, &s, &e) == 0);
    cr_assert(cd_model_finalize(m, &e) == CD_OK);
    m->opt.atol = -1;
    clear(&e);
    cr_expect(cd_data_create(m, 0, &e) == NULL);
    cr_expect_eq(e.status, CD_EINVAL);
    cr_expect(strstr(e.msg, "tolerances") != NULL, "message: %s", e.msg);
    m->opt.atol = 1e-12;
    m->opt.h_fixed = HUGE_VAL;
    cr_expect(cd_data_create(m, 0, &e) == NULL, "an infinite fixed step is refused");
    cd_model_free(m);
}

/* issue 18: a relative tolerance double precision cannot meet is refused up
 * front (a tick at rtol 1e-16 never returned), 0 (pure atol) and 1e-14 are not */
Test(model, options_refuse_an_rtol_below_double_precision)
{
    cd_options o = cd_options_default();
    cd_error e;
    o.rtol = 1e-16;
    cr_expect_eq(cd_options_check(&o, &e), CD_EINVAL);
    cr_expect(strstr(e.msg, "rtol 1e-16") != NULL, "message names the value: %s", e.msg);
    o.rtol = CD_RTOL_MIN;
    cr_expect_eq(cd_options_check(&o, &e), CD_OK, "%s", e.msg);
    o.rtol = 0;
    o.atol = 1e-9;
    cr_expect_eq(cd_options_check(&o, &e), CD_OK, "%s", e.msg);
}
