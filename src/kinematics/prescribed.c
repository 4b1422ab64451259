/* Prescribed motion: joints and bases that follow a given profile exactly
 * (a belt, a test rig, a docking probe). The profile sets the coordinate,
 * its rate and its acceleration; forward dynamics takes the acceleration as
 * given and reports the generalized force it took (qfrc_constraint). */
#include "capdyn/sim.h"
#include "../math/cd_math.h"
#include "prescribed.h"

#include <string.h>

/* ---- prescribed motion ----------------------------------------------------- */

/* minimum-jerk blend s(x) = 10x^3 - 15x^4 + 6x^5 on [0, 1] and its derivatives */
static void minjerk(double x, double *s, double *ds, double *dds)
{
    double x2 = x * x, x3 = x2 * x;
    *s = x3 * (10.0 - 15.0 * x + 6.0 * x2);
    *ds = 30.0 * x2 * (1.0 - 2.0 * x + x2);
    *dds = 60.0 * x * (1.0 - 3.0 * x + 2.0 * x2);
}

void cd_prescribed_joint(const cd_model *m, int b, double t, double *q, double *qd, double *qdd)
{
    *q = m->body_q0[b];
    *qd = *qdd = 0.0;
    if (m->body_presc[b] == CD_PRESCRIBE_VELOCITY) {
        double v = m->body_presc_prm[6 * b], t0 = m->body_presc_prm[6 * b + 1];
        if (t > t0) {
            *q += v * (t - t0);
            *qd = v;
        }
    } else if (m->body_presc[b] == CD_PRESCRIBE_WAYPOINTS) {
        const double *tt = m->tbl_t + m->body_wp_adr[b], *qq = m->tbl_v + m->body_wp_adr[b];
        int n = m->body_wp_n[b], lo = cd_count_le(tt, n, t); /* the waypoint ahead */
        double q0, q1, t0, t1, s, ds, dds;
        /* before the first waypoint: from the initial position, starting at t = 0 */
        if (lo >= n) { *q = qq[n - 1]; return; }
        if (lo == 0) {
            q0 = m->body_q0[b]; t0 = 0.0;
            if (!(tt[0] > 0)) { *q = qq[0]; return; }
        } else {
            q0 = qq[lo - 1]; t0 = tt[lo - 1];
        }
        q1 = qq[lo]; t1 = tt[lo];
        if (t <= t0) { *q = q0; return; }
        minjerk((t - t0) / (t1 - t0), &s, &ds, &dds);
        *q = q0 + (q1 - q0) * s;
        *qd = (q1 - q0) * ds / (t1 - t0);
        *qdd = (q1 - q0) * dds / ((t1 - t0) * (t1 - t0));
    }
}

void cd_prescribed_apply(const cd_model *m, double t, double *y)
{
    int s, b;
    for (s = 0; s < m->nsys; s++) {
        int b0 = m->sys_body_adr[s], a = m->sys_y_adr[s], nj = m->sys_nbody[s] - 1;
        int free_base = m->sys_base_type[s] == CD_BASE_FREE;
        int qa = a + (free_base ? 7 : 0), va = qa + nj + (free_base ? 6 : 0);
        if (free_base && m->body_presc[b0] != CD_PRESCRIBE_NONE) {
            const double *v = m->body_presc_prm + 6 * b0, *w = v + 3;
            double R0[9], Rw[9], R[9], ax[3], wn = cd_v3_norm(w);
            cd_v3_copy(y + a, m->sys_pos0 + 3 * s);
            cd_v3_axpy(y + a, t, v);
            cd_quat_to_m3(R0, m->sys_quat0 + 4 * s);
            if (wn > 0) {
                cd_v3_scale(ax, w, 1.0 / wn);
                cd_m3_axis_angle(Rw, ax, wn * t);
                double qn[4], *qy = y + a + 3;
                int k;
                cd_m3_mul(R, Rw, R0);
                cd_m3_to_quat(qn, R);
                /* the sign that continues the stored quaternion */
                if (qn[0] * qy[0] + qn[1] * qy[1] + qn[2] * qy[2] + qn[3] * qy[3] < 0)
                    for (k = 0; k < 4; k++) qn[k] = -qn[k];
                memcpy(qy, qn, sizeof qn);
            } else {
                memcpy(y + a + 3, m->sys_quat0 + 4 * s, 4 * sizeof(double));
            }
            cd_v3_copy(y + qa + nj, v);
            cd_v3_copy(y + qa + nj + 3, w);
        }
        for (b = b0 + 1; b < b0 + m->sys_nbody[s]; b++)
            if (m->body_presc[b] != CD_PRESCRIBE_NONE) {
                double qdd;
                cd_prescribed_joint(m, b, t, y + qa + (b - b0 - 1), y + va + (b - b0 - 1), &qdd);
            }
    }
}
