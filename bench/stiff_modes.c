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
 * --gap H also compares that Jacobian with the structured one of the
 * linearly implicit steppers (src/sim/jac.c, the same unknowns) and prints
 * the size of what the structured one leaves out, D = J_difference -
 * J_structured: its Frobenius and 2-norms, h |D|_2 at the step H, and the
 * rows and columns that carry its largest entries (docs/performance.md
 * section 19: an order-4 W-method's error expansion in h (J - A) needs
 * h |D| well below 1).
 *
 * Usage: stiff_modes SCENARIO.toml T [-n N] [--gap H] [--set KEY=VALUE]...
 * (run from the repository root; built by `make build/stiff_modes`). */
#include <capdyn/capdyn.h>
#include <capdyn/io.h>
#include "../src/sim/jac.h"
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

/* the largest entry of row (by = 0) or column (by = 1) i of the n x n D */
static double line_max(const double *D, int n, int i, int by)
{
    double mx = 0;
    int k;
    for (k = 0; k < n; k++) {
        double v = fabs(by ? D[(size_t)k * n + i] : D[(size_t)i * n + k]);
        if (v > mx) mx = v;
    }
    return mx;
}

/* --gap: J (the differences) against the structured Jacobian on the same unknowns */
static int print_gap(const cd_model *m, cd_data *d, const int *act, int na, const gsl_matrix *J, double H)
{
    double *Js = (double *)calloc((size_t)na * (size_t)na, sizeof(double)), *x = (double *)malloc(sizeof(double) * (size_t)na);
    double *u = (double *)malloc(sizeof(double) * (size_t)na), fro = 0, fro_d = 0, n2 = 0;
    void *mem = malloc(cd_jacw_size(m, na));
    cd_jacw jw;
    int i, j, k, by, *done = (int *)calloc((size_t)na, sizeof(int));
    if (!Js || !x || !u || !mem || !done) { fprintf(stderr, "out of memory\n"); return 1; }
    cd_jacw_init(&jw, m, na, mem);
    if (cd_jac_model(m, d, d->t, d->y, act, na, Js, &jw) != CD_OK) { fprintf(stderr, "structured Jacobian failed\n"); return 1; }
    for (i = 0; i < na; i++)
        for (j = 0; j < na; j++) {
            double f = gsl_matrix_get(J, (size_t)i, (size_t)j);
            Js[(size_t)i * na + j] = f - Js[(size_t)i * na + j]; /* now D */
            fro += f * f;
            fro_d += Js[(size_t)i * na + j] * Js[(size_t)i * na + j];
        }
    for (i = 0; i < na; i++) x[i] = 1.0 / (1 + i % 5);
    for (k = 0; k < 100; k++) { /* |D|_2 by power iteration on D^T D */
        double nx = 0;
        for (i = 0; i < na; i++) nx += x[i] * x[i];
        nx = sqrt(nx);
        if (!(nx > 0)) break;
        for (i = 0; i < na; i++) {
            u[i] = 0;
            for (j = 0; j < na; j++) u[i] += Js[(size_t)i * na + j] * x[j] / nx;
        }
        for (j = 0; j < na; j++) {
            x[j] = 0;
            for (i = 0; i < na; i++) x[j] += Js[(size_t)i * na + j] * u[i];
        }
        n2 = 0;
        for (i = 0; i < na; i++) n2 += u[i] * u[i];
        n2 = sqrt(n2);
    }
    printf("left out of the structured Jacobian: |D|_F %.3g against |J|_F %.3g; |D|_2 %.3g 1/s^2, h |D|_2 = %.3g at h = %g s\n",
           sqrt(fro_d), sqrt(fro), n2, H * n2, H);
    for (by = 0; by < 2; by++) {
        printf("    largest %s of D:\n", by ? "columns" : "rows");
        for (k = 0; k < 4; k++) {
            int best = -1;
            double bv = 0;
            char buf[160];
            for (i = 0; i < na; i++)
                if (!done[i] && line_max(Js, na, i, by) > bv) { bv = line_max(Js, na, i, by); best = i; }
            if (best < 0) break;
            done[best] = 1;
            label(m, act[best], buf, sizeof buf);
            printf("      %-48s %.3g\n", buf, bv);
        }
        memset(done, 0, sizeof(int) * (size_t)na);
    }
    free(Js);
    free(x);
    free(u);
    free(mem);
    free(done);
    return 0;
}

int main(int argc, char **argv)
{
    const char *sets[MAX_SETS];
    int nsets = 0, nshow = 5, i, j, k, na = 0, *act;
    double T, *y0, *f0, gap = 0;
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
        fprintf(stderr, "usage: %s SCENARIO.toml T [-n N] [--gap H] [--set KEY=VALUE]...\n", argv[0]);
        return 2;
    }
    T = atof(argv[2]);
    for (i = 3; i < argc; i++) {
        if (!strcmp(argv[i], "-n") && i + 1 < argc) nshow = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--gap") && i + 1 < argc) gap = atof(argv[++i]);
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
    if (cd_forward(m, d) != CD_OK) { fprintf(stderr, "evaluation failed\n"); return 1; }
    if (gap > 0 && print_gap(m, d, act, na, J, gap)) return 1;
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
