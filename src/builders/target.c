/* Shapes (with the generated handrail) and rigid targets on the model
 * builder (include/capdyn/build.h). The handrail generator moved here from
 * the scenario loader, which fills a cd_shape_desc per `shape` table. */
#include "capdyn/build.h"
#include "../math/cd_math.h"

#include <math.h>
#include <string.h>

cd_shape_desc cd_shape_desc_default(void)
{
    cd_shape_desc s;
    memset(&s, 0, sizeof s);
    s.type = CD_SHAPE_SPHERE;
    cd_m3_identity(s.rot);
    s.radius = 0.05;
    s.length = 0.1;
    s.size[0] = s.size[1] = s.size[2] = 0.1;
    s.height = 0.05;
    return s;
}

int cd_shape_desc_count(const cd_shape_desc *s) { return s && s->type == CD_SHAPE_HANDRAIL ? 3 : 1; }

/* A handrail fixture (ISS-era EVA handrail): a round bar of radius r and
 * length L along the shape's x axis, h above its base plane z = 0, on two
 * square posts of side w at its ends: a capsule and two boxes. */
static int build_handrail(cd_model *m, int body, const cd_shape_desc *s, cd_error *err)
{
    struct part { cd_shape_type type; double p[3]; double rpy[3]; double sz[3]; };
    double r = s->radius, L = s->length, h = s->height, w = s->post > 0 ? s->post : 2 * r;
    struct part parts[3];
    int i, first = -1;
    if (!(r > 0) || !(L > 0) || !(h > 0) || !isfinite(r) || !isfinite(L) || !isfinite(h) || !(w > 0) || !isfinite(w)) {
        cd_error_set(err, CD_EINVAL, "handrail: radius, length, height and post must be finite and > 0");
        return -1;
    }
    if (!(L > 2 * w)) {
        cd_error_set(err, CD_EINVAL, "handrail: length %g m must exceed its two posts (%g m)", L, 2 * w);
        return -1;
    }
    if (!(h > r)) {
        cd_error_set(err, CD_EINVAL, "handrail: the bar's height %g m must exceed its radius %g m", h, r);
        return -1;
    }
    memset(parts, 0, sizeof parts);
    parts[0].type = CD_SHAPE_CAPSULE;
    parts[0].p[2] = h;
    parts[0].rpy[1] = CD_PI / 2;
    parts[0].sz[0] = r; parts[0].sz[1] = L / 2 - r;
    for (i = 1; i < 3; i++) {
        parts[i].type = CD_SHAPE_BOX;
        parts[i].p[0] = i == 1 ? -(L / 2 - w / 2) : L / 2 - w / 2;
        parts[i].p[2] = h / 2;
        parts[i].sz[0] = w / 2; parts[i].sz[1] = w / 2; parts[i].sz[2] = h / 2;
    }
    for (i = 0; i < 3; i++) {
        double Rl[9], Rw[9], pw[3];
        int id;
        cd_m3_from_rpy(Rl, parts[i].rpy[0], parts[i].rpy[1], parts[i].rpy[2]);
        cd_m3_mul(Rw, s->rot, Rl);
        cd_m3_mulv(pw, s->rot, parts[i].p);
        cd_v3_add(pw, pw, s->pos);
        id = cd_model_add_shape(m, body, parts[i].type, pw, Rw, parts[i].sz, NULL, 0, err);
        if (id < 0) return -1;
        if (i == 0) first = id;
    }
    return first;
}

int cd_build_shape(cd_model *m, int body, const cd_shape_desc *s, cd_error *err)
{
    double sz[3] = {0, 0, 0};
    if (!m || !s) { cd_error_set(err, CD_EINVAL, "shape: model or description is NULL"); return -1; }
    if (s->type == CD_SHAPE_HANDRAIL) return build_handrail(m, body, s, err);
    switch (s->type) {
    case CD_SHAPE_PLANE: break;
    case CD_SHAPE_SPHERE: sz[0] = s->radius; break;
    case CD_SHAPE_BOX:
        sz[0] = s->size[0] * 0.5;
        sz[1] = s->size[1] * 0.5;
        sz[2] = s->size[2] * 0.5;
        break;
    case CD_SHAPE_CYLINDER: case CD_SHAPE_CAPSULE:
        sz[0] = s->radius;
        sz[1] = 0.5 * s->length;
        break;
    case CD_SHAPE_CONVEX: break;
    default: cd_error_set(err, CD_EINVAL, "shape: unknown type %d", s->type); return -1;
    }
    return cd_model_add_shape(m, body, (cd_shape_type)s->type, s->pos, s->rot, sz, s->type == CD_SHAPE_CONVEX ? s->verts : NULL,
                              s->type == CD_SHAPE_CONVEX ? s->nvert : 0, err);
}

cd_target_desc cd_target_desc_default(void)
{
    cd_target_desc t;
    memset(&t, 0, sizeof t);
    t.name = "target";
    t.mass = 1.0;
    t.inertia[0] = t.inertia[4] = t.inertia[8] = 1.0;
    t.quat[0] = 1.0;
    return t;
}

int cd_build_target(cd_model *m, const cd_target_desc *t, cd_error *err)
{
    cd_system_desc d = cd_system_desc_default();
    int sys, b0, i;
    if (!m || !t || (t->nshape > 0 && !t->shapes) || t->nshape < 0) {
        cd_error_set(err, CD_EINVAL, "target: model, description or shapes are NULL");
        return -1;
    }
    d.name = t->name;
    d.type = t->fixed ? CD_BASE_FIXED : CD_BASE_FREE;
    d.mass = t->mass;
    memcpy(d.inertia, t->inertia, sizeof d.inertia);
    cd_v3_copy(d.pos, t->pos);
    memcpy(d.quat, t->quat, sizeof d.quat);
    if (!t->fixed) {
        cd_v3_copy(d.vel, t->vel);
        cd_v3_copy(d.angvel, t->angvel);
    }
    sys = cd_model_add_system(m, &d, err);
    if (sys < 0) return -1;
    if (t->prescribed && cd_model_prescribe_base(m, sys, t->vel, t->angvel, err) != CD_OK) return -1;
    b0 = m->sys_body_adr[sys];
    for (i = 0; i < t->nshape; i++)
        if (cd_build_shape(m, b0, &t->shapes[i], err) < 0) return -1;
    return sys;
}

/* steps per radian of a tumbling box at rtol = 1e-9, and the exponent k of
 * their tolerance scaling (the stepper's order + 1, roughly), measured with
 * `capdyn run` on a free box of inertia (100, 150, 200) kg m^2 at
 * w = (1e3, 1, 1e3) and (1e4, 1, 1e4) rad/s for 0.2 s (stats_nsteps), and at
 * rtol = 1e-6: docs/embedding.md, "Tumbling rate" */
static int spin_cost(cd_stepper st, double *c, double *k)
{
    switch (st) {
    case CD_STEP_RK8PD: case CD_STEP_AUTO: *c = 2.6; *k = 8; return 1; /* auto: rk8pd while not stiff */
    case CD_STEP_RKCK: *c = 15; *k = 5; return 1;
    case CD_STEP_RKF45: *c = 22; *k = 5; return 1;
    case CD_STEP_RK4IMP: *c = 14.5; *k = 5; return 1; /* capdyn's Gauss stepper (2026-11-27) */
    case CD_STEP_MSBDF: *c = 29; *k = 6; return 1;    /* capdyn's BDF, its step clipped to its growth limit (2026-11-28) */
    case CD_STEP_ROS34PW2: *c = 635; *k = 3; return 1;
    default: return 0; /* fixed steps */
    }
}

int cd_spin_steps(const cd_model *m, double duration, double *rate, double *steps)
{
    double c, k, w = 0, rt;
    int s, best = -1;
    if (rate) *rate = 0;
    if (steps) *steps = 0;
    if (!m || !spin_cost(m->opt.stepper, &c, &k)) return -1;
    for (s = 0; s < m->nsys; s++) {
        double ws;
        if (m->sys_base_type[s] != CD_BASE_FREE) continue;
        ws = cd_v3_norm(m->sys_angvel0 + 3 * s);
        if (ws > w) { w = ws; best = s; }
    }
    if (best < 0) return -1;
    rt = m->opt.rtol > 0 ? m->opt.rtol : m->opt.atol > 0 ? m->opt.atol : 1e-9; /* rtol 0: atol rules */
    if (rate) *rate = w;
    if (steps) *steps = c * pow(1e-9 / rt, 1.0 / k) * w * (duration > 0 ? duration : 0);
    return best;
}
