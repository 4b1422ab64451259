/* Actuation: generalized forces from the joint actuators at time t.
 * This is the seam for gripper mechanisms (Soft Gripper torque split, TAKO's
 * single motor, the Space Gripper's synchronised closing and clutch): they
 * will read d (joint state, slot modes) and write d->tau here. */
#include "capdyn/sim.h"
#include "actuation.h"

#include <string.h>

static double table_value(const double *t, const double *v, int n, double x)
{
    int lo = 0, hi = n - 1;
    if (x <= t[0]) return v[0];
    if (x >= t[n - 1]) return v[n - 1];
    while (hi - lo > 1) { /* bisection: t strictly increasing */
        int mid = (lo + hi) / 2;
        if (t[mid] <= x) lo = mid; else hi = mid;
    }
    return v[lo] + (v[hi] - v[lo]) * (x - t[lo]) / (t[hi] - t[lo]);
}

void cd_actuation(const cd_model *m, cd_data *d)
{
    int b;
    memset(d->tau, 0, (size_t)m->nv * sizeof(double));
    for (b = 0; b < m->nbody; b++) {
        const double *a = m->body_act + 4 * b;
        double tau = 0;
        if (m->body_dof[b] < 0) continue;
        switch (m->body_act_type[b]) {
        case CD_ACT_CONSTANT: tau = a[0]; break;
        case CD_ACT_TABLE:
            tau = table_value(m->tbl_t + m->body_tbl_adr[b], m->tbl_v + m->body_tbl_adr[b],
                              m->body_tbl_n[b], d->t);
            break;
        case CD_ACT_PD:
            tau = a[0] + a[1] * (a[3] - cd_joint_q(m, d, b)) - a[2] * cd_joint_qd(m, d, b);
            break;
        default: break;
        }
        d->tau[m->body_dof[b]] = tau;
    }
}
