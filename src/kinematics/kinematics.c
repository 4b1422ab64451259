/* Kinematics: poses and velocities of every body from the state, and point
 * queries. Contact and mechanism use these; they never need dynamics. */
#include "capdyn/sim.h"
#include "../math/cd_math.h"
#include "kinematics.h"

#include <string.h>

void cd_kinematics(const cd_model *m, cd_data *d)
{
    if (!m || !d) return;
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
        /* every body's spatial inertia about P in world axes, once per
         * evaluation for the dynamics (ABA, CRBA, RNE, the controllers'
         * mass matrices) */
        for (b = b0; b < b0 + nb; b++) {
            double Iw[9], c[3];
            cd_m3_rotsym(Iw, d->body_R + 9 * b, m->body_inertia + 9 * b);
            cd_v3_sub(c, d->body_c + 3 * b, P);
            cd_rbi_make((cd_rbi *)d->body_rbi + b, m->body_mass[b], c, Iw);
        }
    }
}

void cd_point_world(const cd_model *m, const cd_data *d, int b, const double pb[3],
                    double pw[3], double vw[3])
{
    if (!m || !d || !pb) return;
    double t[3], p[3];
    (void)m;
    cd_body_point(d, b, pb, p);
    if (vw) {
        /* v = v_c + w x (p - c) */
        cd_v3_sub(t, p, d->body_c + 3 * b);
        cd_v3_cross(vw, d->body_w + 3 * b, t);
        cd_v3_add(vw, vw, d->body_v + 3 * b);
    }
    if (pw) cd_v3_copy(pw, p);
}

