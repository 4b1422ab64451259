/* The structured Jacobian of the right-hand side (jac.h), for the linearly
 * implicit steppers.
 *
 * Why: a finite-difference Jacobian on the active set costs one full
 * evaluation (kinematics, every contact slot, dynamics) per unknown; around
 * contact events, where every restart renewed it, that was half of all
 * evaluations of the Fig. 5 grasp (docs/performance.md). The stiffness of a
 * grasp sits in a few places the model knows in closed form: the compliant
 * contact laws (eq. 3, 4, 5: K, D, K_t, D_t, and the slip law's mu f_n / |u|),
 * the joint elements (springs, dampers, compliant stops, stick springs of
 * joint friction) and the stiff wires of the clutched fingers. Those are
 * assembled here from the contact points' Jacobians and the mass matrix, at
 * the cost of about one evaluation.
 *
 * What is left out, and why that is safe: the Rosenbrock-W stepper
 * (ROS34PW2) keeps its order 3 with any matrix in place of the Jacobian
 * (Rang & Angermann 2005); the matrix only has to carry the stiff modes for
 * stability. The terms dropped are of the order of the forces, not of the
 * stiffnesses: velocity products (Coriolis, centrifugal), gravity, the change
 * of H with q, the turning of a contact's normal and of the shape's frame
 * with the bodies, and whatever a user control callback computes (it is
 * opaque). tests/test_jac.c checks the stiff blocks against the finite
 * difference Jacobian on random states of the shipped hands. */
#include "jac.h"
#include "../math/cd_math.h"
#include "../mechanism/actuation.h"
#include "../contact/contact.h"

#include <stdint.h>
#include <string.h>

static int maxdof_of(const cd_model *m)
{
    int s, n = 1;
    for (s = 0; s < m->nsys; s++)
        if (m->sys_ndof[s] > n) n = m->sys_ndof[s];
    return n;
}

size_t cd_jacw_size(const cd_model *m, int na_max)
{
    size_t ny = (size_t)(m->ny ? m->ny : 1), nv = (size_t)(m->nv ? m->nv : 1), md = (size_t)maxdof_of(m);
    size_t na = (size_t)(na_max > 0 ? na_max : 1), nf = (size_t)m->nfric + 1;
    return 16 + (nv * na + 12 * md + 3 * md + md * md + ny + 2 * nv + 2 * nf) * sizeof(double) +
           (ny + 2 * nv) * sizeof(int) + 16;
}

void cd_jacw_init(cd_jacw *w, const cd_model *m, int na_max, void *mem)
{
    size_t ny = (size_t)(m->ny ? m->ny : 1), nv = (size_t)(m->nv ? m->nv : 1), md = (size_t)maxdof_of(m);
    size_t na = (size_t)(na_max > 0 ? na_max : 1), nf = (size_t)m->nfric + 1;
    double *p = (double *)(void *)(((uintptr_t)mem + 15) & ~(uintptr_t)15);
    int s, i, *ip;
    w->na_max = na_max;
    w->maxdof = (int)md;
    w->dQ = p; p += nv * na;
    w->G[0] = p; p += 6 * md;
    w->G[1] = p; p += 6 * md;
    w->T = p; p += 3 * md;
    w->L = p; p += md * md;
    w->ys = p; p += ny;
    w->Q0 = p; p += nv;
    w->Q1 = p; p += nv;
    w->z0 = p; p += nf;
    w->z1 = p; p += nf;
    ip = (int *)(void *)p;
    w->map = ip; ip += ny;
    w->qi = ip; ip += nv;
    w->vi = ip;
    /* where each generalized coordinate's position and velocity sit in y
     * (the layout of cd_state_of: free [r0 quat q | v0 w0 qd], fixed [q | qd]) */
    for (s = 0; s < m->nsys; s++) {
        int a = m->sys_y_adr[s], nj = m->sys_nbody[s] - 1, va = m->sys_v_adr[s];
        int fr = m->sys_base_type[s] == CD_BASE_FREE, q = fr ? a + 7 : a, v = fr ? a + 7 + nj : a + nj;
        for (i = 0; i < m->sys_ndof[s]; i++) {
            int j = fr ? i - 6 : i;
            w->vi[va + i] = v + i;
            w->qi[va + i] = j >= 0 ? q + j : -1;
        }
    }
}

/* ---- 3x3 helpers (row-major) ---- */
static void m3_outer_add(double A[9], double s, const double a[3], const double b[3])
{
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) A[3 * i + j] += s * a[i] * b[j];
}

/* d/da of K |a|^(p-1) a (the signed vector power of contact.c); p = 1: K I */
static void vpow_jac(double Jm[9], const double a[3], double K, double p)
{
    double na = cd_v3_norm(a), e[3];
    int i;
    memset(Jm, 0, 9 * sizeof(double));
    if (p == 1.0) {
        Jm[0] = Jm[4] = Jm[8] = K;
        return;
    }
    if (!(na > 1e-12)) na = 1e-12; /* a sublinear law is infinitely stiff at 0: cap it */
    for (i = 0; i < 3; i++) Jm[4 * i] = K * pow(na, p - 1.0);
    cd_v3_scale(e, a, 1.0 / na);
    m3_outer_add(Jm, K * pow(na, p - 1.0) * (p - 1.0), e, e);
}

/* r = K |a|^p a/|a| (contact.c's vector law) */
static void vpow_vec(double r[3], const double a[3], double K, double p)
{
    double na;
    if (p == 1.0) { cd_v3_scale(r, a, K); return; }
    na = cd_v3_norm(a);
    cd_v3_scale(r, a, na > 0 ? K * pow(na, p - 1.0) : 0.0);
}

/* E (3 x 4): world rotation increment of a quaternion increment,
 * dphi = 2 (w dv - dw v + v x dv) for the unit quaternion q/|q|, over |q| */
static void quat_E(double E[12], const double *q)
{
    double nq = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]), w, v[3];
    int k, i;
    w = q[0] / nq;
    v[0] = q[1] / nq; v[1] = q[2] / nq; v[2] = q[3] / nq;
    for (i = 0; i < 3; i++) E[4 * i] = -2.0 * v[i] / nq;
    for (k = 0; k < 3; k++) {
        double ek[3] = {0, 0, 0}, c[3];
        ek[k] = 1.0;
        cd_v3_cross(c, v, ek);
        for (i = 0; i < 3; i++) E[4 * i + 1 + k] = 2.0 * (w * ek[i] + c[i]) / nq;
    }
}

typedef struct {
    int body, sys, n, va, sgn; /* side of a slot: body, system, its dof count and address, +1 A / -1 B */
    double *G;                 /* 6 x n: rows 0-2 the contact point's linear Jacobian */
} side;

/* dQ[va_X .. , columns of Y] += sX sY G_Xᵀ A G_Y, on Y's velocity columns
 * (pos = 0) or position columns (pos = 1: through E for a base rotation) */
static void add_block(const cd_model *m, const cd_data *d, cd_jacw *w, int na, const side *X, const side *Y,
                      const double A[9], int pos)
{
    int i, j, c, k;
    double s = (double)(X->sgn * Y->sgn), E[12];
    int fr = m->sys_base_type[Y->sys] == CD_BASE_FREE, ya = m->sys_y_adr[Y->sys];
    if (X->n == 0 || Y->n == 0) return;
    if (pos && fr) quat_E(E, d->y + ya + 3);
    /* T = G_Xᵀ A (n_X x 3) */
    for (i = 0; i < X->n; i++)
        for (c = 0; c < 3; c++) {
            double t = 0;
            for (k = 0; k < 3; k++) t += X->G[k * X->n + i] * A[3 * k + c];
            w->T[3 * i + c] = s * t;
        }
    for (j = 0; j < Y->n; j++) {
        double g[3] = {Y->G[j], Y->G[Y->n + j], Y->G[2 * Y->n + j]};
        int ycol;
        if (g[0] == 0 && g[1] == 0 && g[2] == 0) continue;
        if (!pos) ycol = w->vi[Y->va + j];
        else if (fr && j < 3) ycol = ya + j;
        else if (fr && j < 6) ycol = -2; /* base rotation: spread over the quaternion below */
        else ycol = w->qi[Y->va + j];
        for (i = 0; i < X->n; i++) {
            double v = w->T[3 * i] * g[0] + w->T[3 * i + 1] * g[1] + w->T[3 * i + 2] * g[2];
            double *row = w->dQ + (size_t)(X->va + i) * (size_t)na;
            if (v == 0) continue;
            if (ycol == -2) {
                for (c = 0; c < 4; c++) {
                    int a = w->map[ya + 3 + c];
                    if (a >= 0) row[a] += v * E[4 * (j - 3) + c];
                }
            } else if (ycol >= 0 && w->map[ycol] >= 0) {
                row[w->map[ycol]] += v;
            }
        }
    }
}

/* the stiff derivatives of one closed slot's force F (on A, world) with
 * respect to the relative velocity, the relative displacement and the stick
 * anchor (shape-body axes); Zv: the anchor's rate against the relative velocity */
static void slot_derivs(const cd_model *m, const cd_data *d, int k, double Av[9], double Ap[9], double Az[9],
                        double Zv[9], double Zz[9], int *stick)
{
    const cd_contact_law *L = &m->law[m->slot_law[k]];
    const double *n = d->slot_normal + 3 * k, *RB = d->body_R + 9 * m->shape_body[m->slot_shape[k]];
    double x = d->slot_x[k], xd = d->slot_xdot[k], fn = d->slot_fn[k], P[9], dfx, dfv, dfk;
    int i;
    for (i = 0; i < 9; i++) P[i] = (i % 4 == 0) ? 1.0 : 0.0;
    m3_outer_add(P, -1.0, n, n);
    /* the normal law's partials (contact.h: linear eq. (3) or Hunt-Crossley) */
    (void)cd_law_normal(L, x, xd, &dfx, &dfv);
    /* the spring's share alone: the slip law's cone rate uses only it (contact.c) */
    dfk = L->p == 1.0 ? L->K : L->K * L->p * pow(fabs(x) > 1e-12 ? fabs(x) : 1e-12, L->p - 1.0);
    /* normal: f_n(x, xdot), x' = -n.dp, xdot = -n.v */
    memset(Av, 0, 9 * sizeof(double));
    memset(Ap, 0, 9 * sizeof(double));
    memset(Az, 0, 9 * sizeof(double));
    memset(Zv, 0, 9 * sizeof(double));
    memset(Zz, 0, 9 * sizeof(double));
    m3_outer_add(Av, -dfv, n, n);
    m3_outer_add(Ap, -dfx, n, n);
    *stick = d->slot_mode[k] == CD_MODE_STICK;
    if (*stick) {
        /* eq. (4): f_t = -(K_t z_t^pt + D_t v_t^qt), z_t = P R_B z, v_t = P v; z' = R_Bᵀ v_t */
        double Dv[9], Dj[9], Kj[9], zw[3], zt[3], RBt[9], PR[9];
        const double *z = d->y + m->ny_slot_adr + 3 * k;
        vpow_jac(Dv, d->slot_vt + 3 * k, L->Dt, L->qt);
        cd_m3_mul(Dj, Dv, P);
        for (i = 0; i < 9; i++) Av[i] -= Dj[i];
        cd_m3_mulv(zw, RB, z);
        cd_m3_mulv(zt, P, zw);
        vpow_jac(Kj, zt, L->Kt, L->pt);
        cd_m3_mul(PR, P, RB);
        cd_m3_mul(Az, Kj, PR);
        for (i = 0; i < 9; i++) Az[i] = -Az[i];
        for (i = 0; i < 9; i++) RBt[i] = RB[3 * (i % 3) + i / 3];
        cd_m3_mul(Zv, RBt, P);
    } else if (L->Dt > 0) {
        /* slip of the saturated bristle (contact.c): with the trial force
         * f_tr = K_t z_t^pt + D_t v_t^qt and s = f_tr/|f_tr|, f_t = -mu f_n s and
         * the anchor's rate z' = R_Bᵀ (v_t - v_a), v_a = (|f_tr| - mu f_n) s / D_t
         * (the rate's law taken as linear in D_t for any qt):
         *   df_t = -mu s df_n - mu f_n / |f_tr| (I - s sᵀ) df_tr
         *   dv_a = (1/D_t) [(s sᵀ + c (I - s sᵀ)) df_tr - mu s df_n],  c = 1 - mu f_n / |f_tr| */
        double Dv[9], Dj[9], Kj[9], Kz[9], zw[3], zt[3], fk[3], fd[3], ftr[3], sh[3], nf, c, Ps[9], Q[9], Tm[9];
        double RBt[9], PR[9];
        const double *z = d->y + m->ny_slot_adr + 3 * k, *vt = d->slot_vt + 3 * k;
        cd_m3_mulv(zw, RB, z);
        cd_m3_mulv(zt, P, zw);
        vpow_jac(Kj, zt, L->Kt, L->pt);
        vpow_jac(Dv, vt, L->Dt, L->qt);
        vpow_vec(fk, zt, L->Kt, L->pt);
        vpow_vec(fd, vt, L->Dt, L->qt);
        cd_v3_add(ftr, fk, fd);
        nf = cd_v3_norm(ftr);
        if (!(nf > 0) || !(fn > 0 || (CD_CONTACT_SLIP_SMOOTH && !L->pull))) return; /* the law contact.c applies */
        cd_v3_scale(sh, ftr, 1.0 / nf);
        c = 1.0 - L->mu_k * fn / nf;
        for (i = 0; i < 9; i++) Ps[i] = (i % 4 == 0) ? 1.0 : 0.0;
        m3_outer_add(Ps, -1.0, sh, sh);                     /* I - s sᵀ */
        cd_m3_mul(Dj, Dv, P);                               /* df_tr/dv */
        cd_m3_mul(PR, P, RB);
        cd_m3_mul(Kz, Kj, PR);                              /* df_tr/dz */
        m3_outer_add(Av, L->mu_k * dfv, sh, n);
        m3_outer_add(Ap, L->mu_k * dfx, sh, n);
        cd_m3_mul(Tm, Ps, Dj);
        for (i = 0; i < 9; i++) Av[i] -= L->mu_k * fn / nf * Tm[i];
        cd_m3_mul(Tm, Ps, Kz);
        for (i = 0; i < 9; i++) Az[i] = -L->mu_k * fn / nf * Tm[i];
        /* Q = s sᵀ + c (I - s sᵀ); z'_world = v_t - v_a */
        for (i = 0; i < 9; i++) Q[i] = c * Ps[i];
        m3_outer_add(Q, 1.0, sh, sh);
        for (i = 0; i < 9; i++) RBt[i] = RB[3 * (i % 3) + i / 3];
        cd_m3_mul(Tm, Q, Dj);
        for (i = 0; i < 9; i++) Tm[i] = P[i] - Tm[i] / L->Dt;
        m3_outer_add(Tm, -L->mu_k * dfv / L->Dt, sh, n);   /* -(1/D_t)(-mu s df_n/dv), df_n/dv = -dfv nᵀ */
        cd_m3_mul(Zv, RBt, Tm);
        cd_m3_mul(Tm, Q, Kz);
        for (i = 0; i < 9; i++) Tm[i] = -Tm[i] / L->Dt;
        cd_m3_mul(Zz, RBt, Tm);
        *stick = 2;
    } else {
        /* eq. (5): f_t = -mu f_n u/|u|, u = v_a + 2 v_reg s_t, v_a = v_t - zrate s_t,
         * zrate = (mu / K_t) K p x^(p-1) xdot (the cone's elastic rate, pt = 1) */
        double st[3], u[3], nu, uh[3], dva[9], Iu[9], Tm[9];
        const double *va = d->slot_va + 3 * k;
        cd_m3_mulv(st, P, d->slot_dir + 3 * k);
        if (!(cd_v3_norm(st) > 0)) return;
        cd_v3_normalize(st);
        cd_v3_copy(u, va);
        cd_v3_axpy(u, 2.0 * d->opt.v_reg, st);
        nu = cd_v3_norm(u);
        if (!(nu > 0) || !(fn > 0 || (CD_CONTACT_SLIP_SMOOTH && !L->pull))) return;
        cd_v3_scale(uh, u, 1.0 / nu);
        memcpy(dva, P, sizeof dva);
        if (L->pt == 1.0) m3_outer_add(dva, L->mu_k * dfk / L->Kt, st, n);
        /* -mu uh (df_n/dv) - mu f_n / |u| (I - uh uhᵀ) dva/dv */
        m3_outer_add(Av, L->mu_k * dfv, uh, n);
        m3_outer_add(Ap, L->mu_k * dfx, uh, n);
        for (i = 0; i < 9; i++) Iu[i] = (i % 4 == 0) ? 1.0 : 0.0;
        m3_outer_add(Iu, -1.0, uh, uh);
        cd_m3_mul(Tm, Iu, dva);
        for (i = 0; i < 9; i++) Av[i] -= L->mu_k * fn / nu * Tm[i];
    }
}

static void contacts(const cd_model *m, cd_data *d, cd_jacw *w, int na, double *J)
{
    int k, a, b, i, j;
    for (k = 0; k < m->nslot; k++) {
        double Av[9], Ap[9], Az[9], Zv[9], Zz[9], pb[3], t[3];
        side S[2];
        int stick, zc = m->ny_slot_adr + 3 * k;
        if (d->slot_mode[k] == CD_MODE_OPEN || d->slot_geomfail[k]) continue;
        slot_derivs(m, d, k, Av, Ap, Az, Zv, Zz, &stick);
        S[0].body = m->cp_body[m->slot_cp[k]];
        S[1].body = m->shape_body[m->slot_shape[k]];
        for (a = 0; a < 2; a++) {
            int bd = S[a].body;
            S[a].sys = m->body_sys[bd];
            S[a].n = m->sys_ndof[S[a].sys];
            S[a].va = m->sys_v_adr[S[a].sys];
            S[a].sgn = a == 0 ? 1 : -1;
            S[a].G = w->G[a];
            if (S[a].n == 0) continue;
            /* the contact point c in the body's frame */
            cd_v3_sub(t, d->slot_point + 3 * k, d->body_x + 3 * bd);
            cd_m3_tmulv(pb, d->body_R + 9 * bd, t);
            cd_point_jacobian(m, d, bd, pb, S[a].G);
        }
        for (a = 0; a < 2; a++)
            for (b = 0; b < 2; b++) {
                add_block(m, d, w, na, &S[a], &S[b], Av, 0);
                add_block(m, d, w, na, &S[a], &S[b], Ap, 1);
            }
        if (!stick) continue;
        /* dQ_X += s_X G_Xᵀ Az on the anchor's columns; the anchor's rows z' = Zv v_rel */
        for (a = 0; a < 2; a++) {
            const side *X = &S[a];
            for (i = 0; i < X->n; i++)
                for (j = 0; j < 3; j++) {
                    int col = w->map[zc + j];
                    double v = 0;
                    int r;
                    if (col < 0) continue;
                    for (r = 0; r < 3; r++) v += X->G[r * X->n + i] * Az[3 * r + j];
                    w->dQ[(size_t)(X->va + i) * (size_t)na + col] += X->sgn * v;
                }
        }
        for (i = 0; i < 3; i++) {
            int row = w->map[zc + i];
            if (row < 0) continue;
            for (a = 0; a < 2; a++) {
                const side *Y = &S[a];
                for (j = 0; j < Y->n; j++) {
                    int col = w->map[w->vi[Y->va + j]];
                    double v = 0;
                    int r;
                    if (col < 0) continue;
                    for (r = 0; r < 3; r++) v += Zv[3 * i + r] * Y->G[r * Y->n + j];
                    J[(size_t)row * (size_t)na + col] += Y->sgn * v;
                }
            }
            if (stick == 2) /* a slipping bristle's own relaxation */
                for (j = 0; j < 3; j++) {
                    int col = w->map[zc + j];
                    if (col >= 0) J[(size_t)row * (size_t)na + col] += Zz[3 * i + j];
                }
        }
    }
}

/* generalized forces of the joint elements and actuation at d->y (no kinematics needed) */
static void elements(const cd_model *m, cd_data *d, double *Q, double *zf)
{
    int i;
    cd_joint_passive(m, d, zf);
    cd_actuation(m, d);
    if (m->nfinger) cd_gripper_torques(m, d);
    for (i = 0; i < m->nv; i++) Q[i] = d->qfrc_actuator[i] + d->qfrc_passive[i];
}

/* joint elements: forward differences in joint space (joint positions and
 * rates, joint-friction anchors), each a pass over the joints only */
static void joint_elements(const cd_model *m, cd_data *d, cd_jacw *w, int na, const double *y, double *J)
{
    int v, i, pass;
    double eps = d->opt.fd_eps, *ysave = d->y;
    memcpy(w->ys, y, (size_t)m->ny * sizeof(double));
    d->y = w->ys;
    elements(m, d, w->Q0, w->z0);
    for (pass = 0; pass < 3; pass++) {
        int ncol = pass < 2 ? m->nv : m->nfric;
        for (v = 0; v < ncol; v++) {
            int j = pass == 0 ? w->qi[v] : pass == 1 ? w->vi[v] : m->ny_fric_adr + v, col, r;
            double h;
            if (j < 0 || (pass == 1 && w->qi[v] < 0)) continue; /* base coordinates carry no joint element */
            col = w->map[j];
            if (col < 0) continue;
            h = eps * (fabs(y[j]) > 1.0 ? fabs(y[j]) : 1.0);
            w->ys[j] = y[j] + h;
            h = w->ys[j] - y[j];
            elements(m, d, w->Q1, w->z1);
            for (i = 0; i < m->nv; i++)
                if (w->Q1[i] != w->Q0[i]) w->dQ[(size_t)i * (size_t)na + col] += (w->Q1[i] - w->Q0[i]) / h;
            for (i = 0; i < m->nfric; i++)
                if ((r = w->map[m->ny_fric_adr + i]) >= 0 && w->z1[i] != w->z0[i])
                    J[(size_t)r * (size_t)na + col] += (w->z1[i] - w->z0[i]) / h;
            w->ys[j] = y[j];
        }
    }
    elements(m, d, w->Q0, w->z0); /* leave d's element outputs at y */
    d->y = ysave;
}

/* the kinematic rows: r0' = v0, quat' = 0.5 [0, w] x quat, q' = qd */
static void kinematic_rows(const cd_model *m, const double *y, cd_jacw *w, int na, double *J)
{
    int s, i, c;
    for (s = 0; s < m->nsys; s++) {
        int va = m->sys_v_adr[s], ya = m->sys_y_adr[s];
        for (i = 0; i < m->sys_ndof[s]; i++) {
            int row = -1, col = w->map[w->vi[va + i]];
            if (w->qi[va + i] >= 0) row = w->map[w->qi[va + i]];
            else if (i < 3) row = w->map[ya + i];
            if (row >= 0 && col >= 0) J[(size_t)row * (size_t)na + col] += 1.0;
        }
        if (m->sys_base_type[s] == CD_BASE_FREE) {
            const double *q = y + ya + 3, *om = y + w->vi[va + 3];
            for (c = 0; c < 3; c++) { /* d quat' / d w_c */
                double e[3] = {0, 0, 0}, out[4];
                int col = w->map[w->vi[va + 3 + c]];
                e[c] = 1.0;
                cd_quat_deriv_world(out, q, e);
                if (col >= 0)
                    for (i = 0; i < 4; i++)
                        if (w->map[ya + 3 + i] >= 0) J[(size_t)w->map[ya + 3 + i] * (size_t)na + col] += out[i];
            }
            for (c = 0; c < 4; c++) { /* d quat' / d quat_c (linear in quat) */
                double e[4] = {0, 0, 0, 0}, out[4];
                int col = w->map[ya + 3 + c];
                e[c] = 1.0;
                cd_quat_deriv_world(out, e, om);
                if (col >= 0)
                    for (i = 0; i < 4; i++)
                        if (w->map[ya + 3 + i] >= 0) J[(size_t)w->map[ya + 3 + i] * (size_t)na + col] += out[i];
            }
        }
    }
}

cd_status cd_jac_model(const cd_model *m, cd_data *d, double t, const double *y, const int *act, int na,
                       double *J, cd_jacw *w)
{
    double *ysave = d->y, tsave = d->t;
    cd_status st;
    int i, s, a;
    memset(J, 0, (size_t)na * (size_t)na * sizeof(double));
    memset(w->dQ, 0, (size_t)m->nv * (size_t)na * sizeof(double));
    for (i = 0; i < m->ny; i++) w->map[i] = -1;
    for (a = 0; a < na; a++) w->map[act[a]] = a;
    d->y = (double *)y;
    d->t = t;
    st = cd_forward(m, d); /* kinematics, contact outputs and modes' forces at y */
    d->stats.nrhs++;
    if (st != CD_OK) { d->y = ysave; d->t = tsave; return CD_ENUMERIC; }
    kinematic_rows(m, y, w, na, J);
    contacts(m, d, w, na, J);
    joint_elements(m, d, w, na, y, J);
    /* velocity rows: H^-1 dQ, one system at a time */
    for (s = 0; s < m->nsys; s++) {
        int n = m->sys_ndof[s], va = m->sys_v_adr[s], c;
        if (n == 0) continue;
        cd_mass_matrix(m, d, s, w->L);
        if (cd_chol_decomp(w->L, n) != 0) { d->y = ysave; d->t = tsave; return CD_ENUMERIC; }
        for (c = 0; c < na; c++) {
            double *col = w->Q1; /* n <= nv scratch */
            int any = 0;
            for (i = 0; i < n; i++) {
                col[i] = w->dQ[(size_t)(va + i) * (size_t)na + c];
                if (col[i] != 0) any = 1;
            }
            if (!any) continue;
            cd_chol_solve(w->L, n, col);
            for (i = 0; i < n; i++) {
                int row = w->map[w->vi[va + i]];
                if (row >= 0) J[(size_t)row * (size_t)na + c] += col[i];
            }
        }
    }
    d->y = ysave;
    d->t = tsave;
    return CD_OK;
}
