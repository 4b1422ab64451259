/* One right-hand-side evaluation (DESIGN.md): prescribed coordinates ->
 * kinematics -> control callback -> input wrenches -> contacts -> joint
 * elements -> actuation -> forward dynamics -> ydot. Allocates nothing. */
#include "capdyn/sim.h"
#include "../math/cd_math.h"
#include "../contact/contact.h"
#include "../mechanism/actuation.h"
#include "../kinematics/prescribed.h"

#include <string.h>

cd_status cd_forward(const cd_model *m, cd_data *d)
{
    if (!m || !d) return CD_EINVAL;
    int i, s, b;
    cd_status st = CD_OK;
    double *ysave = d->y;
    if (!cd_all_finite(d->y, m->ny)) return CD_ENUMERIC;
    if (m->npresc) {
        /* prescribed joints and bases follow their profile exactly */
        memcpy(d->ypresc, d->y, (size_t)m->ny * sizeof(double));
        cd_prescribed_apply(m, d->t, d->ypresc);
        d->y = d->ypresc;
    }
    cd_kinematics(m, d);
    if (d->control) d->control(m, d, d->control_user);
    /* input wrenches [torque about CoM; force at CoM] (world, and body axes
     * rotated to world) -> [moment about the reference point; force] */
    for (b = 0; b < m->nbody; b++) {
        const double *fu = d->xfrc_applied + 6 * b, *fb = d->xfrc_body + 6 * b, *R = d->body_R + 9 * b;
        double *fe = d->body_fext + 6 * b, arm[3], n[3], f[3], t[3];
        cd_m3_mulv(n, R, fb);
        cd_m3_mulv(f, R, fb + 3);
        cd_v3_add(n, n, fu);
        cd_v3_add(f, f, fu + 3);
        cd_v3_sub(arm, d->body_c + 3 * b, d->sys_ref + 3 * m->body_sys[b]);
        cd_v3_cross(t, arm, f);
        cd_v3_add(fe, n, t);
        cd_v3_copy(fe + 3, f);
    }
    cd_contact_eval(m, d, d->ydot + m->ny_slot_adr);
    cd_joint_passive(m, d, d->ydot + m->ny_fric_adr);
    cd_actuation(m, d);
    if (m->nfinger) cd_gripper_torques(m, d);
    for (i = 0; i < m->nv; i++) d->tau[i] = d->qfrc_actuator[i] + d->qfrc_passive[i] + d->qfrc_applied[i];
    st = cd_forward_dynamics(m, d);
    if (st == CD_OK) {
        /* ydot: per system [r0dot = v0, quatdot, qdot = qd | udot] */
        for (s = 0; s < m->nsys; s++) {
            cd_sys_state x = cd_state_of(m, d, s);
            int va = m->sys_v_adr[s], nj = x.njoint, ya = m->sys_y_adr[s], off = 0;
            double *yd = d->ydot + ya;
            if (x.pos) {
                cd_v3_copy(yd, x.vel);
                cd_quat_deriv_world(yd + 3, x.quat, x.angvel);
                off = 7;
            }
            for (i = 0; i < nj; i++) yd[off + i] = x.qd[i];
            for (i = 0; i < m->sys_ndof[s]; i++) yd[off + nj + i] = d->udot[va + i];
        }
        if (!cd_all_finite(d->ydot, m->ny)) st = CD_ENUMERIC;
    }
    d->y = ysave;
    return st;
}
