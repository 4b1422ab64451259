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
#include "aba.h"
#include "capdyn/dynamics.h"

#include <string.h>

/* offsets of a system's parts inside y */
static void sys_layout(const cd_model *m, int s, int *pos, int *q, int *vel, int *qd)
{
    int a = m->sys_y_adr[s], nj = m->sys_nbody[s] - 1;
    if (m->sys_base_type[s] == CD_BASE_FREE) {
        *pos = a; *q = a + 7; *vel = a + 7 + nj; *qd = a + 7 + nj + 6;
    } else {
        *pos = -1; *q = a; *vel = -1; *qd = a + nj;
    }
}

cd_sys_state cd_state_of(const cd_model *m, const cd_data *d, int s)
{
    cd_sys_state r;
    int pos, q, vel, qd;
    sys_layout(m, s, &pos, &q, &vel, &qd);
    r.njoint = m->sys_nbody[s] - 1;
    r.pos = pos >= 0 ? d->y + pos : NULL;
    r.quat = pos >= 0 ? d->y + pos + 3 : NULL;
    r.vel = vel >= 0 ? d->y + vel : NULL;
    r.angvel = vel >= 0 ? d->y + vel + 3 : NULL;
    r.q = d->y + q;
    r.qd = d->y + qd;
    return r;
}

double cd_joint_q(const cd_model *m, const cd_data *d, int b)
{
    int s = m->body_sys[b];
    if (m->body_parent[b] < 0) return 0.0;
    return cd_state_of(m, d, s).q[b - m->sys_body_adr[s] - 1];
}

double cd_joint_qd(const cd_model *m, const cd_data *d, int b)
{
    int s = m->body_sys[b];
    if (m->body_parent[b] < 0) return 0.0;
    return cd_state_of(m, d, s).qd[b - m->sys_body_adr[s] - 1];
}

void cd_kinematics(const cd_model *m, cd_data *d)
{
    int s, b;
    for (s = 0; s < m->nsys; s++) {
        cd_sys_state st = cd_state_of(m, d, s);
        int b0 = m->sys_body_adr[s], nb = m->sys_nbody[s];
        double *P = d->sys_ref + 3 * s, *V;
        /* base */
        if (st.pos) {
            cd_v3_copy(P, st.pos);
            cd_quat_to_m3(d->body_R + 9 * b0, st.quat);
            cd_v3_copy(d->body_w + 3 * b0, st.angvel);
            cd_v3_copy(d->body_v + 3 * b0, st.vel);
        } else {
            cd_v3_copy(P, m->sys_pos0 + 3 * s);
            cd_quat_to_m3(d->body_R + 9 * b0, m->sys_quat0 + 4 * s);
            cd_v3_zero(d->body_w + 3 * b0);
            cd_v3_zero(d->body_v + 3 * b0);
        }
        cd_v3_copy(d->body_x + 3 * b0, P);
        cd_v3_copy(d->body_c + 3 * b0, P);
        cd_v3_zero(d->body_axisw + 3 * b0);
        memset(d->body_S + 6 * b0, 0, 6 * sizeof(double));
        V = d->body_V + 6 * b0;
        cd_v3_copy(V, d->body_w + 3 * b0);
        cd_v3_copy(V + 3, d->body_v + 3 * b0);
        /* links, parents first */
        for (b = b0 + 1; b < b0 + nb; b++) {
            int p = m->body_parent[b];
            double q = st.q[b - b0 - 1], qd = st.qd[b - b0 - 1];
            double Rfix[9], Rq[9], t[3], r[3];
            double *R = d->body_R + 9 * b, *x = d->body_x + 3 * b, *z = d->body_axisw + 3 * b;
            double *S = d->body_S + 6 * b, *Vb = d->body_V + 6 * b, *Vp = d->body_V + 6 * p;
            int i;
            cd_m3_mulv(t, d->body_R + 9 * p, m->body_jnt_pos + 3 * b);
            cd_v3_add(x, d->body_x + 3 * p, t);
            cd_m3_mul(Rfix, d->body_R + 9 * p, m->body_jnt_rot + 9 * b);
            cd_m3_mulv(z, Rfix, m->body_axis + 3 * b);
            if (m->body_jnt_type[b] == CD_JOINT_REVOLUTE) {
                cd_m3_axis_angle(Rq, m->body_axis + 3 * b, q);
                cd_m3_mul(R, Rfix, Rq);
                /* S = [z; (x - P) x z] */
                cd_v3_copy(S, z);
                cd_v3_sub(r, x, P);
                cd_v3_cross(S + 3, r, z);
            } else {
                cd_m3_copy(R, Rfix);
                cd_v3_axpy(x, q, z);
                cd_v3_zero(S);
                cd_v3_copy(S + 3, z);
            }
            for (i = 0; i < 6; i++) Vb[i] = Vp[i] + S[i] * qd;
            cd_m3_mulv(t, R, m->body_com + 3 * b);
            cd_v3_add(d->body_c + 3 * b, x, t);
            cd_v3_copy(d->body_w + 3 * b, Vb);
            /* CoM velocity: v_P + w x (c - P) */
            cd_v3_sub(r, d->body_c + 3 * b, P);
            cd_v3_cross(t, Vb, r);
            cd_v3_add(d->body_v + 3 * b, Vb + 3, t);
        }
    }
}

void cd_point_world(const cd_model *m, const cd_data *d, int b, const double pb[3],
                    double pw[3], double vw[3])
{
    double t[3], p[3];
    (void)m;
    cd_m3_mulv(t, d->body_R + 9 * b, pb);
    cd_v3_add(p, d->body_x + 3 * b, t);
    if (vw) {
        /* v = v_c + w x (p - c) */
        cd_v3_sub(t, p, d->body_c + 3 * b);
        cd_v3_cross(vw, d->body_w + 3 * b, t);
        cd_v3_add(vw, vw, d->body_v + 3 * b);
    }
    if (pw) cd_v3_copy(pw, p);
}

/* spatial inertia of every body of system s about its reference point */
static void body_inertias(const cd_model *m, cd_data *d, int s)
{
    cd_rbi *I = (cd_rbi *)d->body_rbi;
    int b, b0 = m->sys_body_adr[s];
    for (b = b0; b < b0 + m->sys_nbody[s]; b++) {
        double Iw[9], c[3];
        cd_m3_rotsym(Iw, d->body_R + 9 * b, m->body_inertia + 9 * b);
        cd_v3_sub(c, d->body_c + 3 * b, d->sys_ref + 3 * s);
        cd_rbi_make(&I[b], m->body_mass[b], c, Iw);
    }
}

void cd_inverse_dynamics(const cd_model *m, cd_data *d, int s, const double *udot, double *tau)
{
    int b0 = m->sys_body_adr[s], nb = m->sys_nbody[s], b, i;
    int free_base = m->sys_base_type[s] == CD_BASE_FREE, j0 = free_base ? 6 : 0;
    cd_rbi *I = (cd_rbi *)d->body_rbi;
    double *A = d->work, *F = d->work + 6 * m->nbody; /* (nbody x 6) each */
    double *A0 = A + 6 * b0, t[6], IV[6];
    body_inertias(m, d, s);
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

void cd_mass_matrix(const cd_model *m, cd_data *d, int s, double *H)
{
    int b0 = m->sys_body_adr[s], nb = m->sys_nbody[s], n = m->sys_ndof[s], b, i, k;
    int free_base = m->sys_base_type[s] == CD_BASE_FREE, j0 = free_base ? 6 : 0;
    cd_rbi *I = (cd_rbi *)d->body_rbi, *Ic = (cd_rbi *)d->body_rbi + m->nbody;
    body_inertias(m, d, s);
    for (b = b0; b < b0 + nb; b++) Ic[b] = I[b];
    for (b = b0 + nb - 1; b > b0; b--) cd_rbi_add(&Ic[m->body_parent[b]], &Ic[b]);
    memset(H, 0, (size_t)n * (size_t)n * sizeof(double));
    for (b = b0 + 1; b < b0 + nb; b++) {
        int ib = j0 + b - b0 - 1, a;
        double F[6];
        cd_rbi_mulv(F, &Ic[b], d->body_S + 6 * b);
        H[ib * n + ib] = cd_sv_dot(d->body_S + 6 * b, F);
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

cd_status cd_forward_dynamics(const cd_model *m, cd_data *d) { return cd_forward_dynamics_method(m, d, CD_FD_AUTO); }

/* ABA (aba.c) from CD_ABA_MIN_DOF on, measured crossover (docs/performance.md) */
cd_status cd_forward_dynamics_method(const cd_model *m, cd_data *d, cd_fd_method method)
{
    int s, i;
    for (s = 0; s < m->nsys; s++) {
        int n = m->sys_ndof[s], va = m->sys_v_adr[s];
        double *rhs = d->work + 12 * m->nbody, *zero = rhs + n;
        if (n == 0) continue;
        if (method == CD_FD_ABA || (method == CD_FD_AUTO && n >= CD_ABA_MIN_DOF)) {
            if (cd_aba_forward(m, d, s) != CD_OK) return CD_ENUMERIC;
            continue;
        }
        for (i = 0; i < n; i++) zero[i] = 0.0;
        cd_inverse_dynamics(m, d, s, zero, rhs); /* rhs = h - J^T F (bias) */
        for (i = 0; i < n; i++) rhs[i] = d->tau[va + i] - rhs[i];
        cd_mass_matrix(m, d, s, d->H);
        if (cd_chol_decomp(d->H, n) != 0) return CD_ENUMERIC;
        cd_chol_solve(d->H, n, rhs);
        for (i = 0; i < n; i++) d->udot[va + i] = rhs[i];
    }
    return CD_OK;
}

void cd_momentum(const cd_model *m, const cd_data *d, int s, double *ke, double P[3],
                 double Lc[3], double Lo[3], double com[3])
{
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
    int b0 = m->sys_body_adr[s], b;
    double u = 0;
    for (b = b0; b < b0 + m->sys_nbody[s]; b++)
        u -= m->body_mass[b] * cd_v3_dot(m->gravity, d->body_c + 3 * b);
    return u;
}
