/* ROS34PW2: a linearly implicit Rosenbrock-W method for stiff contact.
 *
 * Why: with explicit Runge-Kutta steppers the step in a grasp is capped by
 * stability, not accuracy: the contact damping on light finger links puts an
 * eigenvalue near -3e4 1/s, so rk8pd holds h ~ 5/|lambda| whatever the
 * tolerance (docs/performance.md). A linearly implicit step solves with
 * (I - h gamma J) once per stage and is stable for any h on such modes.
 *
 * The method (Rang and Angermann, BIT 45 (2005) 761-787, "ROS34PW2"): 4
 * stages, order 3 with an embedded order-2 solution, L-stable, stiffly
 * accurate, and a W-method: its order holds with any matrix in place of the
 * exact Jacobian. That is what lets capdyn
 *   - keep a Jacobian for several steps (CD_ROSW_JAC_AGE accepted steps, or
 *     until a restart: an event, a mode or input change, a breakpoint);
 *   - use it on the *active* unknowns only (every generalized coordinate and
 *     velocity, the joint-friction anchors, and the tangential deflections of
 *     closed contact slots, at most CD_ROSW_MAX_SLOTS of them): the rest
 *     (deflections of open slots, whose derivative is 0) are stepped
 *     explicitly, which is exact for them;
 *   - ignore df/dt (time enters through schedules, whose steps are
 *     breakpoints, and through smooth profiles).
 * The Jacobian is a forward finite difference, one evaluation per active
 * unknown (opt.fd_eps as for rk4imp/msbdf). The stiffness comes from the
 * contact forces, whose derivatives are what the difference captures.
 *
 * Stages (increments k_i include h; gamma the diagonal):
 *   (I - h gamma J) k_i = h f(t + a_i h, y + sum_j alpha_ij k_j) + h J sum_j gamma_ij k_j
 *   y1 = y + sum b_i k_i,   error = sum (b_i - bhat_i) k_i.
 * They are computed in the transformed unknowns u_i = sum_j Gamma_ij k_j
 * (rosw_state), which needs no product of J with a vector.
 * f(t, y) comes from the driver (can_use_dydt_in). dydt_out must be the
 * exact f(t + h, y1): GSL's evolve hands it back as the next step's dydt_in
 * (whatever gives_exact_dydt_out says), and the standard control scales the
 * tolerance with it. A step so costs 4 evaluations (3 stages and the end),
 * plus the Jacobian when it is renewed. */
#include "rosw.h"
#include "rk8.h"
#include "../math/cd_math.h"

#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* A tableau in the increment form above: s stages, alpha (strictly lower),
 * gamma (strictly lower; the diagonal is gam), the solution b and the
 * embedded bhat. exact: the method is a Rosenbrock method, not a W-method,
 * and its order needs the exact Jacobian (and df/dt): rosw_apply then renews
 * a finite-difference Jacobian at every step start and adds
 * gsum_i h^2 df/dt to the stages (gsum_i = gam + sum_j gamma_ij). filter:
 * the error estimate goes through (I - h gam J)^-1 (ROS34PW2's embedded
 * solution is not L-stable; RODAS4's is). */
#define CD_ROSW_SMAX 6
typedef struct {
    const char *name;
    int s, order, exact, filter;
    double gam;
    double alpha[CD_ROSW_SMAX][CD_ROSW_SMAX], gamma[CD_ROSW_SMAX][CD_ROSW_SMAX];
    double b[CD_ROSW_SMAX], bhat[CD_ROSW_SMAX], gsum[CD_ROSW_SMAX];
} rosw_tab;

#define GAM 0.435866521508459
#ifdef CD_TRIAL_ROS34PW3
/* A build-time trial only (docs/performance.md section 18): ROS34PW3 of
 * the same paper (order 4 with the exact Jacobian, 3 as a W-method,
 * A-stable, R(inf) = 0.63) in place of ROS34PW2's tableau, converted to the
 * increment form here (Gamma = (I/gam - C)^-1 of its transformed form; the
 * same conversion gives ROS34PW2's coefficients below to 1e-15). */
static const rosw_tab TAB_ROS34PW2 = {
    "ros34pw3", 4, 4, 0, 1, 1.0685790213016289,
    {{0, 0, 0}, {2.5155456020628821, 0, 0}, {0.50777280103144151, 0.75, 0}, {0.1395908140427724, -0.33111001065419338, 0.82040559712714178}},
    {{0, 0, 0},
     {-2.5155456020628817, 0, 0},
     {-0.87991339217106534, -0.96014187766190695, 0},
     {-0.41731389379448769, 0.41091047035857714, -1.3558873204765276}},
    {0.22047681286931822, 0.0027828278331186, 0.00718447876351395, 0.7695558805340499},
    {0.31300297285209672, -0.28946895245112703, 0.97646597959903003, 0},
    {0}};
#else
static const rosw_tab TAB_ROS34PW2 = {
    "ros34pw2", 4, 3, 0, 1, GAM,
    {{0, 0, 0}, {0.87173304301691801, 0, 0}, {0.84457060015369423, -0.11299064236484185, 0}, {0, 0, 1}},
    {{0, 0, 0},
     {-0.87173304301691801, 0, 0},
     {-0.90338057013044082, 0.054180672388095326, 0},
     {0.24212380706095346, -1.2232505839045147, 0.54526025533510214}},
    {0.24212380706095346, -1.2232505839045147, 1.5452602553351020, GAM},
    {0.37810903145819369, -0.096042292212423178, 0.5, 0.2179332607542295},
    {0}};
#endif

/* RODAS4: Hairer & Wanner, Solving Ordinary Differential Equations II (2nd
 * ed., Springer 1996), sec. VI.4, and the coefficients of their code
 * rodas.f (METH = 1: gamma = 0.25, c = 0.386, 0.21, 0.63, 1, 1): 6 stages,
 * order 4 with an embedded order-3 solution, L-stable, stiffly accurate (the
 * embedded solution is the last stage's argument). rodas.f states them in
 * the transformed variables u_i = sum_j Gamma_ij k_j (a_ij, c_ij, m_i,
 * e_i); converted to the increment form here by Gamma = (I/gam - C)^-1,
 * alpha = a Gamma, b = m Gamma, bhat = (m - e) Gamma (tests/test_ros4.c
 * checks the row sums against rodas.f's c_i and gamma_i and the measured
 * order). 6 evaluations per step (5 stages and the end), plus the Jacobian. */
static const rosw_tab TAB_RODAS4 = {
    "rodas4", 6, 4, 1, 0, 0.25,
    {{0, 0, 0, 0, 0},
     {0.38600000000000001, 0, 0, 0, 0},
     {0.1460747075254179, 0.063925292474582104, 0, 0, 0},
     {-0.33081150366773016, 0.71115102516828466, 0.24966047849944542, 0, 0},
     {-4.5525571863180314, 1.7101813632413321, 4.0143473321031724, -0.17197150902647376, 0},
     {2.4286337654669881, -0.38274873376478435, -1.8557203309295804, 0.55983529922737629, 0.25}},
    {{0, 0, 0, 0, 0},
     {-0.3543, 0, 0, 0, 0},
     {-0.13360250526817558, -0.012897494731824468, 0, 0, 0},
     {1.5268491730064673, -0.53365628875045723, -1.2793928842560101, 0, 0},
     {6.9811909517850195, -2.0929300970061164, -5.8700676630327528, 0.73180680825385003, 0},
     {-2.0801894941809369, 0.59576235567668334, 1.7016177982672627, -0.088514519835880545, -0.3786761399271284}},
    {0.34844427128605115, 0.21301362191189899, -0.15410253266231777, 0.47132077939149575, -0.1286761399271284, 0.25},
    {2.4286337654669881, -0.38274873376478435, -1.8557203309295804, 0.55983529922737629, 0.25, 0},
    {0.25, -0.1043, 0.1035, -0.0362, 0, 0}};

static int jacobian(cd_rosw *w, double t, const double *y, const double *f0, const gsl_odeiv2_system *sys, int exact);

static int na_capacity(const cd_model *m)
{
    int ns = m->nslot < CD_ROSW_MAX_SLOTS ? m->nslot : CD_ROSW_MAX_SLOTS;
    return m->ny_slot_adr + 3 * ns + m->nfric;
}

int cd_rosw_na_max(const cd_model *m) { return na_capacity(m); }

int cd_rosw_jacobian(cd_rosw *w, double t, const double *y, const double *f0, const gsl_odeiv2_system *sys)
{
    return jacobian(w, t, y, f0, sys, 0);
}

/* Bytes of carve()'s buffers for n unknowns and an active capacity na - 1
 * (16-aligned start): the three na x na matrices, the sparse rows of the
 * reduced solve (at most 2 nU (na - nU) <= na^2 / 2 nonzeros), the stage and
 * work vectors, the index arrays and the runs of unknowns that can move. */
static size_t buf_size(size_t n, size_t na)
{
    return 16 + (3 * na * na + 12 * n + 2 * na) * sizeof(double) + na * (sizeof(size_t) + 4 * sizeof(int)) + 16 +
           (na * na / 2 + 1) * (sizeof(double) + sizeof(int)) + (2 * na + 2) * sizeof(int) + 16 +
           2 * (n + 2) * sizeof(int) + 2 * na * sizeof(int);
}

size_t cd_rosw_size(const cd_model *m)
{
    size_t n = (size_t)(m->ny ? m->ny : 1), na = (size_t)na_capacity(m) + 1;
    return buf_size(n, na) + cd_jacw_size(m, (int)na);
}

/* The buffers of w from p (aligned): the three na x na matrices, the stage
 * and work vectors of n, then the index arrays; returns the end. */
static int *carve(cd_rosw *w, double *p, size_t n, size_t na)
{
    int i;
    w->J = p; p += na * na;
    w->W = p; p += na * na;
    w->M2 = p; p += na * na;
    w->sv = p; p += na * na / 2 + 1;
    w->tu = p; p += na;
    for (i = 0; i < CD_ROSW_SMAX; i++) { w->k[i] = p; p += n; }
    w->ft = p; p += n;
    w->g = p; p += n;
    w->ytmp = p; p += n;
    w->fs = p; p += n;
    w->fd = p; p += n;
    w->r = p; p += n;   /* na <= ny entries used */
    w->perm = (int *)(void *)p;
    w->act = w->perm + na;
    w->iP = w->act + na;
    w->iU = w->iP + na;
    w->iZ = w->iU + na;
    w->sp = w->iZ + na;
    w->sc = w->sp + 2 * na + 2;
    w->rlo = w->sc + na * na / 2 + 1;
    w->rhi = w->rlo + n + 2;
    w->jlo = w->rhi + n + 2;
    w->jhi = w->jlo + na;
    return w->jhi + na;
}

void cd_rosw_init(cd_rosw *w, const cd_model *m, cd_data *d, void *mem)
{
    size_t n = (size_t)(m->ny ? m->ny : 1), na = (size_t)na_capacity(m) + 1;
    double *p = (double *)(void *)(((uintptr_t)mem + 15) & ~(uintptr_t)15);
    memset(w, 0, sizeof *w);
    w->m = NULL; (void)m; /* set per call */
    w->d = d;
    w->ny = m->ny;
    w->na_max = (int)na - 1;
    w->gam = GAM;
    cd_jacw_init(&w->jw, m, (int)na, (void *)carve(w, p, n, na));
}

size_t cd_rosw_size_plain(int ny)
{
    size_t n = (size_t)(ny > 0 ? ny : 1), na = n + 1;
    return buf_size(n, na);
}

void cd_rosw_init_plain(cd_rosw *w, int ny, double fd_eps, void *mem)
{
    size_t n = (size_t)(ny > 0 ? ny : 1), na = n + 1;
    double *p = (double *)(void *)(((uintptr_t)mem + 15) & ~(uintptr_t)15);
    memset(w, 0, sizeof *w);
    w->ny = ny;
    w->na_max = ny;
    w->gam = GAM;
    w->fd_eps_plain = fd_eps;
    (void)carve(w, p, n, na);
}

void cd_rosw_invalidate(cd_rosw *w) { w->jac_ok = 0; w->lu_ok = 0; w->rho_ok = 0; }

/* the active set at the current modes */
static void active_set(cd_rosw *w)
{
    const cd_model *m = w->m;
    const cd_data *d = w->d;
    int i, k, ns = 0, na = 0;
    if (!m) { /* cd_rosw_init_plain: every unknown */
        for (i = 0; i < w->ny; i++) w->act[i] = i;
        w->na = w->ny;
        return;
    }
    for (i = 0; i < m->ny_slot_adr; i++) w->act[na++] = i;
    for (k = 0; k < m->nslot && ns < CD_ROSW_MAX_SLOTS; k++)
        if (d->slot_mode[k] != CD_MODE_OPEN) {
            for (i = 0; i < 3; i++) w->act[na++] = m->ny_slot_adr + 3 * k + i;
            ns++;
        }
    for (i = 0; i < m->nfric; i++) w->act[na++] = m->ny_fric_adr + i;
    w->na = na;
}

/* the place in the active set of the k-th of the positions and anchors (iP, then iZ) */
static int pz_at(const cd_rosw *w, int k) { return k < w->nP ? w->iP[k] : w->iZ[k - w->nP]; }

/* The reduced solve. A structured Jacobian has the pattern of a second-order
 * system: positions move with the velocities (P rows: U columns, and the
 * quaternions' own 4x4 blocks), the anchors too (Z rows: U columns), and the
 * velocities' rows hold everything stiff. The anchors of slipping slots with a
 * tangential damper (the saturated bristle, contact.c) relax on their own:
 * they join the velocities in U. The matrix the W-method uses is
 * this J without the quaternions' blocks J_PP (0.5 |w|: not stiff; a
 * W-method keeps its order with any matrix, the same one in the solve and in
 * the stage sums). Then (I - c J) x = r reduces exactly to the velocities:
 *   S u = r_U + c (J_UP r_P + J_UZ r_Z),  S = I - c J_UU - c^2 (J_UP J_PU + J_UZ J_ZU)
 *   x_P = r_P + c J_PU u,  x_Z = r_Z + c J_ZU u,  x_U = u
 * one LU of nU unknowns instead of nP + nU + nZ (Fig. 5: 14 instead of 39).
 * M2 = J_UP J_PU + J_UZ J_ZU is formed once per Jacobian. */
static void reduce(cd_rosw *w)
{
    const cd_model *m = w->m;
    int na = w->na, a, s, i, j, k;
    w->nP = w->nU = w->nZ = 0;
    for (a = 0; a < na; a++) {
        int yi = w->act[a], cls = 2;
        for (s = 0; s < m->nsys && yi < m->ny_slot_adr; s++) {
            int ya = m->sys_y_adr[s], nj = m->sys_nbody[s] - 1;
            int np = m->sys_base_type[s] == CD_BASE_FREE ? 7 + nj : nj;
            if (yi >= ya && yi < ya + np) { cls = 0; break; }
            if (yi >= ya + np && yi < ya + np + m->sys_ndof[s]) { cls = 1; break; }
        }
        if (yi >= m->ny_slot_adr && yi < m->ny_slot_adr + 3 * m->nslot) {
            /* a slipping bristle's anchor relaxes on its own (z' depends on z,
             * at the rate K_t/D_t): it goes with the velocities, whose rows
             * may depend on anything; the other anchors move with the
             * velocities only */
            int k = (yi - m->ny_slot_adr) / 3;
            if (w->d->slot_mode[k] == CD_MODE_SLIP && m->law[m->slot_law[k]].Dt > 0) cls = 1;
        }
        if (cls == 0) w->iP[w->nP++] = a;
        else if (cls == 1) w->iU[w->nU++] = a;
        else w->iZ[w->nZ++] = a;
    }
    /* the blocks the reduced matrix leaves out are zero in it (and in the stage sums) */
    for (i = 0; i < w->nP; i++) {
        for (j = 0; j < w->nP; j++) w->J[(size_t)w->iP[i] * na + w->iP[j]] = 0;
        for (j = 0; j < w->nZ; j++) w->J[(size_t)w->iP[i] * na + w->iZ[j]] = 0;
    }
    for (i = 0; i < w->nZ; i++) {
        for (j = 0; j < w->nP; j++) w->J[(size_t)w->iZ[i] * na + w->iP[j]] = 0;
        for (j = 0; j < w->nZ; j++) w->J[(size_t)w->iZ[i] * na + w->iZ[j]] = 0;
    }
    /* the blocks the solve multiplies by, as sparse rows (solve_active): the
     * velocities' rows over the positions' and anchors' columns (in the order
     * iP then iZ), then the positions' and anchors' rows over the velocities'
     * columns. Most of the latter are zero (a position moves with its own
     * velocity, an anchor with the velocities of its two bodies). */
    {
        int nnz = 0, r = 0, nPZ = w->nP + w->nZ;
        for (i = 0; i < w->nU; i++, r++) {
            const double *Ju = w->J + (size_t)w->iU[i] * na;
            w->sp[r] = nnz;
            for (k = 0; k < nPZ; k++) {
                double v = Ju[pz_at(w, k)];
                if (v != 0) { w->sv[nnz] = v; w->sc[nnz++] = k; }
            }
        }
        for (k = 0; k < nPZ; k++, r++) {
            const double *Jr = w->J + (size_t)pz_at(w, k) * na;
            w->sp[r] = nnz;
            for (j = 0; j < w->nU; j++)
                if (Jr[w->iU[j]] != 0) { w->sv[nnz] = Jr[w->iU[j]]; w->sc[nnz++] = j; }
        }
        w->sp[r] = nnz;
    }
    /* M2 = J_U,PZ J_PZ,U from the sparse rows: row i of M2 sums, over the
     * nonzeros (k, v) of row i of J_U,PZ in the order of k, v times row k of
     * J_PZ,U */
    for (i = 0; i < w->nU; i++) {
        double *Mi = w->M2 + (size_t)i * w->nU;
        int e, f;
        for (j = 0; j < w->nU; j++) Mi[j] = 0;
        for (e = w->sp[i]; e < w->sp[i + 1]; e++) {
            const int row = w->nU + w->sc[e];
            for (f = w->sp[row]; f < w->sp[row + 1]; f++) Mi[w->sc[f]] += w->sv[e] * w->sv[f];
        }
    }
    w->red = 1;
}

/* forward-difference Jacobian of f on the active set at (t, y), f0 = f(t, y) */
static int jacobian(cd_rosw *w, double t, const double *y, const double *f0, const gsl_odeiv2_system *sys, int exact)
{
    int a, c, na, n = w->ny;
    double eps = w->d ? w->d->opt.fd_eps : w->fd_eps_plain;
    active_set(w);
    na = w->na;
    w->red = 0;
    w->rho_ok = 0;
    if (!w->m && sys->jacobian) { /* plain: the system's own (exact) Jacobian and df/dt */
        if (sys->jacobian(t, y, w->J, w->ft, sys->params) != GSL_SUCCESS) return GSL_EBADFUNC;
        if (!exact) memset(w->ft, 0, (size_t)n * sizeof(double));
        goto done;
    }
    if (exact) { /* df/dt by a forward difference in t (schedules and profiles) */
        double dt = eps * (fabs(t) > 1.0 ? fabs(t) : 1.0);
        double tp = t + dt;
        dt = tp - t;
        if (GSL_ODEIV_FN_EVAL(sys, t + dt, y, w->fd) != GSL_SUCCESS) return GSL_EBADFUNC;
        for (c = 0; c < n; c++) w->ft[c] = (w->fd[c] - f0[c]) / dt;
    }
    if (!exact && w->d && w->d->opt.jacobian == CD_JAC_MODEL) {
        if (cd_jac_model(w->m, w->d, t, y, w->act, na, w->J, &w->jw) != CD_OK) return GSL_EBADFUNC;
        reduce(w);
        goto done;
    }
    memcpy(w->ytmp, y, (size_t)n * sizeof(double));
    for (c = 0; c < na; c++) {
        int j = w->act[c];
        double h = eps * (fabs(y[j]) > 1.0 ? fabs(y[j]) : 1.0);
        w->ytmp[j] = y[j] + h;
        h = w->ytmp[j] - y[j]; /* the representable increment */
        if (GSL_ODEIV_FN_EVAL(sys, t, w->ytmp, w->fd) != GSL_SUCCESS) return GSL_EBADFUNC;
        for (a = 0; a < na; a++) w->J[a * na + c] = (w->fd[w->act[a]] - f0[w->act[a]]) / h;
        w->ytmp[j] = y[j];
    }
done:
    w->jac_ok = 1;
    w->lu_ok = 0;
    w->jac_t = t;
    w->jac_age = 0;
    if (w->d) w->d->stats.njac++;
    return GSL_SUCCESS;
}

/* In-place LU with partial pivoting of the row-major n x n matrix A (Doolittle,
 * Golub & Van Loan alg. 3.4.1): no allocation, unlike gsl_linalg_LU_decomp,
 * whose recursive blocked variant allocates. piv[k]: the row swapped with k.
 * Returns -1 on a zero or non-finite pivot. */
int cd_rosw_lu_decomp(double *A, int n, int *piv)
{
    int i, j, k;
    for (k = 0; k < n; k++) {
        int p = k;
        double big = fabs(A[(size_t)k * n + k]), akk;
        for (i = k + 1; i < n; i++)
            if (fabs(A[(size_t)i * n + k]) > big) { big = fabs(A[(size_t)i * n + k]); p = i; }
        piv[k] = p;
        if (!(big > 0) || !isfinite(big)) return -1;
        if (p != k)
            for (j = 0; j < n; j++) {
                double t = A[(size_t)k * n + j];
                A[(size_t)k * n + j] = A[(size_t)p * n + j];
                A[(size_t)p * n + j] = t;
            }
        akk = A[(size_t)k * n + k];
        for (i = k + 1; i < n; i++) {
            double *ri = A + (size_t)i * n, l = ri[k] / akk;
            const double *rk = A + (size_t)k * n;
            ri[k] = l;
            if (l != 0)
                for (j = k + 1; j < n; j++) ri[j] -= l * rk[j];
        }
    }
    return 0;
}

/* The two triangular solves column by column: once b_j is final it is taken
 * out of every later (forward) or earlier (backward) entry. The updates of
 * different entries do not depend on each other, so they overlap in the
 * processor, where the row-by-row dot products were one chain of dependent
 * subtractions each (the solve was 13 % of the capture twin's time, 8 %
 * after this). The forward sweep subtracts in the dot product's order (j
 * ascending), bit for bit; the backward sweep in the reverse order (j
 * descending), which rounds differently. (Storing the factors by columns,
 * so that these sweeps run along contiguous memory, measured no faster on
 * the two MuJoCo twins.) */
void cd_rosw_lu_solve(const double *A, int n, const int *piv, double *b)
{
    int i, j;
    for (i = 0; i < n; i++)
        if (piv[i] != i) { double t = b[i]; b[i] = b[piv[i]]; b[piv[i]] = t; }
    for (j = 0; j < n - 1; j++) {
        const double *cj = A + j, bj = b[j];
        if (bj != 0)
            for (i = j + 1; i < n; i++) b[i] -= cj[(size_t)i * n] * bj;
    }
    for (j = n - 1; j >= 0; j--) {
        const double *cj = A + j, bj = b[j] / cj[(size_t)j * n];
        b[j] = bj;
        if (bj != 0)
            for (i = 0; i < j; i++) b[i] -= cj[(size_t)i * n] * bj;
    }
}

int cd_rosw_factor_c(const cd_rosw *w, double c, double *W, int *perm)
{
    int na = w->na, i, j;
    if (w->red) { /* S = I - c J_UU - c^2 M2 */
        int nU = w->nU;
        for (i = 0; i < nU; i++)
            for (j = 0; j < nU; j++)
                W[(size_t)i * nU + j] = (i == j ? 1.0 : 0.0) - c * w->J[(size_t)w->iU[i] * na + w->iU[j]] -
                                        c * c * w->M2[(size_t)i * nU + j];
        return nU && cd_rosw_lu_decomp(W, nU, perm) != 0 ? -1 : 0;
    }
    for (i = 0; i < na * na; i++) W[i] = -c * w->J[i];
    for (i = 0; i < na; i++) W[i * na + i] += 1.0;
    return na && cd_rosw_lu_decomp(W, na, perm) != 0 ? -1 : 0;
}

void cd_rosw_solve_c(const cd_rosw *w, double c, const double *W, const int *perm, double *r, double *u,
                     double *rpz)
{
    int nPZ = w->nP + w->nZ, i, k, e;
    if (!w->red) {
        cd_rosw_lu_solve(W, w->na, perm, r);
        return;
    }
    for (k = 0; k < nPZ; k++) rpz[k] = r[pz_at(w, k)];
    for (i = 0; i < w->nU; i++) {
        double acc = 0;
        for (e = w->sp[i]; e < w->sp[i + 1]; e++) acc += w->sv[e] * rpz[w->sc[e]];
        u[i] = r[w->iU[i]] + c * acc;
    }
    if (w->nU) cd_rosw_lu_solve(W, w->nU, perm, u);
    for (k = 0; k < nPZ; k++) {
        const int row = w->nU + k;
        double acc = 0;
        for (e = w->sp[row]; e < w->sp[row + 1]; e++) acc += w->sv[e] * u[w->sc[e]];
        r[pz_at(w, k)] = rpz[k] + c * acc;
    }
    for (i = 0; i < w->nU; i++) r[w->iU[i]] = u[i];
}

static int factor(cd_rosw *w, double h)
{
    int na = w->na, i;
    if (cd_rosw_factor_c(w, h * w->gam, w->W, w->perm) != 0) return GSL_FAILURE;
    if (!w->red)
        for (i = 0; i < na; i++)
            if (!(fabs(w->W[i * na + i]) > 0) || !isfinite(w->W[i * na + i])) return GSL_FAILURE;
    w->lu_ok = 1;
    w->lu_h = h;
    return GSL_SUCCESS;
}

/* r <- (I - h gamma J)^-1 r on the active set (the LU of factor) */
static int solve_active(cd_rosw *w, double *r)
{
    cd_rosw_solve_c(w, w->lu_h * w->gam, w->W, w->perm, r, w->tu, w->g);
    return GSL_SUCCESS;
}

/* The stepper's state. The stages are computed in the transformed unknowns
 * u_i = sum_{j<=i} Gamma_ij k_j (Gamma: the tableau's gamma below the
 * diagonal, gam on it), as rodas.f and PETSc's TSROSW do. Substituting
 * k = Gamma^-1 u in the stage equation above gives, exactly for any J,
 *   (I - h gam J) u_i = h gam (F_i + gsum_i h df/dt) - sum_{j<i} cu_ij u_j,
 *   Y_i = y + sum_{j<i} au_ij u_j,   y1 = y + sum_i mu_i u_i,   error = sum_i eu_i u_i,
 * with au = alpha Gamma^-1, cu_ij = gam (Gamma^-1)_ij, mu = b Gamma^-1,
 * eu = (b - bhat) Gamma^-1 (transform(), from the tableau when bound). So a
 * stage needs no product of J with a vector: the right-hand side of each solve
 * is formed from the stage vectors alone, one pass over y. */
typedef struct {
    cd_rosw *w;
    const rosw_tab *tab;
    int locator;
    int have_prev, nretry;
    double t_prev;
    double au[CD_ROSW_SMAX][CD_ROSW_SMAX], cu[CD_ROSW_SMAX][CD_ROSW_SMAX], ai[CD_ROSW_SMAX];
    double mu[CD_ROSW_SMAX], eu[CD_ROSW_SMAX];
} rosw_state;

/* au, cu, mu, eu and the nodes ai of the bound tableau (see rosw_state) */
static void transform(rosw_state *st)
{
    const rosw_tab *T = st->tab;
    double Gi[CD_ROSW_SMAX][CD_ROSW_SMAX] = {{0}};
    int i, j, k, s = T->s;
    /* Gamma^-1 by forward substitution: Gamma is lower triangular, gam on the diagonal */
    for (j = 0; j < s; j++) {
        Gi[j][j] = 1.0 / T->gam;
        for (i = j + 1; i < s; i++) {
            double acc = 0;
            for (k = j; k < i; k++) acc += T->gamma[i][k] * Gi[k][j];
            Gi[i][j] = -acc / T->gam;
        }
    }
    for (i = 0; i < s; i++) {
        st->ai[i] = 0;
        st->mu[i] = st->eu[i] = 0;
        for (j = 0; j < s; j++) {
            st->au[i][j] = st->cu[i][j] = 0;
            if (j < i) {
                st->ai[i] += T->alpha[i][j];
                st->cu[i][j] = T->gam * Gi[i][j];
                for (k = j; k < i; k++) st->au[i][j] += T->alpha[i][k] * Gi[k][j];
            }
        }
        for (k = i; k < s; k++) {
            st->mu[i] += T->b[k] * Gi[k][i];
            st->eu[i] += (T->b[k] - T->bhat[k]) * Gi[k][i];
        }
    }
}

static void *rosw_alloc(size_t dim)
{
    rosw_state *s = (rosw_state *)calloc(1, sizeof *s);
    (void)dim;
    if (!s) GSL_ERROR_NULL("failed to allocate the Rosenbrock stepper state", GSL_ENOMEM);
    return s;
}

static int rosw_apply(void *vs, size_t dim, double t, double h, double y[], double yerr[], const double dydt_in[],
                      double dydt_out[], const gsl_odeiv2_system *sys)
{
    rosw_state *s = (rosw_state *)vs;
    cd_rosw *w = s->w;
    const rosw_tab *T = s->tab;
    int n = (int)dim, i, j, a, c, r, na;
    const double *f0;
    if (!w || n != w->ny) return GSL_EINVAL;
    if (dydt_in) {
        f0 = dydt_in;
    } else {
        if (GSL_ODEIV_FN_EVAL(sys, t, y, w->fs) != GSL_SUCCESS) return GSL_EBADFUNC;
        f0 = w->fs;
    }
    if (T->exact) {
        /* a Rosenbrock (not W) method: the Jacobian of this step's start,
         * renewed at every new start (a retry or a locator step from the
         * same start shares it: same t, and the state there is the same
         * until an event, which invalidates) */
        if (!w->jac_ok || w->jac_t != t)
            if (jacobian(w, t, y, f0, sys, !CD_RODAS4_STRUCTURED_JAC) != GSL_SUCCESS) return GSL_EBADFUNC;
    } else if (!s->locator) {
        /* the CD_ROSW_RENEW_ON_RETRY-th retry at the same start (the steps
         * before were rejected) renews a Jacobian formed earlier */
        int retry = s->have_prev && s->t_prev == t;
        s->nretry = retry ? s->nretry + 1 : 0;
        if (!w->jac_ok || w->jac_age >= CD_ROSW_JAC_AGE ||
            (CD_ROSW_RENEW_ON_RETRY && s->nretry >= CD_ROSW_RENEW_ON_RETRY && w->jac_t != t))
            if (jacobian(w, t, y, f0, sys, 0) != GSL_SUCCESS) return GSL_EBADFUNC;
        s->have_prev = 1;
        s->t_prev = t;
    } else if (!w->jac_ok) {
        if (jacobian(w, t, y, f0, sys, 0) != GSL_SUCCESS) return GSL_EBADFUNC;
    }
    na = w->na;
    if (!w->lu_ok || w->lu_h != h || w->gam != T->gam) {
        w->gam = T->gam;
        if (factor(w, h) != GSL_SUCCESS) return GSL_FAILURE;
    }
    /* the stage algebra runs over the unknowns that can move; the others keep
     * y in every stage argument and in the solution, with error 0 */
    w->nrun = cd_moving_runs(w->m, w->d, w->ny, w->rlo, w->rhi);
    memcpy(w->ytmp, y, (size_t)n * sizeof(double));
    for (i = 0; i < T->s; i++) {
        double *u = w->k[i], hg = h * T->gam;
        const double *F;
        if (i == 0) {
            F = f0;
        } else {
            for (r = 0; r < w->nrun; r++)
                for (c = w->rlo[r]; c < w->rhi[r]; c++) {
                    double acc = y[c];
                    for (j = 0; j < i; j++) acc += s->au[i][j] * w->k[j][c];
                    w->ytmp[c] = acc;
                }
            if (GSL_ODEIV_FN_EVAL(sys, t + s->ai[i] * h, w->ytmp, w->fs) != GSL_SUCCESS) return GSL_EBADFUNC;
            F = w->fs;
        }
        /* the right-hand side h gam F_i (+ df/dt) - sum_j cu_ij u_j, then the solve on the active set
         * (the other unknowns have no Jacobian rows: theirs is the right-hand side itself) */
        for (r = 0; r < w->nrun; r++)
            for (c = w->rlo[r]; c < w->rhi[r]; c++) {
                double acc = hg * F[c];
                if (T->exact && T->gsum[i] != 0) acc += hg * T->gsum[i] * h * w->ft[c];
                for (j = 0; j < i; j++) acc -= s->cu[i][j] * w->k[j][c];
                u[c] = acc;
            }
        if (na) {
            for (a = 0; a < na; a++) w->r[a] = u[w->act[a]];
            if (solve_active(w, w->r) != GSL_SUCCESS) return GSL_FAILURE;
            for (a = 0; a < na; a++) u[w->act[a]] = w->r[a];
        }
        for (r = 0; r < w->nrun; r++)
            for (c = w->rlo[r]; c < w->rhi[r]; c++)
                if (!isfinite(u[c])) return GSL_FAILURE;
    }
    memset(yerr, 0, (size_t)n * sizeof(double));
    for (r = 0; r < w->nrun; r++)
        for (c = w->rlo[r]; c < w->rhi[r]; c++) {
            double dy = 0, e = 0;
            for (i = 0; i < T->s; i++) {
                dy += s->mu[i] * w->k[i][c];
                e += s->eu[i] * w->k[i][c];
            }
            y[c] += dy;
            yerr[c] = e;
        }
    if (na && T->filter) { /* the error estimate filtered by (I - h gamma J)^-1: stiff components, which
                            * the L-stable solution damps but the embedded one does not, do not count */
        for (a = 0; a < na; a++) w->r[a] = yerr[w->act[a]];
        if (solve_active(w, w->r) != GSL_SUCCESS) return GSL_FAILURE;
        for (a = 0; a < na; a++) yerr[w->act[a]] = w->r[a];
    }
    if (dydt_out && GSL_ODEIV_FN_EVAL(sys, t + h, y, dydt_out) != GSL_SUCCESS) return GSL_EBADFUNC;
    if (!s->locator) w->jac_age++;
    return GSL_SUCCESS;
}

double cd_rosw_spectral_radius(cd_rosw *w, double t, const double *y)
{
    int na, i, k;
    double *v = w->r, *u = w->g, logsum = 0;
    const int own = w->jac_ok; /* the stepper's J: its estimate is kept until J is formed again */
    if (own && w->rho_ok) return w->rho; /* the same J, the same iterations: the same value */
    w->rho_ok = 0;
    if (!own) {
        active_set(w);
        if (cd_jac_model(w->m, w->d, t, y, w->act, w->na, w->J, &w->jw) != CD_OK) return -1.0;
        w->jac_ok = 0; /* formed for the estimate only: the stepper forms its own at its step */
    }
    na = w->na;
    if (na == 0) return 0.0;
    /* each row's nonzeros lie in [jlo, jhi): the rows of the positions and
     * anchors hold a few velocities' columns (reduce()), so the products
     * below skip most of J. Bit for bit the dense sums: a skipped term is a
     * zero times a finite v (a non-finite one ends the iteration), and the
     * sum it is left out of is never -0 */
    for (i = 0; i < na; i++) {
        const double *Ji = w->J + (size_t)i * (size_t)na;
        int a = 0, b = na;
        while (a < na && Ji[a] == 0) a++;
        while (b > a && Ji[b - 1] == 0) b--;
        w->jlo[i] = a;
        w->jhi[i] = b;
    }
    /* power iteration: rho ~ (|J^20 v| / |J^10 v|)^(1/10), which also
     * converges for a complex pair and damps the transient of a non-normal J */
    for (i = 0; i < na; i++) v[i] = 1.0 / (double)(1 + i % 7);
    for (k = 0; k < 20; k++) {
        double nu = 0, nv = 0;
        for (i = 0; i < na; i++) nv += v[i] * v[i];
        nv = sqrt(nv);
        for (i = 0; i < na; i++) {
            const double *Ji = w->J + (size_t)i * (size_t)na;
            double acc = 0;
            int c, c1 = w->jhi[i];
            for (c = w->jlo[i]; c < c1; c++) acc += Ji[c] * v[c];
            u[i] = acc / nv;
        }
        for (i = 0; i < na; i++) nu += u[i] * u[i];
        nu = sqrt(nu);
        if (!(nu > 0) || !isfinite(nu)) return nu == 0 ? 0.0 : -1.0;
        if (k >= 10) logsum += log(nu);
        memcpy(v, u, (size_t)na * sizeof(double));
    }
    w->rho = exp(logsum / 10.0);
    w->rho_ok = own;
    return w->rho;
}

static int rosw_set_driver(void *vs, const gsl_odeiv2_driver *d)
{
    (void)vs;
    (void)d;
    return GSL_SUCCESS;
}

static int rosw_reset(void *vs, size_t dim)
{
    rosw_state *s = (rosw_state *)vs;
    (void)dim;
    s->have_prev = 0;
    if (s->w && !s->locator) cd_rosw_invalidate(s->w);
    return GSL_SUCCESS;
}

static unsigned int rosw_order(void *vs)
{
    (void)vs;
    return (unsigned int)TAB_ROS34PW2.order;
}

static unsigned int rodas4_order(void *vs)
{
    (void)vs;
    return (unsigned int)TAB_RODAS4.order;
}

int cd_rosw_tableau_sums(const gsl_odeiv2_step_type *T, double *c, double *gsum)
{
    const rosw_tab *tab = T == cd_step_rodas4 ? &TAB_RODAS4 : &TAB_ROS34PW2;
    int i, j;
    for (i = 0; i < tab->s; i++) {
        c[i] = 0;
        gsum[i] = tab->gam;
        for (j = 0; j < i; j++) {
            c[i] += tab->alpha[i][j];
            gsum[i] += tab->gamma[i][j];
        }
    }
    return tab->s;
}

static void rosw_free(void *vs) { free(vs); }

static const gsl_odeiv2_step_type rosw_type = {"ros34pw2", 1, 1, rosw_alloc, rosw_apply, rosw_set_driver,
                                               rosw_reset, rosw_order, rosw_free};
const gsl_odeiv2_step_type *cd_step_ros34pw2 = &rosw_type;
static const gsl_odeiv2_step_type rodas4_type = {"rodas4", 1, 1, rosw_alloc, rosw_apply, rosw_set_driver,
                                                 rosw_reset, rodas4_order, rosw_free};
const gsl_odeiv2_step_type *cd_step_rodas4 = &rodas4_type;

void cd_rosw_bind(gsl_odeiv2_step *s, cd_rosw *w, int locator)
{
    rosw_state *st = (rosw_state *)s->state;
    st->w = w;
    st->tab = s->type == cd_step_rodas4 ? &TAB_RODAS4 : &TAB_ROS34PW2;
    w->gam = st->tab->gam;
    w->lu_ok = 0;
    transform(st);
    st->locator = locator;
    st->have_prev = 0;
}
