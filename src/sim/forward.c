/* One right-hand-side evaluation (DESIGN.md): unpack -> kinematics ->
 * contacts -> actuation -> forward dynamics -> ydot. Allocates nothing. */
#include "capdyn/sim.h"
#include "../math/cd_math.h"
#include "../contact/contact.h"
#include "../mechanism/actuation.h"

#include <string.h>

cd_status cd_forward(const cd_model *m, cd_data *d)
{
    int i, s, b;
    cd_status st;
    for (i = 0; i < m->ny; i++)
        if (!isfinite(d->y[i])) return CD_ENUMERIC;
    cd_kinematics(m, d);
    /* user wrenches [torque about CoM; force at CoM] -> about the reference point */
    for (b = 0; b < m->nbody; b++) {
        const double *fu = d->body_fuser + 6 * b;
        double *fe = d->body_fext + 6 * b, arm[3];
        cd_v3_sub(arm, d->body_c + 3 * b, d->sys_ref + 3 * m->body_sys[b]);
        cd_v3_cross(fe, arm, fu + 3);
        cd_v3_add(fe, fe, fu);
        cd_v3_copy(fe + 3, fu + 3);
    }
    cd_contact_eval(m, d, d->ydot + m->ny_slot_adr);
    cd_actuation(m, d);
    st = cd_forward_dynamics(m, d);
    if (st != CD_OK) return st;
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
    for (i = 0; i < m->ny; i++)
        if (!isfinite(d->ydot[i])) return CD_ENUMERIC;
    return CD_OK;
}
