/* Built-in capture controllers (include/capdyn/control.h, docs/capture.md).
 *
 * Resolved-rate control of a free-floating manipulator (Whitney 1969; on a
 * free-flying base through the generalized Jacobian, Umetani & Yoshida,
 * IEEE T-RA 1989): the palm twist V = [v; w] commanded from the pose error
 * is mapped to joint rates with the generalized Jacobian J_g of the arm's
 * joints, by damped least squares (Nakamura & Hanafusa 1986):
 *     qd_ref = J_g^T (J_g J_g^T + lambda^2 I)^-1 V,
 * scaled to the joint-rate limit, then turned into torques by a rate servo
 * with each joint's own inertia (the diagonal of the chaser's mass matrix,
 * a decoupled computed-torque law without the bias terms)
 *     tau_j = H_jj k_v (qd_ref_j - qd_j),  |tau_j| <= tau_max
 * (no integrator state: the control is a function of the state, so the
 * integrator's error control stays honest). J_g assumes zero momentum of
 * the chaser (SpaceDyn's calc_GJ); after contact the difference is a
 * disturbance that the pose feedback corrects.
 * HOLD: tau_j = H_jj (w_n^2 (q_c_j - q_j) - 2 zeta w_n qd_j) about the joint
 * angles q_c at the instant HOLD began (a joint-space impedance, each joint a
 * second-order system of natural frequency w_n and damping ratio zeta for
 * its own inertia; the target's inertia, once held, lowers the frequency).
 * DETUMBLE: a damping wrench at the palm's grasp point against the palm's
 * twist V relative to the base (V = sum_j S_j qd_j over the arm's joints,
 * S_j = [a_j x (x_g - x_j); a_j] for a revolute joint), per palm axis i
 *     W_i = -sat(k_d M_i V_i, W_max,i),   tau = J^T W,
 * M_i the held target's mass or its moment of inertia about that axis
 * through the grasp point (as if it were fixed to the palm: the arm's own
 * inertia is thousands of times smaller than a held satellite's). Passive:
 * tau . qd = W . V = sum_i W_i V_i <= 0, whatever the coupling with the
 * contacts and the base, and the torque limit scales tau as a whole, which
 * keeps the sign. The per-axis limits keep the wrench within what the grasp
 * carries: a moment about a bar's own axis only by friction, about the
 * approach axis only up to the fingers' grip (beyond it they are
 * back-driven and the target turns in the hand). Per-joint damping scaled
 * by the target's inertia about each joint's axis was tried first: the
 * shoulder's share (410 kg at 3 m) saturated at any rate and twisted the
 * bar in the fingers. Attitude: n = sat(k_p e - k_d w0)
 * with e = 1/2 sum_i r_i x r0_i (columns of the base rotation now and at
 * t = 0), the small-angle rotation vector that turns the base back. */
#include "capdyn/control.h"
#include "../math/cd_math.h"
#include "../dynamics/jacobian.h"
#include "../dynamics/mass.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAXJ 32

struct cd_ctrl {
    cd_ctrl_config c;
    int na;                 /* arm joints (base to palm) */
    int arm[MAXJ];
    int arm_col[MAXJ];      /* their indices among the chaser's joints (columns of J_g; + 6 in H) */
    int nj;                 /* joints of the chaser */
    double *Jg;             /* (6 x nj) */
    double R0[9];           /* base attitude at t = 0 */
    double q_hold[MAXJ];
    double t_trig, t_hold, t_det;
    int tsys;               /* the target's system (the fixture's) */
};

cd_ctrl_config cd_ctrl_config_default(void)
{
    cd_ctrl_config c;
    memset(&c, 0, sizeof c);
    c.sys = c.palm = c.fixture_body = -1;
    cd_m3_identity(c.palm_rot);
    cd_m3_identity(c.fixture_rot);
    cd_m3_identity(c.grasp_rot);
    c.approach_axis[1] = 1.0;
    c.lateral_tol = 0.01;
    c.kp_pos = c.kp_rot = 1.0;
    c.v_max = 0.1;
    c.w_max = 0.2;
    c.dls = 0.05;
    c.qd_max = 0.2;
    c.rate_gain = 20.0;
    c.trigger_distance = 0.02;
    c.close_time = 1.0;
    c.imp_wn = 1.0;
    c.imp_zeta = 1.0;
    c.att_kp = 500.0;
    c.att_kd = 2000.0;
    c.att_tau_max = 1.0;
    c.detumble_after = 1.0;
    c.detumble_gain = 1.0;
    c.detumble_f_max = 10.0;
    c.detumble_n_max[0] = c.detumble_n_max[1] = c.detumble_n_max[2] = 1.0;
    c.detumble_base = 1;
    return c;
}

cd_ctrl *cd_ctrl_create(const cd_model *m, const cd_ctrl_config *cfg, cd_error *err)
{
    cd_ctrl *c;
    int b, b0, n = 0, tmp[MAXJ], i;
    if (!m || !cfg || !m->finalized) {
        cd_error_set(err, CD_EINVAL, "control: needs a finalized model and a configuration");
        return NULL;
    }
    if (cfg->sys < 0 || cfg->sys >= m->nsys || m->sys_base_type[cfg->sys] != CD_BASE_FREE) {
        cd_error_set(err, CD_EINVAL, "control: the chaser (system %d) must be a free-floating system", cfg->sys);
        return NULL;
    }
    if (cfg->palm < 0 || cfg->palm >= m->nbody || m->body_sys[cfg->palm] != cfg->sys) {
        cd_error_set(err, CD_EINVAL, "control: the palm (body %d) must be a body of the chaser", cfg->palm);
        return NULL;
    }
    if (cfg->fixture_body < 0 || cfg->fixture_body >= m->nbody || m->body_sys[cfg->fixture_body] == cfg->sys) {
        cd_error_set(err, CD_EINVAL, "control: the fixture (body %d) must be a body of another system", cfg->fixture_body);
        return NULL;
    }
    if (cfg->user_switch0 < 0 || cfg->user_switch0 + (cfg->detumble ? 3 : 2) > m->nuser) {
        cd_error_set(err, CD_EINVAL, "control: needs user switches %d to %d (the model has %d)", cfg->user_switch0,
                     cfg->user_switch0 + (cfg->detumble ? 2 : 1), m->nuser);
        return NULL;
    }
    if (cfg->nclose < 0 || cfg->nclose > CD_CTRL_MAX_ACT) {
        cd_error_set(err, CD_EINVAL, "control: %d close actuators (at most %d)", cfg->nclose, CD_CTRL_MAX_ACT);
        return NULL;
    }
    if (cfg->nclose_finger < 0 || cfg->nclose_finger > CD_CTRL_MAX_ACT) {
        cd_error_set(err, CD_EINVAL, "control: %d close fingers (at most %d)", cfg->nclose_finger, CD_CTRL_MAX_ACT);
        return NULL;
    }
    for (i = 0; i < cfg->nclose_finger; i++)
        if (cfg->close_finger[i] < 0 || cfg->close_finger[i] >= m->nfinger) {
            cd_error_set(err, CD_EINVAL, "control: close finger %d is not a clutched finger of the model", cfg->close_finger[i]);
            return NULL;
        }
    for (i = 0; i < cfg->nclose; i++)
        if (cfg->close_act[i] < 0 || cfg->close_act[i] >= m->nu) {
            cd_error_set(err, CD_EINVAL, "control: close actuator %d is not an actuator of the model", cfg->close_act[i]);
            return NULL;
        }
    if (!(cfg->dls > 0) || !(cfg->qd_max > 0) || !(cfg->rate_gain > 0) || !(cfg->kp_pos >= 0) || !(cfg->kp_rot >= 0) ||
        !(cfg->v_max > 0) || !(cfg->w_max > 0) || !(cfg->tau_max >= 0) || !(cfg->trigger_distance > 0) ||
        !(cfg->close_time >= 0) || !(cfg->imp_wn >= 0) || !(cfg->imp_zeta >= 0) || !(cfg->lateral_tol > 0) ||
        (cfg->attitude && !(cfg->att_tau_max > 0 && cfg->att_kp >= 0 && cfg->att_kd >= 0)) ||
        (cfg->detumble && !(cfg->detumble_after >= 0 && cfg->detumble_gain > 0 && cfg->detumble_f_max > 0 &&
                            cfg->detumble_n_max[0] > 0 && cfg->detumble_n_max[1] > 0 && cfg->detumble_n_max[2] > 0))) {
        cd_error_set(err, CD_EINVAL, "control: a gain or limit is out of range (control.h lists each one's range)");
        return NULL;
    }
    b0 = m->sys_body_adr[cfg->sys];
    for (b = cfg->palm; b > b0; b = m->body_parent[b]) {
        if (n == MAXJ) {
            cd_error_set(err, CD_EINVAL, "control: more than %d joints between the base and the palm", MAXJ);
            return NULL;
        }
        tmp[n++] = b;
    }
    if (n == 0) {
        cd_error_set(err, CD_EINVAL, "control: the palm is the chaser's base: no arm joint to drive");
        return NULL;
    }
    c = (cd_ctrl *)calloc(1, sizeof *c);
    if (!c) {
        cd_error_set(err, CD_ENOMEM, "control: out of memory");
        return NULL;
    }
    c->c = *cfg;
    cd_v3_normalize(c->c.approach_axis);
    c->na = n;
    for (i = 0; i < n; i++) {
        c->arm[i] = tmp[n - 1 - i];
        c->arm_col[i] = c->arm[i] - b0 - 1;
    }
    c->nj = m->sys_ndof[cfg->sys] - 6;
    c->Jg = (double *)calloc((size_t)(6 * (c->nj > 0 ? c->nj : 1)), sizeof(double));
    if (!c->Jg) {
        free(c);
        cd_error_set(err, CD_ENOMEM, "control: out of memory");
        return NULL;
    }
    cd_quat_to_m3(c->R0, m->sys_quat0 + 4 * cfg->sys);
    c->tsys = m->body_sys[cfg->fixture_body];
    c->t_trig = c->t_hold = c->t_det = NAN;
    if (cfg->start_hold) {
        for (i = 0; i < n; i++) c->q_hold[i] = m->body_q0[c->arm[i]];
        c->t_trig = c->t_hold = 0.0;
    }
    return c;
}

void cd_ctrl_free(cd_ctrl *c)
{
    if (!c) return;
    free(c->Jg);
    free(c);
}

void cd_ctrl_install(cd_ctrl *c, cd_data *d)
{
    cd_data_set_control(d, cd_ctrl_control, c);
    cd_data_set_user_switches(d, cd_ctrl_switch, cd_ctrl_transition, c);
}

cd_ctrl_phase cd_ctrl_phase_of(const cd_ctrl *c, const cd_data *d)
{
    int s = c->c.user_switch0;
    if (c->c.detumble && d->user_mode[s + 2]) return CD_CTRL_DETUMBLE;
    return c->c.start_hold || d->user_mode[s + 1] ? CD_CTRL_HOLD : d->user_mode[s] ? CD_CTRL_CLOSING : CD_CTRL_APPROACH;
}
double cd_ctrl_t_trigger(const cd_ctrl *c) { return c ? c->t_trig : NAN; }
double cd_ctrl_t_hold(const cd_ctrl *c) { return c ? c->t_hold : NAN; }
double cd_ctrl_t_detumble(const cd_ctrl *c) { return c ? c->t_det : NAN; }

/* The controller's memory: [magic, na, t_trig, t_hold, t_det, q_hold[na]] */
#define CTRL_STATE_MAGIC 5471.0 /* an arbitrary tag, stored exactly */
size_t cd_ctrl_state_size(const cd_ctrl *c) { return c ? (size_t)(5 + c->na) : 0; }

void cd_ctrl_state_get(const cd_ctrl *c, double *buf)
{
    if (!c || !buf) return;
    buf[0] = CTRL_STATE_MAGIC;
    buf[1] = (double)c->na;
    buf[2] = c->t_trig;
    buf[3] = c->t_hold;
    buf[4] = c->t_det;
    memcpy(buf + 5, c->q_hold, (size_t)c->na * sizeof(double));
}

cd_status cd_ctrl_state_set(cd_ctrl *c, const double *buf, cd_error *err)
{
    if (!c || !buf) {
        cd_error_set(err, CD_EINVAL, "cd_ctrl_state_set: %s is NULL", !c ? "the controller" : "the buffer");
        return CD_EINVAL;
    }
    if (!buf || buf[0] != CTRL_STATE_MAGIC || buf[1] != (double)c->na) {
        cd_error_set(err, CD_EINVAL, "control: not a state of this controller (expected %d arm joints)", c->na);
        return CD_EINVAL;
    }
    c->t_trig = buf[2];
    c->t_hold = buf[3];
    c->t_det = buf[4];
    memcpy(c->q_hold, buf + 5, (size_t)c->na * sizeof(double));
    return CD_OK;
}

/* the held target's mass and its moment of inertia about the world axis a
 * through x, as if fixed to the palm: sum over its bodies of
 * a^T I_b a + m_b |a x (c_b - x)|^2 */
static double held_inertia(const cd_ctrl *c, const cd_model *m, const cd_data *d, const double a[3], const double x[3],
                           double *mass)
{
    int b, b1 = m->sys_body_adr[c->tsys], b2 = b1 + m->sys_nbody[c->tsys];
    double J = 0;
    *mass = 0;
    for (b = b1; b < b2; b++) {
        double ab[3], Ia[3], r[3], t[3];
        cd_m3_tmulv(ab, d->body_R + 9 * b, a); /* the axis in the body frame */
        cd_m3_mulv(Ia, m->body_inertia + 9 * b, ab);
        cd_v3_sub(r, d->body_c + 3 * b, x);
        cd_v3_cross(t, a, r);
        J += cd_v3_dot(ab, Ia) + m->body_mass[b] * cd_v3_dot(t, t);
        *mass += m->body_mass[b];
    }
    return J;
}

/* a frame (pos, rot) fixed on a body, world */
static void frame_on(const cd_data *d, int b, const double p[3], const double R[9], double x[3], double Rw[9])
{
    double t[3];
    cd_m3_mulv(t, d->body_R + 9 * b, p);
    cd_v3_add(x, d->body_x + 3 * b, t);
    cd_m3_mul(Rw, d->body_R + 9 * b, R);
}

/* 1/2 sum_i a_i x b_i over the columns: the small rotation that turns A toward B */
static void rot_error(double e[3], const double A[9], const double B[9])
{
    int i;
    cd_v3_zero(e);
    for (i = 0; i < 3; i++) {
        double a[3] = {A[i], A[3 + i], A[6 + i]}, b[3] = {B[i], B[3 + i], B[6 + i]}, x[3];
        cd_v3_cross(x, a, b);
        cd_v3_axpy(e, 0.5, x);
    }
}

static void clamp_norm(double v[3], double lim)
{
    double n = cd_v3_norm(v);
    if (n > lim) cd_v3_scale(v, v, lim / n);
}

static double clamp(double v, double lim)
{
    if (lim <= 0) return v;
    return v > lim ? lim : v < -lim ? -lim : v;
}

/* the fixture centre and the palm's grasp point, world */
static void grasp_points(const cd_ctrl *c, const cd_data *d, double xf[3], double Rf[9], double xp[3], double Rp[9],
                         double xg[3])
{
    double t[3];
    frame_on(d, c->c.fixture_body, c->c.fixture_pos, c->c.fixture_rot, xf, Rf);
    frame_on(d, c->c.palm, c->c.palm_pos, c->c.palm_rot, xp, Rp);
    cd_m3_mulv(t, Rp, c->c.grasp_point);
    cd_v3_add(xg, xp, t);
}

/* approach: the commanded palm twist (world) */
static void approach_twist(const cd_ctrl *c, const cd_data *d, double V[6])
{
    const cd_ctrl_config *k = &c->c;
    double xf[3], Rf[9], xp[3], Rp[9], xg[3], Rd[9], xd[3], t[3], ep[3], eR[3], aw[3], lat[3], along, s;
    const double *wf = d->body_w + 3 * k->fixture_body;
    grasp_points(c, d, xf, Rf, xp, Rp, xg);
    /* desired palm frame: the fixture centre at the grasp point */
    cd_m3_mul(Rd, Rf, k->grasp_rot);
    cd_m3_mulv(t, Rd, k->grasp_point);
    cd_v3_sub(xd, xf, t);
    /* its velocity, moving with the fixture's body */
    cd_v3_sub(t, xd, d->body_c + 3 * k->fixture_body);
    cd_v3_cross(V, wf, t);
    cd_v3_add(V, V, d->body_v + 3 * k->fixture_body);
    cd_v3_copy(V + 3, wf);
    /* pose error; the pre-grasp: the approach along the finger axis waits for the lateral error */
    cd_v3_sub(ep, xd, xp);
    cd_m3_mulv(aw, Rp, k->approach_axis);
    along = cd_v3_dot(ep, aw);
    cd_v3_copy(lat, ep);
    cd_v3_axpy(lat, -along, aw);
    s = cd_v3_norm(lat) / k->lateral_tol;
    s = 1.0 / (1.0 + s * s);
    cd_v3_copy(ep, lat);
    cd_v3_axpy(ep, s * along, aw);
    cd_v3_scale(ep, ep, k->kp_pos);
    clamp_norm(ep, k->v_max);
    rot_error(eR, Rp, Rd);
    cd_v3_scale(eR, eR, k->kp_rot);
    clamp_norm(eR, k->w_max);
    cd_v3_add(V, V, ep);
    cd_v3_add(V + 3, V + 3, eR);
}

/* DETUMBLE: the palm's damping wrench against its twist relative to the base, tau = J^T W */
static void detumble_torques(const cd_ctrl *c, const cd_model *m, cd_data *d, double *tau)
{
    const cd_ctrl_config *k = &c->c;
    double xf[3], Rf[9], xp[3], Rp[9], xg[3], V[6] = {0, 0, 0, 0, 0, 0}, W[6] = {0, 0, 0, 0, 0, 0}, S[MAXJ][6], big = 0;
    int i, a;
    grasp_points(c, d, xf, Rf, xp, Rp, xg);
    for (a = 0; a < c->na; a++) {
        int b = c->arm[a];
        const double *ax = d->body_axisw + 3 * b;
        double r[3], qd = cd_joint_qd(m, d, b);
        if (m->body_jnt_type[b] == CD_JOINT_PRISMATIC) {
            cd_v3_copy(S[a], ax);
            cd_v3_zero(S[a] + 3);
        } else {
            cd_v3_sub(r, xg, d->body_x + 3 * b);
            cd_v3_cross(S[a], ax, r);
            cd_v3_copy(S[a] + 3, ax);
        }
        for (i = 0; i < 6; i++) V[i] += S[a][i] * qd;
    }
    for (i = 0; i < 3; i++) { /* per palm axis e_i (column i of Rp) */
        double e[3] = {Rp[i], Rp[3 + i], Rp[6 + i]}, mt, Jt = held_inertia(c, m, d, e, xg, &mt);
        double wf = -clamp(k->detumble_gain * mt * cd_v3_dot(e, V), k->detumble_f_max);
        double wn = -clamp(k->detumble_gain * Jt * cd_v3_dot(e, V + 3), k->detumble_n_max[i]);
        cd_v3_axpy(W, wf, e);
        cd_v3_axpy(W + 3, wn, e);
    }
    for (a = 0; a < c->na; a++) {
        tau[a] = 0;
        for (i = 0; i < 6; i++) tau[a] += S[a][i] * W[i];
        if (fabs(tau[a]) > big) big = fabs(tau[a]);
    }
    if (k->tau_max > 0 && big > k->tau_max) /* scaled as a whole: tau . qd keeps its sign */
        for (a = 0; a < c->na; a++) tau[a] *= k->tau_max / big;
}

void cd_ctrl_control(const cd_model *m, cd_data *d, void *user)
{
    cd_ctrl *c = (cd_ctrl *)user;
    const cd_ctrl_config *k = &c->c;
    int i, j, phase = cd_ctrl_phase_of(c, d), b0 = m->sys_body_adr[k->sys], n = m->sys_ndof[k->sys];
    double tau[MAXJ];
    if (phase == CD_CTRL_DETUMBLE) {
        detumble_torques(c, m, d, tau);
    } else if (phase == CD_CTRL_HOLD) {
        cd_mass_matrix_cols(m, d, k->sys, d->H, c->arm_col, c->na); /* only the arm's diagonal is read */
        for (i = 0; i < c->na; i++) {
            int col = 6 + c->arm_col[i];
            double Hjj = d->H[col * n + col];
            tau[i] = Hjj * (k->imp_wn * k->imp_wn * (c->q_hold[i] - cd_joint_q(m, d, c->arm[i])) -
                            2.0 * k->imp_zeta * k->imp_wn * cd_joint_qd(m, d, c->arm[i]));
        }
    } else {
        double V[6], M[36], y[6], qd_ref[MAXJ], big = 0;
        approach_twist(c, d, V);
        /* the arm's columns only: the rest of J_g is not read */
        if (cd_generalized_jacobian_cols(m, d, k->palm, k->palm_pos, c->Jg, c->arm_col, c->na) != CD_OK) {
            for (i = 0; i < c->na; i++) tau[i] = 0.0;
        } else {
            /* damped least squares over the arm's columns of J_g */
            for (i = 0; i < 6; i++)
                for (j = 0; j < 6; j++) {
                    double s = i == j ? k->dls * k->dls : 0.0;
                    int a;
                    for (a = 0; a < c->na; a++) {
                        int col = c->arm_col[a];
                        s += c->Jg[i * c->nj + col] * c->Jg[j * c->nj + col];
                    }
                    M[6 * i + j] = s;
                }
            memcpy(y, V, sizeof y);
            if (cd_chol_decomp(M, 6) != 0) memset(y, 0, sizeof y);
            else cd_chol_solve(M, 6, y);
            for (i = 0; i < c->na; i++) {
                int col = c->arm_col[i];
                double s = 0;
                for (j = 0; j < 6; j++) s += c->Jg[j * c->nj + col] * y[j];
                qd_ref[i] = s;
                if (fabs(s) > big) big = fabs(s);
            }
            /* (d->H holds the arm's diagonal of the chaser's mass matrix, left by
             * cd_generalized_jacobian_cols) */
            for (i = 0; i < c->na; i++) {
                int col = 6 + c->arm_col[i];
                if (big > k->qd_max) qd_ref[i] *= k->qd_max / big;
                tau[i] = d->H[col * n + col] * k->rate_gain * (qd_ref[i] - cd_joint_qd(m, d, c->arm[i]));
            }
        }
    }
    for (i = 0; i < c->na; i++) d->qfrc_applied[m->body_dof[c->arm[i]]] = clamp(tau[i], k->tau_max);
    for (i = 0; i < k->nclose; i++) d->ctrl[k->close_act[i]] = phase == CD_CTRL_APPROACH ? 0.0 : k->close_u[i];
    for (i = 0; i < k->nclose_finger; i++) d->finger_t0[k->close_finger[i]] = phase == CD_CTRL_APPROACH ? HUGE_VAL : c->t_trig;
    if (k->attitude) {
        double e[3], n[3];
        const double *w0 = d->body_w + 3 * b0;
        double kp = phase == CD_CTRL_DETUMBLE && k->detumble_base ? 0.0 : k->att_kp;
        rot_error(e, d->body_R + 9 * b0, c->R0);
        for (i = 0; i < 3; i++) n[i] = clamp(kp * e[i] - k->att_kd * w0[i], k->att_tau_max);
        for (i = 0; i < 3; i++) d->xfrc_applied[6 * b0 + i] = n[i];
    }
}

double cd_ctrl_switch(const cd_model *m, const cd_data *d, int i, void *user)
{
    const cd_ctrl *c = (const cd_ctrl *)user;
    int s = c->c.user_switch0;
    (void)m;
    if (i == s + 2 && c->c.detumble && d->user_mode[s + 2] == 0 && cd_ctrl_phase_of(c, d) == CD_CTRL_HOLD)
        return c->t_hold + c->c.detumble_after - d->t;
    if (c->c.start_hold) return 1.0;
    if (i == s && d->user_mode[s] == 0) {
        double xf[3], Rf[9], xp[3], Rp[9], xg[3], r[3];
        grasp_points(c, d, xf, Rf, xp, Rp, xg);
        cd_v3_sub(r, xf, xg);
        return cd_v3_norm(r) - c->c.trigger_distance;
    }
    if (i == s + 1 && d->user_mode[s] == 1 && d->user_mode[s + 1] == 0) return c->t_trig + c->c.close_time - d->t;
    return 1.0;
}

int cd_ctrl_transition(const cd_model *m, cd_data *d, int i, void *user)
{
    cd_ctrl *c = (cd_ctrl *)user;
    int s = c->c.user_switch0, a;
    if (i == s) {
        c->t_trig = d->t;
        return 1;
    }
    if (i == s + 1) {
        c->t_hold = d->t;
        for (a = 0; a < c->na; a++) c->q_hold[a] = cd_joint_q(m, d, c->arm[a]);
        return 1;
    }
    if (i == s + 2) {
        c->t_det = d->t;
        return 1;
    }
    return d->user_mode[i];
}

double cd_ctrl_base_angle(const cd_ctrl *c, const cd_model *m, const cd_data *d)
{
    if (!c || !m || !d) return NAN;
    const double *R = d->body_R + 9 * m->sys_body_adr[c->c.sys];
    double tr = 0;
    int i, j;
    /* angle of R0^T R: cos = (trace - 1) / 2 */
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) tr += c->R0[3 * j + i] * R[3 * j + i];
    tr = 0.5 * (tr - 1.0);
    if (tr > 1) tr = 1;
    if (tr < -1) tr = -1;
    return acos(tr);
}

void cd_ctrl_merit_init(cd_ctrl_merit *f, const cd_ctrl *c, const cd_model *m, const cd_data *d)
{
    memset(f, 0, sizeof *f);
    f->target = m->body_sys[c->c.fixture_body];
    cd_momentum(m, d, c->c.sys, NULL, f->P0, NULL, f->L0, NULL);
    cd_ctrl_merit_update(f, c, m, d);
}

void cd_ctrl_merit_update(cd_ctrl_merit *f, const cd_ctrl *c, const cd_model *m, const cd_data *d)
{
    int b0 = m->sys_body_adr[c->c.sys], tb = m->sys_body_adr[f->target], i;
    double P[3], L[3], a = cd_ctrl_base_angle(c, m, d), r[3], v[3];
    cd_momentum(m, d, c->c.sys, NULL, P, NULL, L, NULL);
    cd_v3_sub(f->dP, P, f->P0);
    cd_v3_sub(f->dL, L, f->L0);
    if (a > f->base_angle_max) f->base_angle_max = a;
    f->base_rate = cd_v3_norm(d->body_w + 3 * b0);
    for (i = 0; i < c->na; i++) { /* the controller's arm torques (control: qfrc_applied) */
        double t = fabs(d->qfrc_applied[m->body_dof[c->arm[i]]]);
        if (t > f->tau_arm_max) f->tau_arm_max = t;
    }
    /* the target's CoM velocity against the base's rigid motion there */
    cd_v3_sub(r, d->body_c + 3 * tb, d->body_c + 3 * b0);
    cd_v3_cross(v, d->body_w + 3 * b0, r);
    cd_v3_add(v, v, d->body_v + 3 * b0);
    cd_v3_sub(v, d->body_v + 3 * tb, v);
    f->v_rel = cd_v3_norm(v);
    cd_v3_sub(v, d->body_w + 3 * tb, d->body_w + 3 * b0);
    f->w_rel = cd_v3_norm(v);
}
