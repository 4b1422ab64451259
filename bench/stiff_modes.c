/* The stiffest modes of a scenario at a time of its run: what caps an
 * explicit step there (docs/performance.md section 12).
 *
 * Runs the scenario (its own settings, --set overrides, its built-in
 * controller) to time T, then forms the Jacobian of the right-hand side
 * (cd_forward) by forward differences over the unknowns that can move (the
 * open slots' anchors have derivative 0 and are left out), with the slot
 * modes as they are at T, and prints its N largest eigenvalues by modulus
 * (GSL's nonsymmetric eigensolver) with the unknowns that carry most of
 * each eigenvector. An explicit method is stable for h |lambda| below its
 * stability boundary (about 5 for rk8pd on the negative real axis), so the
 * largest |lambda| bounds its step.
 *
 * Usage: stiff_modes SCENARIO.toml T [-n N] [--set KEY=VALUE]...
 * (run from the repository root; built by `make build/stiff_modes`). */
#include <capdyn/capdyn.h>
#include <capdyn/io.h>
#include <gsl/gsl_complex_math.h>
#include <gsl/gsl_eigen.h>
#include <gsl/gsl_matrix.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_SETS 16

/* a name for unknown i of y (docs/dynamics.md, "State") */
static void label(const cd_model *m, int i, char *buf, size_t len)
{
    int s, off, n, fb, np;
    if (i >= m->ny_fric_adr) { snprintf(buf, len, "joint-friction anchor %d", i - m->ny_fric_adr); return; }
    if (i >= m->ny_slot_adr) {
        snprintf(buf, len, "slot %d anchor [%d]", (i - m->ny_slot_adr) / 3, (i - m->ny_slot_adr) % 3);
        return;
    }
    for (s = m->nsys - 1; s > 0 && i < m->sys_y_adr[s]; s--) {}
    off = i - m->sys_y_adr[s];
    n = m->sys_nbody[s] - 1;
    fb = m->sys_base_type[s] == CD_BASE_FREE;
    np = fb ? 7 + n : n;
    if (off < np) {
        if (fb && off < 3) snprintf(buf, len, "%s base position [%d]", m->sys_name[s], off);
        else if (fb && off < 7) snprintf(buf, len, "%s base quaternion [%d]", m->sys_name[s], off - 3);
        else snprintf(buf, len, "%s q %s", m->sys_name[s], m->body_name[m->sys_body_adr[s] + 1 + off - (fb ? 7 : 0)]);
        return;
    }
    off -= np;
    if (fb && off < 3) snprintf(buf, len, "%s base velocity [%d]", m->sys_name[s], off);
    else if (fb && off < 6) snprintf(buf, len, "%s base angular velocity [%d]", m->sys_name[s], off - 3);
    else snprintf(buf, len, "%s qd %s", m->sys_name[s], m->body_name[m->sys_body_adr[s] + 1 + off - (fb ? 6 : 0)]);
}

int main(int argc, char **argv)
{
    const char *sets[MAX_SETS];
    int nsets = 0, nshow = 5, i, j, k, na = 0, *act;
    double T, *y0, *f0;
    cd_error err;
    cd_scenario *sc;
    cd_data *d;
    cd_ctrl *ctl = NULL;
    const cd_model *m;
    gsl_matrix *J;
    gsl_vector_complex *ev;
    gsl_matrix_complex *V;
    gsl_eigen_nonsymmv_workspace *w;
    if (argc < 3) {
        fprintf(stderr, "usage: %s SCENARIO.toml T [-n N] [--set KEY=VALUE]...\n", argv[0]);
        return 2;
    }
    T = atof(argv[2]);
    for (i = 3; i < argc; i++) {
        if (!strcmp(argv[i], "-n") && i + 1 < argc) nshow = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--set") && i + 1 < argc && nsets < MAX_SETS) sets[nsets++] = argv[++i];
        else { fprintf(stderr, "%s: unknown argument '%s'\n", argv[0], argv[i]); return 2; }
    }
    memset(&err, 0, sizeof err);
    if (!(sc = cd_scenario_load(argv[1], sets, nsets, &err))) { fprintf(stderr, "%s\n", err.msg); return 1; }
    m = sc->model;
    if (!(d = cd_data_create(m, sc->event_capacity, &err))) { fprintf(stderr, "%s\n", err.msg); return 1; }
    if (sc->control) {
        if (!(ctl = cd_ctrl_create(m, sc->control, &err))) { fprintf(stderr, "%s\n", err.msg); return 1; }
        cd_ctrl_install(ctl, d);
    }
    if (cd_sim_advance(m, d, T, NULL, NULL, &err) != CD_OK) { fprintf(stderr, "%s\n", err.msg); return 1; }
    act = (int *)malloc(sizeof(int) * (size_t)m->ny);
    y0 = (double *)malloc(sizeof(double) * (size_t)m->ny);
    f0 = (double *)malloc(sizeof(double) * (size_t)m->ny);
    if (!act || !y0 || !f0) { fprintf(stderr, "out of memory\n"); return 1; }
    for (i = 0; i < m->ny; i++)
        if (!(i >= m->ny_slot_adr && i < m->ny_fric_adr && d->slot_mode[(i - m->ny_slot_adr) / 3] == CD_MODE_OPEN))
            act[na++] = i;
    memcpy(y0, d->y, sizeof(double) * (size_t)m->ny);
    if (cd_forward(m, d) != CD_OK) { fprintf(stderr, "evaluation failed at t = %g\n", d->t); return 1; }
    memcpy(f0, d->ydot, sizeof(double) * (size_t)m->ny);
    J = gsl_matrix_alloc((size_t)na, (size_t)na);
    for (j = 0; j < na; j++) {
        double h = 1e-7 * (1.0 + fabs(y0[act[j]]));
        d->y[act[j]] = y0[act[j]] + h;
        if (cd_forward(m, d) != CD_OK) { fprintf(stderr, "evaluation failed\n"); return 1; }
        for (i = 0; i < na; i++) gsl_matrix_set(J, (size_t)i, (size_t)j, (d->ydot[act[i]] - f0[act[i]]) / h);
        d->y[act[j]] = y0[act[j]];
    }
    ev = gsl_vector_complex_alloc((size_t)na);
    V = gsl_matrix_complex_alloc((size_t)na, (size_t)na);
    w = gsl_eigen_nonsymmv_alloc((size_t)na);
    gsl_eigen_nonsymmv(J, ev, V, w);
    gsl_eigen_nonsymmv_sort(ev, V, GSL_EIGEN_SORT_ABS_DESC);
    printf("%s at t = %.6g s: %d unknowns that can move; closed slots:", argv[1], d->t, na);
    for (k = 0; k < m->nslot; k++)
        if (d->slot_mode[k] != CD_MODE_OPEN) printf(" %d (%s)", k, d->slot_mode[k] == CD_MODE_STICK ? "stick" : "slip");
    printf("\n");
    for (k = 0; k < nshow && k < na; k++) {
        gsl_complex l = gsl_vector_complex_get(ev, (size_t)k);
        double a = gsl_complex_abs(l);
        printf("lambda %d = %.4g %+.4g i  [1/s], |lambda| %.4g: rk8pd stable below h = %.3g s\n", k, GSL_REAL(l),
               GSL_IMAG(l), a, 5.0 / a);
        for (j = 0; j < 4; j++) { /* the unknowns with the largest components */
            int best = -1;
            double bv = 0;
            char buf[160];
            for (i = 0; i < na; i++) {
                double c = gsl_complex_abs(gsl_matrix_complex_get(V, (size_t)i, (size_t)k));
                if (c > bv) { bv = c; best = i; }
            }
            if (best < 0) break;
            label(m, act[best], buf, sizeof buf);
            printf("    %-48s %.3g\n", buf, bv);
            gsl_matrix_complex_set(V, (size_t)best, (size_t)k, GSL_COMPLEX_ZERO);
        }
    }
    gsl_eigen_nonsymmv_free(w);
    gsl_matrix_complex_free(V);
    gsl_vector_complex_free(ev);
    gsl_matrix_free(J);
    free(act);
    free(y0);
    free(f0);
    cd_ctrl_free(ctl);
    cd_data_free(d);
    cd_scenario_free(sc);
    return 0;
}
