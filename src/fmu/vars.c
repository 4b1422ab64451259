/* The variables of a capdyn FMU (vars.h, docs/fmu.md). */
#include "vars.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    cdf_var *v;
    int n, cap;
} vlist;

static cdf_var *add(vlist *l, int causality, int type, int what, int a)
{
    cdf_var *v;
    if (l->n == l->cap) {
        int cap = l->cap ? 2 * l->cap : 64;
        cdf_var *nv = (cdf_var *)realloc(l->v, (size_t)cap * sizeof *nv);
        if (!nv) return NULL;
        l->v = nv;
        l->cap = cap;
    }
    v = &l->v[l->n++];
    memset(v, 0, sizeof *v);
    v->causality = causality;
    v->type = type;
    v->what = what;
    v->a = a;
    return v;
}

/* a body on the [control] arm: the chain from the palm up to the base */
static int on_arm(const cd_model *m, const cd_ctrl_config *c, int body)
{
    int b;
    if (!c) return 0;
    for (b = c->palm; b >= 0 && m->body_parent[b] >= 0; b = m->body_parent[b])
        if (b == body) return 1;
    return 0;
}

static int closed_by_ctrl(const cd_ctrl_config *c, int act)
{
    int i;
    if (!c) return 0;
    for (i = 0; i < c->nclose; i++)
        if (c->close_act[i] == act) return 1;
    return 0;
}

cd_status cdf_vars_build(const cd_scenario *sc, const cd_data *d, cdf_var **vars, int *n, cd_error *err)
{
    static const char *const base_out[13] = {"x", "y", "z", "qw", "qx", "qy", "qz", "vx", "vy", "vz", "wx", "wy", "wz"};
    static const char *const base_desc[13] = {
        "base CoM position x, world [m]", "base CoM position y, world [m]", "base CoM position z, world [m]",
        "base attitude quaternion w (body to world)", "base attitude quaternion x", "base attitude quaternion y",
        "base attitude quaternion z", "base CoM velocity x, world [m/s]", "base CoM velocity y, world [m/s]",
        "base CoM velocity z, world [m/s]", "base angular velocity x, world [rad/s]",
        "base angular velocity y, world [rad/s]", "base angular velocity z, world [rad/s]"};
    static const char *const wrench[6] = {"torque_x", "torque_y", "torque_z", "force_x", "force_y", "force_z"};
    const cd_model *m = sc->model;
    const cd_ctrl_config *c = sc->control;
    vlist l = {NULL, 0, 0};
    cdf_var *v;
    int s, b, k, u;
    *vars = NULL;
    *n = 0;
    /* outputs: every system's state */
    for (s = 0; s < m->nsys; s++) {
        cd_sys_state st = cd_state_of(m, d, s);
        int b0 = m->sys_body_adr[s], nj = m->sys_nbody[s] - 1;
        if (st.pos) {
            const double *at[13];
            for (k = 0; k < 3; k++) {
                at[k] = st.pos + k;
                at[7 + k] = st.vel + k;
                at[10 + k] = st.angvel + k;
            }
            for (k = 0; k < 4; k++) at[3 + k] = st.quat + k;
            for (k = 0; k < 13; k++) {
                if (!(v = add(&l, CDF_OUTPUT, CDF_REAL, CDF_Y, (int)(at[k] - d->y)))) goto oom;
                snprintf(v->name, sizeof v->name, "%s.base.%s", m->sys_name[s], base_out[k]);
                snprintf(v->desc, sizeof v->desc, "%s of %s", base_desc[k], m->sys_name[s]);
            }
        }
        for (b = b0 + 1; b < b0 + 1 + nj; b++) {
            int j = b - b0 - 1, yq = (int)(st.q + j - d->y), yqd = (int)(st.qd + j - d->y);
            if (!(v = add(&l, CDF_OUTPUT, CDF_REAL, CDF_Y, yq))) goto oom;
            snprintf(v->name, sizeof v->name, "%s.%s.q", m->sys_name[s], m->body_name[b]);
            snprintf(v->desc, sizeof v->desc, "joint position of %s/%s [rad | m]", m->sys_name[s], m->body_name[b]);
            if (!(v = add(&l, CDF_OUTPUT, CDF_REAL, CDF_Y, yqd))) goto oom;
            snprintf(v->name, sizeof v->name, "%s.%s.qd", m->sys_name[s], m->body_name[b]);
            snprintf(v->desc, sizeof v->desc, "joint rate of %s/%s [rad/s | m/s]", m->sys_name[s], m->body_name[b]);
        }
    }
    /* outputs: the object's contacts and the capture verdict */
    if (sc->capture_object >= 0) {
        if (!(v = add(&l, CDF_OUTPUT, CDF_REAL, CDF_FN_OBJECT, sc->capture_object))) goto oom;
        snprintf(v->name, sizeof v->name, "contact.fn_total");
        snprintf(v->desc, sizeof v->desc, "sum of the normal forces of the contacts on %s [N]", m->sys_name[sc->capture_object]);
        if (!(v = add(&l, CDF_OUTPUT, CDF_INTEGER, CDF_N_STICK, sc->capture_object))) goto oom;
        snprintf(v->name, sizeof v->name, "contact.n_stick");
        snprintf(v->desc, sizeof v->desc, "contacts on %s sticking", m->sys_name[sc->capture_object]);
        if (!(v = add(&l, CDF_OUTPUT, CDF_INTEGER, CDF_N_SLIP, sc->capture_object))) goto oom;
        snprintf(v->name, sizeof v->name, "contact.n_slip");
        snprintf(v->desc, sizeof v->desc, "contacts on %s slipping", m->sys_name[sc->capture_object]);
    }
    if (sc->capture_hand >= 0 && sc->capture_object >= 0) {
        if (!(v = add(&l, CDF_OUTPUT, CDF_INTEGER, CDF_VERDICT, 0))) goto oom;
        snprintf(v->name, sizeof v->name, "capture.verdict");
        snprintf(v->desc, sizeof v->desc,
                 "capture verdict, cd_verdict values: 0 unresolved, 1 captured, 2 escaped, 3 caged");
        if (!(v = add(&l, CDF_OUTPUT, CDF_REAL, CDF_VERDICT_T, 0))) goto oom;
        snprintf(v->name, sizeof v->name, "capture.time");
        snprintf(v->desc, sizeof v->desc, "time of the verdict [s], -1 while unresolved");
    }
    /* inputs: joint torques, base wrenches, actuator commands */
    for (s = 0; s < m->nsys; s++) {
        int b0 = m->sys_body_adr[s], nj = m->sys_nbody[s] - 1;
        for (b = b0 + 1; b < b0 + 1 + nj; b++) {
            if (on_arm(m, c, b)) continue;
            if (!(v = add(&l, CDF_INPUT, CDF_REAL, CDF_IN_QFRC, m->body_dof[b]))) goto oom;
            snprintf(v->name, sizeof v->name, "%s.%s.tau", m->sys_name[s], m->body_name[b]);
            snprintf(v->desc, sizeof v->desc, "joint torque (force) command on %s/%s [N m | N]", m->sys_name[s], m->body_name[b]);
        }
        if (m->sys_base_type[s] != CD_BASE_FREE) continue;
        for (k = 0; k < 6; k++) {
            if (k < 3 && c && c->attitude && c->sys == s) continue;
            if (!(v = add(&l, CDF_INPUT, CDF_REAL, CDF_IN_XFRC, 6 * b0 + k))) goto oom;
            snprintf(v->name, sizeof v->name, "%s.base.%s", m->sys_name[s], wrench[k]);
            snprintf(v->desc, sizeof v->desc, "%s on the base of %s, world axes, at its CoM [%s]", wrench[k],
                     m->sys_name[s], k < 3 ? "N m" : "N");
        }
    }
    for (u = 0; u < m->nu; u++) {
        if (closed_by_ctrl(c, u)) continue;
        if (!(v = add(&l, CDF_INPUT, CDF_REAL, CDF_IN_CTRL, u))) goto oom;
        snprintf(v->name, sizeof v->name, "%s.ctrl", m->act_name[u]);
        snprintf(v->desc, sizeof v->desc, "command of actuator %s, added to its law [N m | N]", m->act_name[u]);
    }
    *vars = l.v;
    *n = l.n;
    return CD_OK;
oom:
    free(l.v);
    cd_error_set(err, CD_ENOMEM, "out of memory");
    return CD_ENOMEM;
}
