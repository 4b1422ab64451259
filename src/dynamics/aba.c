/* Forward dynamics by the articulated-body algorithm (Featherstone, Rigid
 * Body Dynamics Algorithms, 2008, sec. 7.3; floating base sec. 9.3).
 *
 * Same conventions as dynamics.c: every spatial vector is in world axes about
 * the system's reference point P (the base position), so the transform
 * between a body and its parent is the identity and the algorithm needs no
 * coordinate changes -- only the joint subspaces S_b (d->body_S) and the body
 * velocities V_b (d->body_V) from cd_kinematics. Gravity enters as a
 * fictitious acceleration -g of the base (as in cd_inverse_dynamics): every
 * acceleration below is the true one minus [0; g].
 *
 * Why both paths: ABA costs ~n 6x6 rank-one updates (O(n)); CRBA + Cholesky
 * builds H in O(n d) (d: depth) and factors it in O(n^3 / 6) but with much
 * smaller constants, so it wins for small trees. The switch point,
 * CD_ABA_MIN_DOF, is measured (bench/bench_speed.c, docs/performance.md). */
#include "aba.h"
#include "../math/cd_math.h"

#include <string.h>

/* per-body scratch, CD_ABA_WORK_PER_BODY doubles */
enum { W_IA = 0, W_PA = 36, W_C = 42, W_U = 48, W_A = 54, W_D = 60, W_UU = 61 };

/* 6x6 symmetric spatial inertia of a rigid body about P: [[Io, h x], [-h x, m 1]] */
static void rbi_to_mat(double M[36], const cd_rbi *r)
{
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            M[6 * i + j] = r->I[3 * i + j];
            M[6 * (3 + i) + 3 + j] = (i == j) ? r->m : 0.0;
        }
    /* top-right block: skew(h); bottom-left: skew(h)^T = -skew(h) */
    M[0 * 6 + 3] = 0.0;     M[0 * 6 + 4] = -r->h[2]; M[0 * 6 + 5] = r->h[1];
    M[1 * 6 + 3] = r->h[2]; M[1 * 6 + 4] = 0.0;      M[1 * 6 + 5] = -r->h[0];
    M[2 * 6 + 3] = -r->h[1]; M[2 * 6 + 4] = r->h[0]; M[2 * 6 + 5] = 0.0;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) M[6 * (3 + j) + i] = M[6 * i + 3 + j];
}

static void mat6_mulv(double r[6], const double M[36], const double v[6])
{
    int i;
    for (i = 0; i < 6; i++)
        r[i] = M[6 * i] * v[0] + M[6 * i + 1] * v[1] + M[6 * i + 2] * v[2] + M[6 * i + 3] * v[3] +
               M[6 * i + 4] * v[4] + M[6 * i + 5] * v[5];
}

cd_status cd_aba_forward(const cd_model *m, cd_data *d, int s)
{
    int b0 = m->sys_body_adr[s], nb = m->sys_nbody[s], b, i, j;
    int free_base = m->sys_base_type[s] == CD_BASE_FREE, j0 = free_base ? 6 : 0;
    int va = m->sys_v_adr[s];
    const double *tau = d->tau + va;
    double *udot = d->udot + va, *W = d->work;
    cd_sys_state st = cd_state_of(m, d, s);

    /* pass 1 (any order): rigid-body inertias I_b (from cd_kinematics), bias forces
     * p_b = V_b x* I_b V_b - f_ext_b, velocity-product accelerations
     * c_b = V_b x (S_b qd_b) */
    for (b = b0; b < b0 + nb; b++) {
        double *w = W + CD_ABA_WORK_PER_BODY * b, IV[6];
        const double *V = d->body_V + 6 * b;
        const cd_rbi *I = (const cd_rbi *)d->body_rbi + b; /* cd_kinematics' */
        rbi_to_mat(w + W_IA, I);
        cd_rbi_mulv(IV, I, V);
        cd_sv_crossf(w + W_PA, V, IV);
        for (i = 0; i < 6; i++) w[W_PA + i] -= d->body_fext[6 * b + i];
        if (b > b0) {
            double Sqd[6], qd = st.qd[b - b0 - 1];
            for (i = 0; i < 6; i++) Sqd[i] = d->body_S[6 * b + i] * qd;
            cd_sv_crossm(w + W_C, V, Sqd);
        }
    }

    /* pass 2, leaves to root: articulated inertias and bias forces
     *   U = IA S, D = S.U, u = tau - S.pA
     *   IA_parent += IA - U U^T / D,  pA_parent += pA + Ia c + U u / D */
    for (b = b0 + nb - 1; b > b0; b--) {
        double *w = W + CD_ABA_WORK_PER_BODY * b, *wp = W + CD_ABA_WORK_PER_BODY * m->body_parent[b];
        const double *S = d->body_S + 6 * b;
        double *IA = w + W_IA, *U = w + W_U, Dinv, uu, Iac[6], pa[6];
        mat6_mulv(U, IA, S);
        w[W_D] = cd_sv_dot(S, U);
        if (!(w[W_D] > 0.0)) return CD_ENUMERIC;
        Dinv = 1.0 / w[W_D];
        uu = tau[j0 + b - b0 - 1] - cd_sv_dot(S, w + W_PA);
        w[W_UU] = uu;
        for (i = 0; i < 6; i++)
            for (j = 0; j < 6; j++) IA[6 * i + j] -= U[i] * U[j] * Dinv;
        mat6_mulv(Iac, IA, w + W_C);
        for (i = 0; i < 6; i++) pa[i] = w[W_PA + i] + Iac[i] + U[i] * uu * Dinv;
        for (i = 0; i < 36; i++) wp[W_IA + i] += IA[i];
        for (i = 0; i < 6; i++) wp[W_PA + i] += pa[i];
    }

    /* base: a fixed base moves with -g; a free base solves
     * IA_0 a_0 + pA_0 = f_0 with f_0 = [moment about P; force] from tau */
    {
        double *w = W + CD_ABA_WORK_PER_BODY * b0, *a = w + W_A;
        if (free_base) {
            double L[36];
            memcpy(L, w + W_IA, sizeof L);
            for (i = 0; i < 3; i++) {
                a[i] = tau[3 + i] - w[W_PA + i];
                a[3 + i] = tau[i] - w[W_PA + 3 + i];
            }
            if (cd_chol_decomp(L, 6) != 0) return CD_ENUMERIC;
            cd_chol_solve(L, 6, a);
        } else {
            for (i = 0; i < 3; i++) { a[i] = 0.0; a[3 + i] = -m->gravity[i]; }
        }
    }

    /* pass 3, root to leaves: a_b = a_parent + c_b, qdd = (u - U.a_b) / D,
     * a_b += S qdd */
    for (b = b0 + 1; b < b0 + nb; b++) {
        double *w = W + CD_ABA_WORK_PER_BODY * b, *a = w + W_A;
        const double *ap = W + CD_ABA_WORK_PER_BODY * m->body_parent[b] + W_A, *S = d->body_S + 6 * b;
        double qdd;
        for (i = 0; i < 6; i++) a[i] = ap[i] + w[W_C + i];
        qdd = (w[W_UU] - cd_sv_dot(w + W_U, a)) / w[W_D];
        for (i = 0; i < 6; i++) a[i] += S[i] * qdd;
        udot[j0 + b - b0 - 1] = qdd;
    }

    /* the free base's generalized accelerations from its spatial one (true
     * acceleration a_0 + [0; g]): wdot0 = a_ang, vdot0 = a_lin + w0 x v0 */
    if (free_base) {
        const double *a = W + CD_ABA_WORK_PER_BODY * b0 + W_A;
        double t[3];
        cd_v3_cross(t, d->body_w + 3 * b0, d->body_v + 3 * b0);
        for (i = 0; i < 3; i++) {
            udot[i] = a[3 + i] + m->gravity[i] + t[i];
            udot[3 + i] = a[i];
        }
    }
    return CD_OK;
}

int cd_fd_aba_min_dof(void) { return CD_ABA_MIN_DOF; }
