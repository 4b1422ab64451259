/* A chaser on the model builder (include/capdyn/build.h): base, its shapes,
 * an arm, and the reaction wheels of the capture controller. The same model
 * as the scenario loader's [[system]] table with [[system.shape]] and
 * [[system.link]] (tests/test_build.c). */
#include "capdyn/build.h"

#include <string.h>

cd_chaser_desc cd_chaser_desc_default(void)
{
    cd_chaser_desc c;
    cd_ctrl_config k = cd_ctrl_config_default();
    memset(&c, 0, sizeof c);
    c.name = "chaser";
    c.mass = 1.0;
    c.inertia[0] = c.inertia[4] = c.inertia[8] = 1.0;
    c.quat[0] = 1.0;
    c.wheel_kp = k.att_kp;
    c.wheel_kd = k.att_kd;
    c.wheel_torque = k.att_tau_max;
    return c;
}

int cd_build_chaser(cd_model *m, const cd_chaser_desc *c, cd_error *err)
{
    cd_target_desc base = cd_target_desc_default();
    int sys, b0, i;
    if (!m || !c || c->narm < 0 || (c->narm > 0 && !c->arm)) {
        cd_error_set(err, CD_EINVAL, "chaser: model, description or arm is NULL");
        return -1;
    }
    base.name = c->name;
    base.fixed = c->fixed;
    base.mass = c->mass;
    memcpy(base.inertia, c->inertia, sizeof base.inertia);
    memcpy(base.pos, c->pos, sizeof base.pos);
    memcpy(base.quat, c->quat, sizeof base.quat);
    memcpy(base.vel, c->vel, sizeof base.vel);
    memcpy(base.angvel, c->angvel, sizeof base.angvel);
    base.shapes = c->shapes;
    base.nshape = c->nshape;
    sys = cd_build_target(m, &base, err);
    if (sys < 0) return -1;
    b0 = m->sys_body_adr[sys];
    for (i = 0; i < c->narm; i++) {
        cd_link_desc l = c->arm[i];
        int id;
        if (l.parent < -1 || l.parent >= i) {
            cd_error_set(err, CD_EINVAL, "chaser: arm link %d: parent %d must be -1 (the base) or an earlier link", i, l.parent);
            return -1;
        }
        l.parent = l.parent < 0 ? b0 : b0 + 1 + l.parent;
        id = cd_model_add_link(m, sys, &l, err);
        if (id < 0) return -1;
        if (c->arm_joint && cd_model_set_joint(m, id, &c->arm_joint[i], err) != CD_OK) return -1;
    }
    return sys;
}

void cd_chaser_wheels(const cd_chaser_desc *c, int sys, cd_ctrl_config *cfg)
{
    if (!c || !cfg) return;
    cfg->sys = sys;
    cfg->attitude = c->wheels ? 1 : 0;
    cfg->att_kp = c->wheel_kp;
    cfg->att_kd = c->wheel_kd;
    cfg->att_tau_max = c->wheel_torque;
}
