/* Kinematics, recursive Newton-Euler, composite-rigid-body mass matrix and
 * forward dynamics of free-floating or fixed-base trees.
 *
 * Algorithm choice: the composite-rigid-body algorithm (CRBA) builds H in
 * O(n^2), a Cholesky factorisation solves it in O(n^3/6) (cd_math.h says why
 * not GSL's: it aborts through GSL's error handler on a singular H); the bias h comes from one RNE
 * pass. cd_forward_dynamics uses the articulated-body algorithm (aba.c) from
 * CD_ABA_MIN_DOF on, measured faster at every size (aba.h); CRBA stays for H. All
 * spatial quantities are Plucker vectors in world axes about one reference
 * point per system, the current base position (SpaceDyn's R0), which keeps
 * moment arms small and needs no coordinate transforms between bodies. */
#include "capdyn/sim.h"
#include "../math/cd_math.h"
#include "../kinematics/prescribed.h"
#include "aba.h"
#include "mass.h"
#include "capdyn/dynamics.h"

#include <string.h>

/* spatial inertia of every body of system s about its reference point */
void cd_inverse_dynamics(const cd_model *m, cd_data *d, int s, const double *udot, double *tau)
{
    if (!m || !d || !tau) return;
    int b0 = m->sys_body_adr[s], nb = m->sys_nbody[s], b, i;
    int free_base = m->sys_base_type[s] == CD_BASE_FREE, j0 = free_base ? 6 : 0;
    cd_rbi *I = (cd_rbi *)d->body_rbi;
    double *A = d->work, *F = d->work + 6 * m->nbody; /* (nbody x 6) each */
    double *A0 = A + 6 * b0, t[6], IV[6];
    /* base acceleration, gravity as a fictitious upward acceleration */
    if (free_base) {
        double *v0 = d->body_v + 3 * b0, *w0 = d->body_w + 3 * b0;
        cd_v3_copy(A0, udot + 3);
        cd_v3_cross(t, w0, v0);
        cd_v3_sub(A0 + 3, udot, t);
    } else {
        memset(A0, 0, 6 * sizeof(double));
    }
    cd_v3_sub(A0 + 3, A0 + 3, m->gravity);
    for (b = b0 + 1; b < b0 + nb; b++) {
        int p = m->body_parent[b], k = b - b0 - 1;
        double *S = d->body_S + 6 * b, qd = cd_joint_qd(m, d, b), Sqd[6];
        for (i = 0; i < 6; i++) Sqd[i] = S[i] * qd;
        cd_sv_crossm(t, d->body_V + 6 * b, Sqd);
        for (i = 0; i < 6; i++) A[6 * b + i] = A[6 * p + i] + S[i] * udot[j0 + k] + t[i];
    }
    /* F_b = I A + V x* I V - f_ext */
    for (b = b0; b < b0 + nb; b++) {
        cd_rbi_mulv(F + 6 * b, &I[b], A + 6 * b);
        cd_rbi_mulv(IV, &I[b], d->body_V + 6 * b);
        cd_sv_crossf(t, d->body_V + 6 * b, IV);
        for (i = 0; i < 6; i++) F[6 * b + i] += t[i] - d->body_fext[6 * b + i];
    }
    for (b = b0 + nb - 1; b > b0; b--) {
        int p = m->body_parent[b];
        tau[j0 + b - b0 - 1] = cd_sv_dot(d->body_S + 6 * b, F + 6 * b);
        for (i = 0; i < 6; i++) F[6 * p + i] += F[6 * b + i];
    }
    if (free_base) {
        cd_v3_copy(tau, F + 6 * b0 + 3); /* force */
        cd_v3_copy(tau + 3, F + 6 * b0); /* moment about the base CoM */
    }
}

/* H of system s by CRBA (composite inertias Ic in world axes about the
 * system's reference point). With cols, only the entries of the joints
 * cols[0..ncols) on the diagonal and in the base rows and columns, and the
 * base block, each by the same operations as the whole H (mass.h); with
 * cols NULL, the whole H. */
void cd_mass_matrix_cols(const cd_model *m, cd_data *d, int s, double *H, const int *cols, int ncols)
{
    int b0 = m->sys_body_adr[s], nb = m->sys_nbody[s], n = m->sys_ndof[s], b, c, i, k;
    int free_base = m->sys_base_type[s] == CD_BASE_FREE, j0 = free_base ? 6 : 0;
    cd_rbi *I = (cd_rbi *)d->body_rbi, *Ic = (cd_rbi *)d->body_rbi + m->nbody;
    for (b = b0; b < b0 + nb; b++) Ic[b] = I[b];
    for (b = b0 + nb - 1; b > b0; b--) cd_rbi_add(&Ic[m->body_parent[b]], &Ic[b]);
    if (!cols) memset(H, 0, (size_t)n * (size_t)n * sizeof(double));
    for (c = 0; c < (cols ? ncols : nb - 1); c++) {
        int ib, a;
        double F[6];
        b = b0 + 1 + (cols ? cols[c] : c);
        ib = j0 + b - b0 - 1;
        cd_rbi_mulv(F, &Ic[b], d->body_S + 6 * b);
        H[ib * n + ib] = cd_sv_dot(d->body_S + 6 * b, F);
        if (!cols)
            for (a = m->body_parent[b]; a > b0; a = m->body_parent[a]) {
                int ia = j0 + a - b0 - 1;
                H[ia * n + ib] = H[ib * n + ia] = cd_sv_dot(d->body_S + 6 * a, F);
            }
        if (free_base)
            for (k = 0; k < 3; k++) {
                H[k * n + ib] = H[ib * n + k] = F[3 + k];           /* v0 rows: force */
                H[(3 + k) * n + ib] = H[ib * n + 3 + k] = F[k];     /* w0 rows: moment */
            }
    }
    if (free_base) {
        const cd_rbi *C = &Ic[b0];
        for (k = 0; k < 3; k++) {
            double e[3] = {0, 0, 0}, hx[3];
            e[k] = 1.0;
            cd_v3_cross(hx, C->h, e);
            for (i = 0; i < 3; i++) {
                H[i * n + k] = (i == k) ? C->m : 0.0;      /* v-v: m 1 */
                H[(3 + i) * n + k] = hx[i];                /* w-v: h x e_k */
                H[i * n + 3 + k] = -hx[i];                 /* v-w: -h x e_k */
                H[(3 + i) * n + 3 + k] = C->I[3 * i + k];  /* w-w: Io */
            }
        }
    }
}

void cd_mass_matrix(const cd_model *m, cd_data *d, int s, double *H)
{
    if (!m || !d || !H) return;
    cd_mass_matrix_cols(m, d, s, H, NULL, 0);
}

/* prescribed accelerations of system s into a (ndof); returns how many DoFs are prescribed */
static int prescribed_acc(const cd_model *m, const cd_data *d, int s, double *a, int *is_p)
{
    int b0 = m->sys_body_adr[s], j0 = m->sys_base_type[s] == CD_BASE_FREE ? 6 : 0, b, i, np = 0;
    for (i = 0; i < m->sys_ndof[s]; i++) { a[i] = 0; is_p[i] = 0; }
    if (j0 && m->body_presc[b0] != CD_PRESCRIBE_NONE) /* constant base velocities: zero acceleration */
        for (i = 0; i < 6; i++) { is_p[i] = 1; np++; }
    for (b = b0 + 1; b < b0 + m->sys_nbody[s]; b++)
        if (m->body_presc[b] != CD_PRESCRIBE_NONE) {
            double q, qd;
            int k = j0 + b - b0 - 1;
            cd_prescribed_joint(m, b, d->t, &q, &qd, &a[k]);
            is_p[k] = 1;
            np++;
        }
    return np;
}

cd_status cd_forward_dynamics(const cd_model *m, cd_data *d)
{
    if (!m || !d) return CD_EINVAL;
    return cd_forward_dynamics_method(m, d, CD_FD_AUTO);
}

/* ABA (aba.c) from CD_ABA_MIN_DOF on, measured crossover (docs/performance.md) */
cd_status cd_forward_dynamics_method(const cd_model *m, cd_data *d, cd_fd_method method)
{
    int s, i, j;
    for (s = 0; s < m->nsys; s++) {
        int n = m->sys_ndof[s], va = m->sys_v_adr[s], np = 0, nf;
        double *rhs = d->work + 12 * m->nbody, *zero = rhs + n, *acc = zero + n, *idf = acc + n;
        int *is_p = (int *)(void *)(d->jwork); /* (n) flags, jwork is 12 maxdof + 36 doubles */
        if (n == 0) continue;
        /* prescribed DoFs take the partitioned CRBA path below */
        if (m->npresc) np = prescribed_acc(m, d, s, acc, is_p);
        if (np == 0 && (method == CD_FD_ABA || (method == CD_FD_AUTO && n >= CD_ABA_MIN_DOF))) {
            if (cd_aba_forward(m, d, s) != CD_OK) return CD_ENUMERIC;
            continue;
        }
        for (i = 0; i < n; i++) zero[i] = 0.0;
        cd_inverse_dynamics(m, d, s, zero, rhs); /* rhs = h - J^T F (bias) */
        for (i = 0; i < n; i++) rhs[i] = d->tau[va + i] - rhs[i];
        cd_mass_matrix(m, d, s, d->H);
        if (np == 0) {
            if (cd_chol_decomp(d->H, n) != 0) return CD_ENUMERIC;
            cd_chol_solve(d->H, n, rhs);
            for (i = 0; i < n; i++) d->udot[va + i] = rhs[i];
            continue;
        }
        /* partitioned: H_FF a_F = rhs_F - H_FP a_P, then the generalized force the
         * prescribed DoFs take is ID(a)_P - tau_P (one more RNE pass) */
        nf = 0;
        for (i = 0; i < n; i++) {
            double r = rhs[i];
            if (is_p[i]) continue;
            for (j = 0; j < n; j++)
                if (is_p[j]) r -= d->H[i * n + j] * acc[j];
            zero[nf++] = r;
        }
        if (nf > 0) {
            int ii = 0, jj;
            for (i = 0; i < n; i++) {
                if (is_p[i]) continue;
                jj = 0;
                for (j = 0; j < n; j++)
                    if (!is_p[j]) d->H[ii * nf + jj++] = d->H[i * n + j]; /* compaction in place: never overtakes */
                ii++;
            }
            if (cd_chol_decomp(d->H, nf) != 0) return CD_ENUMERIC;
            cd_chol_solve(d->H, nf, zero);
            for (i = 0, ii = 0; i < n; i++)
                if (!is_p[i]) acc[i] = zero[ii++];
        }
        for (i = 0; i < n; i++) d->udot[va + i] = acc[i];
        cd_inverse_dynamics(m, d, s, acc, idf);
        for (i = 0; i < n; i++) d->qfrc_constraint[va + i] = is_p[i] ? idf[i] - d->tau[va + i] : 0.0;
    }
    return CD_OK;
}

void cd_momentum(const cd_model *m, const cd_data *d, int s, double *ke, double P[3],
                 double Lc[3], double Lo[3], double com[3])
{
    if (!m || !d) return;
    int b0 = m->sys_body_adr[s], b;
    double e = 0, p[3] = {0, 0, 0}, L[3] = {0, 0, 0}, c[3] = {0, 0, 0}, M = 0;
    for (b = b0; b < b0 + m->sys_nbody[s]; b++) {
        double mb = m->body_mass[b], Iw[9], Iw_w[3], mv[3], t[3];
        const double *w = d->body_w + 3 * b, *v = d->body_v + 3 * b, *cb = d->body_c + 3 * b;
        cd_m3_rotsym(Iw, d->body_R + 9 * b, m->body_inertia + 9 * b);
        cd_m3_mulv(Iw_w, Iw, w);
        e += 0.5 * (mb * cd_v3_dot(v, v) + cd_v3_dot(w, Iw_w));
        cd_v3_scale(mv, v, mb);
        cd_v3_add(p, p, mv);
        cd_v3_cross(t, cb, mv);
        cd_v3_add(L, L, t);
        cd_v3_add(L, L, Iw_w);
        cd_v3_axpy(c, mb, cb);
        M += mb;
    }
    cd_v3_scale(c, c, 1.0 / M);
    if (ke) *ke = e;
    if (P) cd_v3_copy(P, p);
    if (Lo) cd_v3_copy(Lo, L);
    if (Lc) {
        double t[3];
        cd_v3_cross(t, c, p);
        cd_v3_sub(Lc, L, t);
    }
    if (com) cd_v3_copy(com, c);
}

double cd_potential_energy(const cd_model *m, const cd_data *d, int s)
{
    if (!m || !d) return NAN;
    int b0 = m->sys_body_adr[s], b;
    double u = 0;
    for (b = b0; b < b0 + m->sys_nbody[s]; b++)
        u -= m->body_mass[b] * cd_v3_dot(m->gravity, d->body_c + 3 * b);
    return u;
}
