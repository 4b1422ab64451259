/* The structured Jacobian (src/sim/jac.c) against the finite-difference
 * Jacobian it replaced, on states of the shipped hands in contact.
 *
 * What must agree: the stiff blocks, i.e. the rows of the generalized
 * accelerations against the positions, the velocities and the stick anchors,
 * and the anchors' own rows. The structured Jacobian leaves out by design
 * the terms of the order of the forces (Coriolis, gravity, the turning of
 * contact normals and frames, dH/dq): on a grasp those are a few per cent of
 * the contact stiffness terms (the normal of a 35 mm cylinder turns by
 * 1/R = 29 rad/m, against f_n / K x ~ 1), so each block must agree within 5 %
 * of its norm (Frobenius), and the kinematic rows exactly (1e-6: the
 * difference's own truncation). The scenarios are run into their grasps
 * first, so every contact mode (stick, slip, open) is exercised. */
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <capdyn/io.h>
#include "../src/sim/jac.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *root(void)
{
    const char *r = getenv("CAPDYN_ROOT");
    return r && *r ? r : ".";
}

/* the active set of ros34pw2: every coordinate and velocity, closed slots' anchors, joint-friction anchors */
static int active(const cd_model *m, const cd_data *d, int *act)
{
    int i, k, na = 0;
    for (i = 0; i < m->ny_slot_adr; i++) act[na++] = i;
    for (k = 0; k < m->nslot; k++)
        if (d->slot_mode[k] != CD_MODE_OPEN)
            for (i = 0; i < 3; i++) act[na++] = m->ny_slot_adr + 3 * k + i;
    for (i = 0; i < m->nfric; i++) act[na++] = m->ny_fric_adr + i;
    return na;
}

/* forward differences, the oracle: central would be better, forward is what ros34pw2 used */
static void fd_jac(const cd_model *m, cd_data *d, const int *act, int na, double *J)
{
    double *y0 = malloc((size_t)m->ny * sizeof(double)), *f0 = malloc((size_t)m->ny * sizeof(double));
    double *ysave = d->y;
    int a, c;
    memcpy(y0, d->y, (size_t)m->ny * sizeof(double));
    cr_assert_eq(cd_forward(m, d), CD_OK);
    memcpy(f0, d->ydot, (size_t)m->ny * sizeof(double));
    d->y = y0;
    for (c = 0; c < na; c++) {
        int j = act[c];
        double yj = y0[j], h = 1e-7 * (fabs(yj) > 1 ? fabs(yj) : 1);
        y0[j] = yj + h;
        h = y0[j] - yj;
        cr_assert_eq(cd_forward(m, d), CD_OK);
        for (a = 0; a < na; a++) J[a * na + c] = (d->ydot[act[a]] - f0[act[a]]) / h;
        y0[j] = yj;
    }
    d->y = ysave;
    cr_assert_eq(cd_forward(m, d), CD_OK);
    free(y0);
    free(f0);
}

/* which block an active unknown belongs to: 0 position, 1 velocity, 2 anchor */
static int kind_of(const cd_model *m, int yi)
{
    int s;
    if (yi >= m->ny_slot_adr) return 2;
    for (s = 0; s < m->nsys; s++) {
        int a = m->sys_y_adr[s], nj = m->sys_nbody[s] - 1;
        int npos = m->sys_base_type[s] == CD_BASE_FREE ? 7 + nj : nj;
        if (yi >= a && yi < a + npos) return 0;
        if (yi >= a + npos && yi < a + npos + m->sys_ndof[s]) return 1;
    }
    return 2;
}

typedef struct { int nclosed, nslip; double worst[3][3]; } jac_report;

static void compare_at(const cd_model *m, cd_data *d, jac_report *rep)
{
    int *act = malloc((size_t)m->ny * sizeof(int)), na, a, c, r, k;
    double *Jm, *Jf, num[3][3] = {{0}}, den[3][3] = {{0}};
    cd_jacw w;
    void *mem;
    na = active(m, d, act);
    Jm = calloc((size_t)na * na, sizeof(double));
    Jf = calloc((size_t)na * na, sizeof(double));
    mem = malloc(cd_jacw_size(m, na));
    cd_jacw_init(&w, m, na, mem);
    cr_assert_eq(cd_jac_model(m, d, d->t, d->y, act, na, Jm, &w), CD_OK);
    fd_jac(m, d, act, na, Jf);
    for (a = 0; a < na; a++)
        for (c = 0; c < na; c++) {
            int ra = kind_of(m, act[a]), rc = kind_of(m, act[c]);
            double e = Jm[a * na + c] - Jf[a * na + c];
            num[ra][rc] += e * e;
            den[ra][rc] += Jf[a * na + c] * Jf[a * na + c];
        }
    for (r = 0; r < 3; r++)
        for (c = 0; c < 3; c++) {
            double rel = den[r][c] > 0 ? sqrt(num[r][c] / den[r][c]) : sqrt(num[r][c]);
            if (rel > rep->worst[r][c]) rep->worst[r][c] = rel;
        }
    for (k = 0; k < m->nslot; k++) {
        if (d->slot_mode[k] != CD_MODE_OPEN) rep->nclosed++;
        if (d->slot_mode[k] == CD_MODE_SLIP) rep->nslip++;
    }
    free(mem);
    free(Jm);
    free(Jf);
    free(act);
}

static void check_scenario_with(const char *name, double t_stop, int nstates, const char *const *extra, int nextra)
{
    char path[1024];
    const char *ov[8] = {"simulation.integrator=\"ros34pw2\""};
    cd_error e;
    cd_scenario *sc;
    cd_data *d;
    jac_report rep;
    int i, r, c;
    snprintf(path, sizeof path, "%s/scenarios/%s", root(), name);
    for (i = 0; i < nextra && i < 7; i++) ov[1 + i] = extra[i];
    sc = cd_scenario_load(path, ov, 1 + (nextra < 7 ? nextra : 7), &e);
    cr_assert(sc, "%s", e.msg);
    d = cd_data_create(sc->model, sc->event_capacity, &e);
    cr_assert(d, "%s", e.msg);
    memset(&rep, 0, sizeof rep);
    srand(7);
    for (i = 0; i < nstates; i++) {
        cr_assert_eq(cd_sim_advance(sc->model, d, t_stop * (i + 1) / nstates, NULL, NULL, &e), CD_OK, "%s", e.msg);
        compare_at(sc->model, d, &rep);
    }
    cr_log_info("%s: %d closed slots (%d slipping) over the states; worst relative errors, rows pos/vel/anchor x "
                "columns pos/vel/anchor: %.2g %.2g %.2g | %.2g %.2g %.2g | %.2g %.2g %.2g", name, rep.nclosed,
                rep.nslip, rep.worst[0][0], rep.worst[0][1], rep.worst[0][2], rep.worst[1][0], rep.worst[1][1],
                rep.worst[1][2], rep.worst[2][0], rep.worst[2][1], rep.worst[2][2]);
    cr_expect_gt(rep.nclosed, 0, "%s: no contact closed at the states compared", name);
    for (r = 0; r < 3; r++)
        for (c = 0; c < 3; c++) {
            /* rows of positions: exact kinematics; the rest: the stiff blocks */
            double tol = r == 0 ? 1e-6 : 0.05;
            if (r == 2 && c == 0) continue; /* anchors' rates against positions: only the turning of the normal, left out */
            cr_expect_leq(rep.worst[r][c], tol, "%s: block (%s, %s) off by %.3g (relative, Frobenius), tolerance %g",
                          name, r == 0 ? "pos" : r == 1 ? "vel" : "anchor", c == 0 ? "pos" : c == 1 ? "vel" : "anchor",
                          rep.worst[r][c], tol);
        }
    cd_data_free(d);
    cd_scenario_free(sc);
}

static void check_scenario(const char *name, double t_stop, int nstates)
{
    check_scenario_with(name, t_stop, nstates, NULL, 0);
}

/* Hunt-Crossley damping (D |x|^p xdot^q, contact.h) on every pair of the
 * Fig. 5 grasp, with p = 1.5 so that both partials carry the x-dependence:
 * the same tolerance against the finite differences as the linear law. */
Test(jac, structured_matches_fd_with_hunt_crossley_pairs, .timeout = 120)
{
    const char *ov[] = {"pair.hand_object.damping_law=\"hunt_crossley\"", "pair.hand_object.D=7500",
                        "pair.hand_object.D_t=109.5", "pair.hand_object.p=1.5", "pair.hand_object.K=5e5"};
    check_scenario_with("paper_fig5_envelope_grasp.toml", 1.0, 5, ov, 5);
}

Test(jac, structured_matches_fd_on_the_fig5_grasp, .timeout = 120) { check_scenario("paper_fig5_envelope_grasp.toml", 1.0, 5); }
Test(jac, structured_matches_fd_on_the_space_gripper, .timeout = 120) { check_scenario("space_gripper_cylinder.toml", 1.0, 5); }
Test(jac, structured_matches_fd_on_tako, .timeout = 120) { check_scenario("tako_centred.toml", 1.0, 5); }
Test(jac, structured_matches_fd_on_the_soft_wrap, .timeout = 120) { check_scenario("soft_wrap.toml", 0.2, 4); }
