/* Actuation and joint elements.
 *
 * Actuator a: command u = law(t, q_a, qdot_a) + ctrl[a], where the
 * transmission coordinate is q_a = sum_j r_j q_j (one motor driving every
 * joint of a finger through belts or wires with ratios r_j), its rate
 * qdot_a = sum_j r_j qdot_j (power-consistent: u qdot_a = sum_j (r_j u) qdot_j).
 * With a motor model the torque is limited to the envelope of a
 * voltage-saturated DC motor, u in [-T_s (1 + w/w_0), T_s (1 - w/w_0)]
 * (stall torque T_s, no-load speed w_0, w = qdot_a); each joint then takes
 * r_j u. The envelope is a Lipschitz kink, not a discontinuity: the
 * integrator needs no event for it.
 *
 * Joint elements (all on the joint's generalized force, in qfrc_passive):
 *   spring  -k (q - q_rest), damper -c qdot;
 *   stops   compliant: depth d beyond the limit, law K d^p + D ddot^q
 *           (signed powers) with the contact's no-pull rule; engagement and
 *           release are located events (mode FREE / LOWER / UPPER);
 *   friction Coulomb with stiction, as the contact's tangential law in 1-D:
 *           stick  tau = -(k_s z + c_s qdot), zdot = qdot (z in y),
 *           slip   tau = -T_c s (s = slip direction anchored at the switch),
 *           stick -> slip where |tau| reaches T_c, slip -> stick where the
 *           joint rate reverses against s (located events). */
#include "capdyn/sim.h"
#include "../math/cd_math.h"
#include "actuation.h"

#include <string.h>

static double sgnpow(double x, double p)
{
    if (p == 1.0) return x;
    return x >= 0 ? pow(x, p) : -pow(-x, p);
}

int cd_schedule_piece(const cd_model *m, int a, double t)
{
    return cd_count_le(m->tbl_t + m->act_tbl_adr[a], m->act_tbl_n[a], t);
}

/* law of actuator a, schedules by the row in d->act_piece */
static double law(const cd_model *m, const cd_data *d, int a, double q, double qd)
{
    const double *p = m->act_prm + 4 * a, *tt = NULL, *vv = NULL;
    int n = m->act_tbl_n[a], k = d->act_piece[a];
    if (n > 0) { /* (no pointer arithmetic on the tables of a model that has none) */
        tt = m->tbl_t + m->act_tbl_adr[a];
        vv = m->tbl_v + m->act_tbl_adr[a];
    }
    switch (m->act_type[a]) {
    case CD_ACT_CONSTANT: return p[0];
    case CD_ACT_PD: return p[0] + p[1] * (p[3] - q) - p[2] * qd;
    case CD_ACT_STEPS: return k == 0 ? vv[0] : vv[k - 1];
    case CD_ACT_TABLE:
        if (k == 0) return vv[0];
        if (k >= n) return vv[n - 1];
        /* the segment of this row, also at its right end (evaluated there before the switch) */
        return vv[k - 1] + (vv[k] - vv[k - 1]) * (d->t - tt[k - 1]) / (tt[k] - tt[k - 1]);
    default: return 0.0;
    }
}

void cd_actuation(const cd_model *m, cd_data *d)
{
    int a, j;
    memset(d->qfrc_actuator, 0, (size_t)m->nv * sizeof(double));
    for (a = 0; a < m->nu; a++) {
        int adr = m->act_trn_adr[a], n = m->act_trn_n[a];
        double q = 0, qd = 0, u, Ts = m->act_motor[2 * a];
        for (j = 0; j < n; j++) {
            q += m->trn_ratio[adr + j] * cd_joint_q(m, d, m->trn_body[adr + j]);
            qd += m->trn_ratio[adr + j] * cd_joint_qd(m, d, m->trn_body[adr + j]);
        }
        u = law(m, d, a, q, qd) + d->ctrl[a];
        if (Ts > 0) {
            double w0 = m->act_motor[2 * a + 1], hi = Ts * (1.0 - qd / w0), lo = -Ts * (1.0 + qd / w0);
            if (u > hi) u = hi;
            if (u < lo) u = lo;
        }
        d->act_velocity[a] = qd;
        d->act_force[a] = u;
        for (j = 0; j < n; j++) d->qfrc_actuator[m->body_dof[m->trn_body[adr + j]]] += m->trn_ratio[adr + j] * u;
    }
}

/* depth beyond each limit (lower, upper) and its rate */
static void limit_depths(const cd_model *m, const cd_data *d, int b, double *dlo, double *dhi, double *qd)
{
    double q = cd_joint_q(m, d, b);
    *qd = cd_joint_qd(m, d, b);
    *dlo = m->body_limit[6 * b] - q;
    *dhi = q - m->body_limit[6 * b + 1];
}

static double stop_law(const double *L, double depth, double rate)
{
    return L[2] * sgnpow(depth, L[4]) + L[3] * sgnpow(rate, L[5]);
}

void cd_joint_passive(const cd_model *m, cd_data *d, double *zdot)
{
    int b, i;
    memset(d->qfrc_passive, 0, (size_t)m->nv * sizeof(double));
    for (b = 0; b < m->nbody; b++) {
        int v = m->body_dof[b];
        if (v < 0) continue;
        if (m->body_spring[2 * b] != 0)
            d->qfrc_passive[v] -= m->body_spring[2 * b] * (cd_joint_q(m, d, b) - m->body_spring[2 * b + 1]);
        if (m->body_damping[b] != 0) d->qfrc_passive[v] -= m->body_damping[b] * cd_joint_qd(m, d, b);
    }
    for (i = 0; i < m->nlim; i++) {
        int b2 = m->lim_body[i], mode = d->lim_mode[i];
        const double *L = m->body_limit + 6 * b2;
        double dlo, dhi, qd, depth, rate, raw, f = 0;
        limit_depths(m, d, b2, &dlo, &dhi, &qd);
        if (mode == CD_LIM_UPPER || (mode == CD_LIM_FREE && dhi > dlo)) { depth = dhi; rate = qd; }
        else { depth = dlo; rate = -qd; }
        raw = stop_law(L, depth, rate);
        if (mode != CD_LIM_FREE) {
            f = raw; /* >= 0 between events: release is located where it reaches 0 */
            if (d->sw_held[m->nslot + i] && f < 0) f = 0;
            d->qfrc_passive[m->body_dof[b2]] += mode == CD_LIM_LOWER ? f : -f;
        }
        d->lim_depth[i] = depth;
        d->lim_raw[i] = raw;
        d->lim_force[i] = mode == CD_LIM_UPPER ? -f : f;
    }
    for (i = 0; i < m->nfric; i++) {
        int b2 = m->fric_body[i], u = m->nslot + m->nlim + i;
        const double *F = m->body_fric + 3 * b2;
        double qd = cd_joint_qd(m, d, b2), tau;
        if (d->fric_mode[i] == CD_MODE_STICK) {
            tau = -(F[1] * d->y[m->ny_fric_adr + i] + F[2] * qd);
            zdot[i] = qd;
            if (d->sw_held[u] && fabs(tau) > F[0]) tau = tau > 0 ? F[0] : -F[0];
        } else {
            tau = -F[0] * d->fric_dir[i];
            zdot[i] = 0.0;
        }
        d->fric_force[i] = tau;
        d->qfrc_passive[m->body_dof[b2]] += tau;
    }
}

/* ---- switch providers ------------------------------------------------------ */

/* FREE: g[0], g[1] = -min(K d, raw) of the lower and upper stop (onset when
 * both the depth and the law's force are positive, as a contact's onset);
 * engaged: g[0] = min(K d, raw) (release where the stop stops pushing). */
void cd_limit_functions(const cd_model *m, const cd_data *d, int i, double g[2])
{
    int b = m->lim_body[i], mode = d->lim_mode[i];
    const double *L = m->body_limit + 6 * b;
    double dlo, dhi, qd, rlo, rhi;
    limit_depths(m, d, b, &dlo, &dhi, &qd);
    rlo = stop_law(L, dlo, -qd);
    rhi = stop_law(L, dhi, qd);
    if (mode == CD_LIM_FREE) {
        g[0] = -(L[2] * dlo < rlo ? L[2] * dlo : rlo);
        g[1] = -(L[2] * dhi < rhi ? L[2] * dhi : rhi);
    } else {
        double dd = mode == CD_LIM_LOWER ? dlo : dhi, r = mode == CD_LIM_LOWER ? rlo : rhi;
        g[0] = L[2] * dd < r ? L[2] * dd : r;
        g[1] = 1.0;
    }
}

int cd_limit_transition(const cd_model *m, cd_data *d, int i, cd_event *ev)
{
    double g[2];
    int from = d->lim_mode[i], to = from;
    cd_limit_functions(m, d, i, g);
    if (from == CD_LIM_FREE) {
        if (g[0] < 0 && g[0] <= g[1]) to = CD_LIM_LOWER;
        else if (g[1] < 0) to = CD_LIM_UPPER;
    } else if (g[0] < 0) {
        to = CD_LIM_FREE;
    }
    if (to == from) return 0;
    ev->kind = to == CD_LIM_FREE ? CD_EV_LIMIT_RELEASE : CD_EV_LIMIT_ENGAGE;
    ev->owner_kind = CD_OWNER_JOINT;
    ev->owner = m->lim_body[i];
    ev->body_a = m->lim_body[i];
    ev->mode_from = from;
    ev->mode_to = to;
    ev->x = d->lim_depth[i];
    ev->fn = d->lim_force[i];
    d->lim_mode[i] = to;
    return 1;
}

/* stick: T_c - |tau| (slip when negative); slip: s qdot + v_reg (stick when
 * the rate reverses against the slip direction). */
void cd_fric_functions(const cd_model *m, const cd_data *d, int i, int forgive, double g[2])
{
    int b = m->fric_body[i];
    double Tc = m->body_fric[3 * b];
    if (d->fric_mode[i] == CD_MODE_STICK) {
        g[0] = Tc - fabs(d->fric_force[i]);
        if (forgive && g[0] >= -1e-9 * Tc) g[0] = 0;
    } else {
        g[0] = d->fric_dir[i] * cd_joint_qd(m, d, b) + d->opt.v_reg;
        if (forgive && g[0] >= -1e-3 * d->opt.v_reg) g[0] = 0;
    }
    g[1] = 1.0;
}

/* The friction torque that stops joint i's acceleration at the evaluated
 * state (d->udot, with the sliding torque -T_c s applied): with the inverse
 * mass matrix's diagonal entry w = (H^-1)_jj of its system, a torque change
 * dtau changes qdd_j by w dtau, so tau_hold = tau_slide - qdd_j / w, kept in
 * the friction band [-T_c, T_c] (Coulomb at rest). H and its Cholesky factor
 * go to d->H, the column of L^-1 to d->work (scratch of an event, not a step). */
static double fric_hold(const cd_model *m, cd_data *d, int i)
{
    int b = m->fric_body[i], s = m->body_sys[b], n = m->sys_ndof[s], j = m->body_dof[b] - m->sys_v_adr[s], r, k;
    double Tc = m->body_fric[3 * b], w = 0.0, *y = d->work, tau;
    cd_mass_matrix(m, d, s, d->H);
    if (cd_chol_decomp(d->H, n) != 0) return d->fric_force[i];
    /* y = L^-1 e_j (zero above j), w = |y|^2 */
    for (r = j; r < n; r++) {
        double acc = r == j ? 1.0 : 0.0;
        for (k = j; k < r; k++) acc -= d->H[r * n + k] * y[k];
        y[r] = acc / d->H[r * n + r];
        w += y[r] * y[r];
    }
    if (!(w > 0)) return d->fric_force[i];
    tau = d->fric_force[i] - d->udot[m->body_dof[b]] / w;
    return tau > Tc ? Tc : tau < -Tc ? -Tc : tau;
}

int cd_fric_transition(const cd_model *m, cd_data *d, int i, cd_event *ev)
{
    int b = m->fric_body[i], from = d->fric_mode[i];
    const double *F = m->body_fric + 3 * b;
    double g[2];
    cd_fric_functions(m, d, i, 0, g);
    if (!(g[0] < 0)) return 0;
    ev->owner_kind = CD_OWNER_JOINT;
    ev->owner = b;
    ev->body_a = b;
    ev->ft = fabs(d->fric_force[i]);
    if (from == CD_MODE_STICK) {
        /* the joint slips where the stick spring is pulled: against its torque */
        d->fric_dir[i] = d->fric_force[i] > 0 ? -1.0 : 1.0;
        d->fric_mode[i] = CD_MODE_SLIP;
        ev->kind = CD_EV_STICK_SLIP;
    } else {
        /* The joint has stopped. Coulomb friction at rest is a reaction: it
         * takes whatever torque keeps the joint at rest, up to T_c, not the
         * sliding value T_c (anchoring at -(k z + c qdot) = -T_c s preloaded
         * the stick spring with T_c and sprang the joint back by T_c / k_s
         * once the drive was gone, issue 22). The anchor gives the stick
         * spring the holding torque at the current state. */
        double tau = fric_hold(m, d, i);
        d->y[m->ny_fric_adr + i] = -(tau + F[2] * cd_joint_qd(m, d, b)) / F[1];
        d->fric_mode[i] = CD_MODE_STICK;
        ev->kind = CD_EV_SLIP_STICK;
    }
    ev->mode_from = from;
    ev->mode_to = d->fric_mode[i];
    return 1;
}

