/* cd_model: builder, validation and layout. Allocation happens only here and
 * in cd_data_create; once finalized the model is never written again. */
#include "capdyn/model.h"
#include "../math/cd_math.h"

#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void cd_error_set(cd_error *err, cd_status st, const char *fmt, ...)
{
    va_list ap;
    if (!err) return;
    err->status = st;
    va_start(ap, fmt);
    vsnprintf(err->msg, sizeof err->msg, fmt, ap);
    va_end(ap);
}
#define seterr cd_error_set

const char *cd_status_string(cd_status s)
{
    switch (s) {
    case CD_OK: return "ok";
    case CD_EINVAL: return "invalid argument";
    case CD_ENOMEM: return "out of memory";
    case CD_ENUMERIC: return "numerical failure";
    case CD_ESTALL: return "integrator stalled";
    case CD_EMAXSTEPS: return "step budget exhausted";
    case CD_EIO: return "input/output error";
    case CD_EINTERRUPT: return "interrupted";
    }
    return "unknown status";
}

const char *cd_version(void) { return CD_VERSION_STRING; }

static const char *shape_names[CD_SHAPE_NTYPES] = {
    "plane", "sphere", "box", "cylinder", "capsule", "convex"};
static const char *stepper_names[CD_STEP_NTYPES] = {
    "rkf45", "rkck", "rk8pd", "rk4imp", "msbdf", "rk4"};

const char *cd_shape_type_name(cd_shape_type t)
{ return (t >= 0 && t < CD_SHAPE_NTYPES) ? shape_names[t] : "?"; }
int cd_shape_type_from_name(const char *name)
{
    int i;
    for (i = 0; name && i < CD_SHAPE_NTYPES; i++)
        if (strcmp(name, shape_names[i]) == 0) return i;
    return -1;
}
const char *cd_stepper_name(cd_stepper s)
{ return (s >= 0 && s < CD_STEP_NTYPES) ? stepper_names[s] : "?"; }
int cd_stepper_from_name(const char *name)
{
    int i;
    for (i = 0; name && i < CD_STEP_NTYPES; i++)
        if (strcmp(name, stepper_names[i]) == 0) return i;
    return -1;
}

cd_options cd_options_default(void)
{
    cd_options o;
    o.stepper = CD_STEP_RK8PD;
    o.rtol = 1e-9;
    o.atol = 1e-12;
    o.h_init = 1e-5;
    o.h_max = 1e-2;
    o.h_min = 1e-14;
    o.h_fixed = 1e-5;
    o.max_steps = 100000000L;
    o.event_tol = 1e-10;
    o.dwell = 1e-7;
    o.v_reg = 1e-6;
    o.fd_eps = 1e-7;
    return o;
}

cd_status cd_options_check(const cd_options *o, cd_error *err)
{
    if (!o) { seterr(err, CD_EINVAL, "options are NULL"); return CD_EINVAL; }
    if (o->stepper < 0 || o->stepper >= CD_STEP_NTYPES) { seterr(err, CD_EINVAL, "unknown stepper %d", (int)o->stepper); return CD_EINVAL; }
    if (!(isfinite(o->rtol) && isfinite(o->atol) && o->rtol >= 0 && o->atol >= 0 && o->rtol + o->atol > 0)) {
        seterr(err, CD_EINVAL, "tolerances must be finite, >= 0 and not both zero (rtol %g, atol %g)", o->rtol, o->atol);
        return CD_EINVAL;
    }
    if (!(o->h_init > 0 && isfinite(o->h_init)) || !(o->h_max >= 0) || !(o->h_min >= 0) ||
        !(o->h_fixed > 0 && isfinite(o->h_fixed)) || o->max_steps < 1 || !(o->event_tol > 0) || !(o->dwell >= 0) ||
        !(o->v_reg > 0) || !(o->fd_eps > 0)) {
        seterr(err, CD_EINVAL, "integrator options out of range (steps, tolerances and budgets must be positive)");
        return CD_EINVAL;
    }
    return CD_OK;
}

cd_contact_law cd_contact_law_default(void)
{
    cd_contact_law l;
    l.K = 1e5; l.D = 100.0; l.p = 1.0; l.q = 1.0;
    l.Kt = 1e5; l.Dt = 100.0;
    l.mu_s = 0.5; l.mu_k = 0.5;
    return l;
}

/* Paper sec. 2: stiff parts get k_ratio (10..100) x the soft part's stiffness;
 * damping ratio zeta ~ 1 for the effective mass: D = 2 zeta sqrt(K m). */
cd_contact_law cd_contact_law_from_rule(double k_soft, double k_ratio, double m_eff,
                                        double zeta, double mu)
{
    cd_contact_law l = cd_contact_law_default();
    l.K = k_soft * k_ratio;
    l.D = 2.0 * zeta * sqrt(l.K * m_eff);
    l.Kt = l.K;
    l.Dt = l.D;
    l.mu_s = l.mu_k = mu;
    return l;
}

cd_system_desc cd_system_desc_default(void)
{
    cd_system_desc s;
    memset(&s, 0, sizeof s);
    s.type = CD_BASE_FREE;
    s.mass = 1.0;
    cd_m3_identity(s.inertia);
    s.quat[0] = 1.0;
    return s;
}

cd_link_desc cd_link_desc_default(void)
{
    cd_link_desc l;
    memset(&l, 0, sizeof l);
    l.parent = -1;
    l.type = CD_JOINT_REVOLUTE;
    cd_m3_identity(l.rot);
    l.axis[2] = 1.0;
    l.mass = 1.0;
    cd_m3_identity(l.inertia);
    return l;
}

/* ---- arrays are resized to the exact count on every add: building happens
 * once, before any simulation, so simplicity beats amortised growth. ---- */
static int resize(void **p, size_t n, size_t elem)
{
    void *q = realloc(*p, (n ? n : 1) * elem);
    if (!q) return -1;
    *p = q;
    return 0;
}
#define RS(ptr, n) resize((void **)&(ptr), (size_t)(n), sizeof *(ptr))

static char *dupstr(const char *s)
{
    char *r;
    if (!s) s = "";
    r = malloc(strlen(s) + 1);
    if (r) strcpy(r, s);
    return r;
}

cd_model *cd_model_create(void)
{
    cd_model *m = calloc(1, sizeof *m);
    if (!m) return NULL;
    m->opt = cd_options_default();
    return m;
}

void cd_model_free(cd_model *m)
{
    int i;
    if (!m) return;
    for (i = 0; i < m->nsys; i++) free(m->sys_name[i]);
    for (i = 0; i < m->nbody; i++) free(m->body_name[i]);
    free(m->sys_name); free(m->sys_base_type); free(m->sys_body_adr); free(m->sys_nbody);
    free(m->sys_ndof); free(m->sys_v_adr); free(m->sys_y_adr); free(m->sys_pos0);
    free(m->sys_quat0); free(m->sys_vel0); free(m->sys_angvel0);
    free(m->body_name); free(m->body_sys); free(m->body_parent); free(m->body_jnt_type);
    free(m->body_dof); free(m->body_jnt_pos); free(m->body_jnt_rot); free(m->body_axis);
    free(m->body_mass); free(m->body_com); free(m->body_inertia); free(m->body_q0);
    free(m->body_qd0); free(m->body_act_type); free(m->body_act); free(m->body_tbl_adr);
    free(m->body_tbl_n); free(m->tbl_t); free(m->tbl_v);
    free(m->cp_body); free(m->cp_pos); free(m->cp_radius);
    free(m->shape_body); free(m->shape_type); free(m->shape_pos); free(m->shape_rot);
    free(m->shape_size); free(m->shape_vert_adr); free(m->shape_vert_num); free(m->vert);
    free(m->shape_face_adr); free(m->shape_face_num); free(m->face_vert); free(m->face_plane);
    free(m->law); free(m->pair_sys); free(m->pair_body); free(m->pair_shape); free(m->pair_law);
    free(m->slot_cp); free(m->slot_shape); free(m->slot_law);
    free(m);
}

static int finite_n(const double *a, int n)
{
    int i;
    for (i = 0; i < n; i++)
        if (!isfinite(a[i])) return 0;
    return 1;
}

/* A rotation matrix is accepted if R R^T = 1 and det R = 1 to 1e-9. */
static int is_rotation(const double R[9])
{
    int i, j, k;
    double det;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            double s = 0;
            for (k = 0; k < 3; k++) s += R[3 * i + k] * R[3 * j + k];
            if (fabs(s - (i == j)) > 1e-9) return 0;
        }
    det = R[0] * (R[4] * R[8] - R[5] * R[7]) - R[1] * (R[3] * R[8] - R[5] * R[6]) +
          R[2] * (R[3] * R[7] - R[4] * R[6]);
    return fabs(det - 1.0) < 1e-9;
}

/* Inertia about the CoM: symmetric, positive definite, and its principal
 * moments obey the triangle inequality (a real mass distribution). Returns
 * NULL if valid, else a reason. */
static const char *inertia_problem(const double I[9])
{
    double a, b, c, d1, d2, d3, tol;
    if (!finite_n(I, 9)) return "inertia has a non-finite entry";
    tol = 1e-9 * (fabs(I[0]) + fabs(I[4]) + fabs(I[8]));
    if (fabs(I[1] - I[3]) > tol || fabs(I[2] - I[6]) > tol || fabs(I[5] - I[7]) > tol)
        return "inertia is not symmetric";
    /* leading minors (Sylvester) */
    d1 = I[0];
    d2 = I[0] * I[4] - I[1] * I[3];
    d3 = I[0] * (I[4] * I[8] - I[5] * I[7]) - I[1] * (I[3] * I[8] - I[5] * I[6]) +
         I[2] * (I[3] * I[7] - I[4] * I[6]);
    if (!(d1 > 0 && d2 > 0 && d3 > 0)) return "inertia is not positive definite";
    /* triangle inequality on the principal moments (eigenvalues) */
    {
        /* eigenvalues of a symmetric 3x3 (trigonometric method) */
        double p1 = I[1] * I[1] + I[2] * I[2] + I[5] * I[5];
        double q = (I[0] + I[4] + I[8]) / 3.0, p2, p, B[9], r, phi;
        int i;
        if (p1 == 0) {
            a = I[0]; b = I[4]; c = I[8];
        } else {
            p2 = (I[0] - q) * (I[0] - q) + (I[4] - q) * (I[4] - q) + (I[8] - q) * (I[8] - q) + 2 * p1;
            p = sqrt(p2 / 6.0);
            for (i = 0; i < 9; i++) B[i] = (I[i] - (i % 4 == 0 ? q : 0.0)) / p;
            r = 0.5 * (B[0] * (B[4] * B[8] - B[5] * B[7]) - B[1] * (B[3] * B[8] - B[5] * B[6]) +
                       B[2] * (B[3] * B[7] - B[4] * B[6]));
            phi = r <= -1 ? CD_PI / 3 : (r >= 1 ? 0 : acos(r) / 3);
            a = q + 2 * p * cos(phi);
            c = q + 2 * p * cos(phi + 2 * CD_PI / 3);
            b = 3 * q - a - c;
        }
        tol = 1e-9 * (a + b + c);
        if (a + b < c - tol || b + c < a - tol || a + c < b - tol)
            return "inertia violates the triangle inequality (no real body has these principal moments)";
    }
    return NULL;
}

#define FROZEN_CHECK(ret)                                                                  \
    do {                                                                                   \
        if (!m) { seterr(err, CD_EINVAL, "model is NULL"); return ret; }                   \
        if (m->finalized) { seterr(err, CD_EINVAL, "model is finalized (read-only)"); return ret; } \
    } while (0)

static int add_body_arrays(cd_model *m)
{
    int n = m->nbody + 1, ok = 0;
    ok |= RS(m->body_name, n); ok |= RS(m->body_sys, n); ok |= RS(m->body_parent, n);
    ok |= RS(m->body_jnt_type, n); ok |= RS(m->body_dof, n); ok |= RS(m->body_jnt_pos, 3 * n);
    ok |= RS(m->body_jnt_rot, 9 * n); ok |= RS(m->body_axis, 3 * n); ok |= RS(m->body_mass, n);
    ok |= RS(m->body_com, 3 * n); ok |= RS(m->body_inertia, 9 * n); ok |= RS(m->body_q0, n);
    ok |= RS(m->body_qd0, n); ok |= RS(m->body_act_type, n); ok |= RS(m->body_act, 4 * n);
    ok |= RS(m->body_tbl_adr, n); ok |= RS(m->body_tbl_n, n);
    return ok ? -1 : 0;
}

static int new_body(cd_model *m, const char *name, int sys, int parent, int jtype,
                    const double pos[3], const double rot[9], const double axis[3], double mass,
                    const double com[3], const double inertia[9], double q0, double qd0)
{
    int b = m->nbody;
    if (add_body_arrays(m)) return -1;
    m->body_name[b] = dupstr(name);
    if (!m->body_name[b]) return -1;
    m->body_sys[b] = sys;
    m->body_parent[b] = parent;
    m->body_jnt_type[b] = jtype;
    m->body_dof[b] = -1;
    cd_v3_copy(m->body_jnt_pos + 3 * b, pos);
    cd_m3_copy(m->body_jnt_rot + 9 * b, rot);
    cd_v3_copy(m->body_axis + 3 * b, axis);
    m->body_mass[b] = mass;
    cd_v3_copy(m->body_com + 3 * b, com);
    cd_m3_copy(m->body_inertia + 9 * b, inertia);
    m->body_q0[b] = q0;
    m->body_qd0[b] = qd0;
    m->body_act_type[b] = CD_ACT_NONE;
    memset(m->body_act + 4 * b, 0, 4 * sizeof(double));
    m->body_tbl_adr[b] = 0;
    m->body_tbl_n[b] = 0;
    m->nbody++;
    return b;
}

int cd_model_add_system(cd_model *m, const cd_system_desc *s, cd_error *err)
{
    int id, n, ok = 0, b;
    const char *why;
    double z3[3] = {0, 0, 0}, R[9], ax[3] = {0, 0, 1}, qn;
    FROZEN_CHECK(-1);
    if (!s) { seterr(err, CD_EINVAL, "system description is NULL"); return -1; }
    if (s->type != CD_BASE_FREE && s->type != CD_BASE_FIXED) {
        seterr(err, CD_EINVAL, "system '%s': base type must be free or fixed", s->name ? s->name : "");
        return -1;
    }
    if (!(s->mass > 0) || !isfinite(s->mass)) {
        seterr(err, CD_EINVAL, "system '%s': base mass must be a positive finite number, got %g",
               s->name ? s->name : "", s->mass);
        return -1;
    }
    if ((why = inertia_problem(s->inertia)) != NULL) {
        seterr(err, CD_EINVAL, "system '%s': base %s", s->name ? s->name : "", why);
        return -1;
    }
    if (!finite_n(s->pos, 3) || !finite_n(s->quat, 4) || !finite_n(s->vel, 3) || !finite_n(s->angvel, 3)) {
        seterr(err, CD_EINVAL, "system '%s': initial state has a non-finite value", s->name ? s->name : "");
        return -1;
    }
    qn = sqrt(s->quat[0] * s->quat[0] + s->quat[1] * s->quat[1] + s->quat[2] * s->quat[2] + s->quat[3] * s->quat[3]);
    if (!(qn > 1e-12)) {
        seterr(err, CD_EINVAL, "system '%s': base quaternion is zero", s->name ? s->name : "");
        return -1;
    }
    id = m->nsys;
    n = id + 1;
    ok |= RS(m->sys_name, n); ok |= RS(m->sys_base_type, n); ok |= RS(m->sys_body_adr, n);
    ok |= RS(m->sys_nbody, n); ok |= RS(m->sys_ndof, n); ok |= RS(m->sys_v_adr, n);
    ok |= RS(m->sys_y_adr, n); ok |= RS(m->sys_pos0, 3 * n); ok |= RS(m->sys_quat0, 4 * n);
    ok |= RS(m->sys_vel0, 3 * n); ok |= RS(m->sys_angvel0, 3 * n);
    if (ok) { seterr(err, CD_ENOMEM, "out of memory"); return -1; }
    m->sys_name[id] = dupstr(s->name);
    if (!m->sys_name[id]) { seterr(err, CD_ENOMEM, "out of memory"); return -1; }
    m->sys_base_type[id] = s->type;
    m->sys_body_adr[id] = m->nbody;
    m->sys_nbody[id] = 1;
    cd_v3_copy(m->sys_pos0 + 3 * id, s->pos);
    m->sys_quat0[4 * id] = s->quat[0] / qn;
    m->sys_quat0[4 * id + 1] = s->quat[1] / qn;
    m->sys_quat0[4 * id + 2] = s->quat[2] / qn;
    m->sys_quat0[4 * id + 3] = s->quat[3] / qn;
    cd_v3_copy(m->sys_vel0 + 3 * id, s->vel);
    cd_v3_copy(m->sys_angvel0 + 3 * id, s->angvel);
    m->nsys++;
    cd_m3_identity(R);
    b = new_body(m, s->name, id, -1, CD_JOINT_BASE, z3, R, ax, s->mass, z3, s->inertia, 0.0, 0.0);
    if (b < 0) { /* undo: the name is not freed by cd_model_free beyond nsys */
        m->nsys--;
        free(m->sys_name[id]);
        seterr(err, CD_ENOMEM, "out of memory");
        return -1;
    }
    return id;
}

int cd_model_add_link(cd_model *m, int sys, const cd_link_desc *l, cd_error *err)
{
    const char *why, *nm;
    double ax[3];
    int b;
    FROZEN_CHECK(-1);
    if (!l) { seterr(err, CD_EINVAL, "link description is NULL"); return -1; }
    nm = l->name ? l->name : "";
    if (sys < 0 || sys >= m->nsys) { seterr(err, CD_EINVAL, "link '%s': no system %d", nm, sys); return -1; }
    if (sys != m->nsys - 1) {
        seterr(err, CD_EINVAL, "link '%s': links must be added to the most recently added system", nm);
        return -1;
    }
    if (l->parent < m->sys_body_adr[sys] || l->parent >= m->nbody) {
        seterr(err, CD_EINVAL, "link '%s': parent %d is not an existing body of system '%s'", nm,
               l->parent, m->sys_name[sys]);
        return -1;
    }
    if (l->type != CD_JOINT_REVOLUTE && l->type != CD_JOINT_PRISMATIC) {
        seterr(err, CD_EINVAL, "link '%s': joint type must be revolute or prismatic", nm);
        return -1;
    }
    if (!(l->mass > 0) || !isfinite(l->mass)) {
        seterr(err, CD_EINVAL, "link '%s': mass must be a positive finite number, got %g", nm, l->mass);
        return -1;
    }
    if ((why = inertia_problem(l->inertia)) != NULL) {
        seterr(err, CD_EINVAL, "link '%s': %s", nm, why);
        return -1;
    }
    if (!finite_n(l->pos, 3) || !finite_n(l->com, 3) || !finite_n(l->rot, 9) || !finite_n(l->axis, 3) ||
        !isfinite(l->q0) || !isfinite(l->qd0)) {
        seterr(err, CD_EINVAL, "link '%s': non-finite value in position, axis, CoM or initial state", nm);
        return -1;
    }
    if (!is_rotation(l->rot)) {
        seterr(err, CD_EINVAL, "link '%s': joint frame rotation is not a proper rotation", nm);
        return -1;
    }
    cd_v3_copy(ax, l->axis);
    if (cd_v3_normalize(ax) < 1e-12) {
        seterr(err, CD_EINVAL, "link '%s': joint axis is zero", nm);
        return -1;
    }
    b = new_body(m, l->name, sys, l->parent, l->type, l->pos, l->rot, ax, l->mass, l->com,
                 l->inertia, l->q0, l->qd0);
    if (b < 0) { seterr(err, CD_ENOMEM, "out of memory"); return -1; }
    m->sys_nbody[sys]++;
    return b;
}

int cd_model_add_checkpoint(cd_model *m, int body, const double pos[3], double radius, cd_error *err)
{
    int id, ok = 0;
    FROZEN_CHECK(-1);
    if (body < 0 || body >= m->nbody) { seterr(err, CD_EINVAL, "check point: no body %d", body); return -1; }
    if (!pos || !finite_n(pos, 3) || !(radius >= 0) || !isfinite(radius)) {
        seterr(err, CD_EINVAL, "check point on body '%s': position must be finite and radius >= 0",
               m->body_name[body]);
        return -1;
    }
    id = m->ncp;
    ok |= RS(m->cp_body, id + 1); ok |= RS(m->cp_radius, id + 1); ok |= RS(m->cp_pos, 3 * (id + 1));
    if (ok) { seterr(err, CD_ENOMEM, "out of memory"); return -1; }
    m->cp_body[id] = body;
    cd_v3_copy(m->cp_pos + 3 * id, pos);
    m->cp_radius[id] = radius;
    m->ncp++;
    return id;
}

int cd_model_add_shape(cd_model *m, int body, cd_shape_type type, const double pos[3],
                       const double rot[9], const double size[3], const double *verts,
                       int nvert, cd_error *err)
{
    int id, n, ok = 0, i;
    double sz[3] = {0, 0, 0}, R[9];
    FROZEN_CHECK(-1);
    if (body < 0 || body >= m->nbody) { seterr(err, CD_EINVAL, "shape: no body %d", body); return -1; }
    if (type < 0 || type >= CD_SHAPE_NTYPES) { seterr(err, CD_EINVAL, "shape: unknown type %d", (int)type); return -1; }
    if (size) memcpy(sz, size, sizeof sz);
    if (rot) cd_m3_copy(R, rot); else cd_m3_identity(R);
    if ((pos && !finite_n(pos, 3)) || !finite_n(sz, 3) || !is_rotation(R)) {
        seterr(err, CD_EINVAL, "%s shape on body '%s': position must be finite and rotation proper",
               cd_shape_type_name(type), m->body_name[body]);
        return -1;
    }
    switch (type) {
    case CD_SHAPE_SPHERE:
        if (!(sz[0] > 0)) { seterr(err, CD_EINVAL, "sphere on body '%s': radius must be > 0", m->body_name[body]); return -1; }
        break;
    case CD_SHAPE_BOX:
        if (!(sz[0] > 0 && sz[1] > 0 && sz[2] > 0)) {
            seterr(err, CD_EINVAL, "box on body '%s': half extents must be > 0", m->body_name[body]);
            return -1;
        }
        break;
    case CD_SHAPE_CYLINDER:
    case CD_SHAPE_CAPSULE:
        if (!(sz[0] > 0 && sz[1] > 0)) {
            seterr(err, CD_EINVAL, "%s on body '%s': radius and half length must be > 0",
                   cd_shape_type_name(type), m->body_name[body]);
            return -1;
        }
        break;
    case CD_SHAPE_CONVEX:
        if (!verts || nvert < 4 || !finite_n(verts, 3 * nvert)) {
            seterr(err, CD_EINVAL, "convex shape on body '%s': needs >= 4 finite vertices", m->body_name[body]);
            return -1;
        }
        break;
    default:
        break;
    }
    id = m->nshape;
    n = id + 1;
    ok |= RS(m->shape_body, n); ok |= RS(m->shape_type, n); ok |= RS(m->shape_pos, 3 * n);
    ok |= RS(m->shape_rot, 9 * n); ok |= RS(m->shape_size, 3 * n); ok |= RS(m->shape_vert_adr, n);
    ok |= RS(m->shape_vert_num, n);
    if (ok) { seterr(err, CD_ENOMEM, "out of memory"); return -1; }
    if (type == CD_SHAPE_CONVEX) {
        if (RS(m->vert, 3 * (m->nvert + nvert))) {
            seterr(err, CD_ENOMEM, "out of memory");
            return -1;
        }
        for (i = 0; i < 3 * nvert; i++) m->vert[3 * m->nvert + i] = verts[i];
        m->shape_vert_adr[id] = m->nvert;
        m->shape_vert_num[id] = nvert;
        m->nvert += nvert;
    } else {
        m->shape_vert_adr[id] = 0;
        m->shape_vert_num[id] = 0;
    }
    m->shape_body[id] = body;
    m->shape_type[id] = type;
    if (pos) cd_v3_copy(m->shape_pos + 3 * id, pos); else cd_v3_zero(m->shape_pos + 3 * id);
    cd_m3_copy(m->shape_rot + 9 * id, R);
    cd_v3_copy(m->shape_size + 3 * id, sz);
    m->nshape++;
    return id;
}

int cd_model_add_law(cd_model *m, const cd_contact_law *l, cd_error *err)
{
    int id;
    FROZEN_CHECK(-1);
    if (!l) { seterr(err, CD_EINVAL, "contact law is NULL"); return -1; }
    if (!(l->K > 0) || !isfinite(l->K)) { seterr(err, CD_EINVAL, "contact law: K must be > 0, got %g", l->K); return -1; }
    if (!(l->D >= 0) || !isfinite(l->D)) { seterr(err, CD_EINVAL, "contact law: D must be >= 0, got %g", l->D); return -1; }
    if (!(l->p >= 1) || !isfinite(l->p)) { seterr(err, CD_EINVAL, "contact law: p must be >= 1, got %g", l->p); return -1; }
    if (!(l->q > 0) || !isfinite(l->q)) { seterr(err, CD_EINVAL, "contact law: q must be > 0, got %g", l->q); return -1; }
    if (!(l->Kt > 0) || !isfinite(l->Kt)) { seterr(err, CD_EINVAL, "contact law: K_t must be > 0, got %g", l->Kt); return -1; }
    if (!(l->Dt >= 0) || !isfinite(l->Dt)) { seterr(err, CD_EINVAL, "contact law: D_t must be >= 0, got %g", l->Dt); return -1; }
    if (!(l->mu_s >= 0) || !isfinite(l->mu_s)) { seterr(err, CD_EINVAL, "contact law: mu_max must be >= 0, got %g", l->mu_s); return -1; }
    if (!(l->mu_k >= 0) || !(l->mu_k <= l->mu_s)) {
        seterr(err, CD_EINVAL, "contact law: mu must be in [0, mu_max=%g], got %g", l->mu_s, l->mu_k);
        return -1;
    }
    id = m->nlaw;
    if (RS(m->law, id + 1)) { seterr(err, CD_ENOMEM, "out of memory"); return -1; }
    m->law[id] = *l;
    m->nlaw++;
    return id;
}

int cd_model_add_pair(cd_model *m, int sys, int body, int shape, int law, cd_error *err)
{
    int id, ok = 0;
    FROZEN_CHECK(-1);
    if (sys < 0 || sys >= m->nsys) { seterr(err, CD_EINVAL, "pair: no system %d", sys); return -1; }
    if (body >= 0 && (body >= m->nbody || m->body_sys[body] != sys)) {
        seterr(err, CD_EINVAL, "pair: body %d is not in system '%s'", body, m->sys_name[sys]);
        return -1;
    }
    if (shape < 0 || shape >= m->nshape) { seterr(err, CD_EINVAL, "pair: no shape %d", shape); return -1; }
    if (body >= 0 && body == m->shape_body[shape]) {
        seterr(err, CD_EINVAL, "pair: the check points of body '%s' cannot touch its own shape %d (%s)",
               m->body_name[body], shape, cd_shape_type_name(m->shape_type[shape]));
        return -1;
    }
    if (law < 0 || law >= m->nlaw) { seterr(err, CD_EINVAL, "pair: no contact law %d", law); return -1; }
    id = m->npair;
    ok |= RS(m->pair_sys, id + 1); ok |= RS(m->pair_body, id + 1);
    ok |= RS(m->pair_shape, id + 1); ok |= RS(m->pair_law, id + 1);
    if (ok) { seterr(err, CD_ENOMEM, "out of memory"); return -1; }
    m->pair_sys[id] = sys;
    m->pair_body[id] = body;
    m->pair_shape[id] = shape;
    m->pair_law[id] = law;
    m->npair++;
    return id;
}

cd_status cd_model_set_actuator(cd_model *m, int body, const cd_actuator *a, cd_error *err)
{
    int i, ok = 0;
    FROZEN_CHECK(CD_EINVAL);
    if (body < 0 || body >= m->nbody || m->body_parent[body] < 0) {
        seterr(err, CD_EINVAL, "actuator: body %d is not a joint body", body);
        return CD_EINVAL;
    }
    if (!a || a->type < CD_ACT_NONE || a->type > CD_ACT_PD) {
        seterr(err, CD_EINVAL, "actuator on '%s': unknown type", m->body_name[body]);
        return CD_EINVAL;
    }
    if (!isfinite(a->tau0) || !isfinite(a->kp) || !isfinite(a->kd) || !isfinite(a->qref)) {
        seterr(err, CD_EINVAL, "actuator on '%s': non-finite parameter", m->body_name[body]);
        return CD_EINVAL;
    }
    m->body_act_type[body] = a->type;
    m->body_act[4 * body] = a->tau0;
    m->body_act[4 * body + 1] = a->kp;
    m->body_act[4 * body + 2] = a->kd;
    m->body_act[4 * body + 3] = a->qref;
    if (a->type == CD_ACT_TABLE) {
        if (!a->tbl_t || !a->tbl_v || a->ntbl < 1) {
            seterr(err, CD_EINVAL, "actuator on '%s': a table needs at least one (t, value) row", m->body_name[body]);
            return CD_EINVAL;
        }
        for (i = 0; i < a->ntbl; i++) {
            if (!isfinite(a->tbl_t[i]) || !isfinite(a->tbl_v[i]) || (i > 0 && !(a->tbl_t[i] > a->tbl_t[i - 1]))) {
                seterr(err, CD_EINVAL, "actuator on '%s': table row %d: times must be finite and strictly increasing",
                       m->body_name[body], i);
                return CD_EINVAL;
            }
        }
        ok |= RS(m->tbl_t, m->ntbl + a->ntbl);
        ok |= RS(m->tbl_v, m->ntbl + a->ntbl);
        if (ok) { seterr(err, CD_ENOMEM, "out of memory"); return CD_ENOMEM; }
        memcpy(m->tbl_t + m->ntbl, a->tbl_t, (size_t)a->ntbl * sizeof(double));
        memcpy(m->tbl_v + m->ntbl, a->tbl_v, (size_t)a->ntbl * sizeof(double));
        m->body_tbl_adr[body] = m->ntbl;
        m->body_tbl_n[body] = a->ntbl;
        m->ntbl += a->ntbl;
    }
    return CD_OK;
}

int cd_model_system_id(const cd_model *m, const char *name)
{
    int i;
    for (i = 0; m && name && i < m->nsys; i++)
        if (strcmp(m->sys_name[i], name) == 0) return i;
    return -1;
}

int cd_model_body_id(const cd_model *m, const char *name)
{
    int i, found = -1;
    const char *slash;
    if (!m || !name) return -1;
    slash = strchr(name, '/');
    if (slash) {
        int s;
        char sysname[256];
        size_t n = (size_t)(slash - name);
        if (n >= sizeof sysname) return -1;
        memcpy(sysname, name, n);
        sysname[n] = 0;
        s = cd_model_system_id(m, sysname);
        if (s < 0) return -1;
        for (i = m->sys_body_adr[s]; i < m->sys_body_adr[s] + m->sys_nbody[s]; i++)
            if (strcmp(m->body_name[i], slash + 1) == 0) return i;
        return -1;
    }
    for (i = 0; i < m->nbody; i++)
        if (strcmp(m->body_name[i], name) == 0) {
            if (found >= 0) return -1; /* ambiguous */
            found = i;
        }
    return found;
}

/* Faces of the convex hull of shape sh's vertices, by brute force over
 * vertex triples: a triple is a face when every vertex lies on one side of
 * its plane (within 1e-9 of the hull's size). Coplanar faces with more than
 * three vertices yield several overlapping triangles, which is harmless for
 * the distance query. O(n^4): meant for hulls of tens of vertices, run once.
 * With store == 0 only counts. Returns the number of faces, or -1 if all
 * vertices lie in one plane (no volume). */
static int hull_faces(cd_model *m, int sh, int store, int at)
{
    const double *v = m->vert + 3 * m->shape_vert_adr[sh];
    int nv = m->shape_vert_num[sh], i, j, k, l, nf = 0;
    double size = 0, c[3] = {0, 0, 0};
    for (i = 0; i < nv; i++) cd_v3_axpy(c, 1.0 / nv, v + 3 * i);
    for (i = 0; i < nv; i++) {
        double t[3], r;
        cd_v3_sub(t, v + 3 * i, c);
        r = cd_v3_norm(t);
        if (r > size) size = r;
    }
    for (i = 0; i < nv; i++)
        for (j = i + 1; j < nv; j++)
            for (k = j + 1; k < nv; k++) {
                double a[3], b[3], n[3], o, len;
                int pos = 0, neg = 0;
                cd_v3_sub(a, v + 3 * j, v + 3 * i);
                cd_v3_sub(b, v + 3 * k, v + 3 * i);
                cd_v3_cross(n, a, b);
                len = cd_v3_norm(n);
                if (!(len > 1e-12 * size * size)) continue; /* collinear */
                cd_v3_scale(n, n, 1.0 / len);
                o = cd_v3_dot(n, v + 3 * i);
                for (l = 0; l < nv && !(pos && neg); l++) {
                    double h = cd_v3_dot(n, v + 3 * l) - o;
                    if (h > 1e-9 * size) pos = 1;
                    if (h < -1e-9 * size) neg = 1;
                }
                if (pos && neg) continue;
                if (!pos && !neg) return -1; /* every vertex on this plane: a flat hull */
                if (pos) { cd_v3_scale(n, n, -1.0); o = -o; }
                if (store) {
                    int f = at + nf;
                    m->face_vert[3 * f] = m->shape_vert_adr[sh] + i;
                    m->face_vert[3 * f + 1] = m->shape_vert_adr[sh] + j;
                    m->face_vert[3 * f + 2] = m->shape_vert_adr[sh] + k;
                    cd_v3_copy(m->face_plane + 4 * f, n);
                    m->face_plane[4 * f + 3] = o;
                }
                nf++;
            }
    return nf;
}

/* does pair i make a slot for check point k? */
static int slot_wanted(const cd_model *m, int i, int k)
{
    int cb = m->cp_body[k], sb = m->shape_body[m->pair_shape[i]];
    if (m->body_sys[cb] != m->pair_sys[i]) return 0;
    if (m->pair_body[i] >= 0 && cb != m->pair_body[i]) return 0;
    if (cb == sb || m->body_parent[cb] == sb || m->body_parent[sb] == cb) return 0;
    return 1;
}

/* ---- contact slots: every check point of a pair's system/body x the pair's
 * shape (slot_wanted), one slot per (check point, shape), the first pair's
 * law kept, in pair order then check-point order.
 * Design: a pair whose (system or body, shape) is covered by an earlier pair
 * adds nothing and is skipped (found by sorting the pairs); the others visit
 * only their own check points (bucketed by system and by body); the rare
 * remaining duplicates (a body pair, then a whole-system pair on the same
 * shape) are found by sorting the candidates on (shape, check point, order).
 * O((P + C) log(P + C)) for P pairs and C candidate slots, where the former
 * scan was O(P x ncp) and the duplicate test O(slots^2). ---- */
/* at most 10^7 slots (a slot costs about 300 bytes of cd_data and 3 states) */
#define CD_MAX_SLOTS 10000000u
typedef struct { int a, b, c, i; } slot_key;
static int slot_key_cmp(const void *x, const void *y)
{
    const slot_key *p = (const slot_key *)x, *q = (const slot_key *)y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    if (p->c != q->c) return p->c < q->c ? -1 : 1;
    return p->i < q->i ? -1 : (p->i > q->i);
}

/* ncp ids grouped by owner (body or system), ascending within a group */
static int bucket_cps(const cd_model *m, int by_sys, int nown, int **adr, int **ids)
{
    int k, o, *cnt;
    *adr = calloc((size_t)nown + 1, sizeof(int));
    *ids = malloc((size_t)(m->ncp ? m->ncp : 1) * sizeof(int));
    cnt = calloc((size_t)nown + 1, sizeof(int));
    if (!*adr || !*ids || !cnt) { free(cnt); return -1; }
    for (k = 0; k < m->ncp; k++) (*adr)[1 + (by_sys ? m->body_sys[m->cp_body[k]] : m->cp_body[k])]++;
    for (o = 0; o < nown; o++) (*adr)[o + 1] += (*adr)[o];
    for (k = 0; k < m->ncp; k++) {
        o = by_sys ? m->body_sys[m->cp_body[k]] : m->cp_body[k];
        (*ids)[(*adr)[o] + cnt[o]++] = k;
    }
    free(cnt);
    return 0;
}

static cd_status build_slots(cd_model *m, int ny, cd_error *err)
{
    cd_status st = CD_ENOMEM;
    int i, k, j, *skip = NULL, *body_adr = NULL, *body_cp = NULL, *sys_adr = NULL, *sys_cp = NULL;
    slot_key *pk = NULL, *ck = NULL;
    size_t nc = 0, cap = 0, n, limit = (size_t)(INT_MAX - ny) / 3;
    if (limit > CD_MAX_SLOTS) limit = CD_MAX_SLOTS;
    free(m->slot_cp); free(m->slot_shape); free(m->slot_law); /* a failed earlier finalize */
    m->slot_cp = m->slot_shape = m->slot_law = NULL;
    m->nslot = 0;
    skip = calloc((size_t)(m->npair ? m->npair : 1), sizeof(int));
    pk = malloc((size_t)(m->npair ? m->npair : 1) * sizeof *pk);
    if (!skip || !pk || bucket_cps(m, 0, m->nbody, &body_adr, &body_cp) || bucket_cps(m, 1, m->nsys, &sys_adr, &sys_cp))
        goto out;
    /* pairs covered by an earlier one: same (shape, system) and the same body
     * or an earlier whole-system pair (body -1 sorts first in its group) */
    for (i = 0; i < m->npair; i++) {
        pk[i].a = m->pair_shape[i]; pk[i].b = m->pair_sys[i]; pk[i].c = m->pair_body[i]; pk[i].i = i;
    }
    if (m->npair) qsort(pk, (size_t)m->npair, sizeof *pk, slot_key_cmp);
    for (i = 0; i < m->npair; i++) {
        int g = i, whole = -1;
        if (i > 0 && pk[i].a == pk[i - 1].a && pk[i].b == pk[i - 1].b) continue;
        while (g < m->npair && pk[g].a == pk[i].a && pk[g].b == pk[i].b) g++; /* group [i, g) */
        if (pk[i].c < 0) whole = pk[i].i;
        for (j = i; j < g; j++) {
            if (whole >= 0 && pk[j].i > whole) skip[pk[j].i] = 1;
            else if (j > i && pk[j].c == pk[j - 1].c) skip[pk[j].i] = 1;
        }
    }
    /* candidates in pair order, then check-point order */
    for (n = 0, i = 0; i < m->npair; i++) {
        const int *ids;
        int cnt;
        if (skip[i]) continue;
        if (m->pair_body[i] >= 0) { ids = body_cp + body_adr[m->pair_body[i]]; cnt = body_adr[m->pair_body[i] + 1] - body_adr[m->pair_body[i]]; }
        else { ids = sys_cp + sys_adr[m->pair_sys[i]]; cnt = sys_adr[m->pair_sys[i] + 1] - sys_adr[m->pair_sys[i]]; }
        for (j = 0; j < cnt; j++) {
            k = ids[j];
            if (!slot_wanted(m, i, k)) continue;
            if (nc == cap) {
                slot_key *q;
                cap = cap ? 2 * cap : 1024;
                q = realloc(ck, cap * sizeof *ck);
                if (!q) goto out;
                ck = q;
            }
            ck[nc].a = m->pair_shape[i]; ck[nc].b = k; ck[nc].c = (int)n; ck[nc].i = i;
            nc++;
            n++;
            if (nc > 2 * limit + 2) break; /* far too many already */
        }
        if (nc > 2 * limit + 2) break;
    }
    /* keep the first of each (shape, check point), then restore the order */
    if (nc) qsort(ck, nc, sizeof *ck, slot_key_cmp);
    for (n = 0, j = 0; (size_t)j < nc; j++)
        if (j == 0 || ck[j].a != ck[j - 1].a || ck[j].b != ck[j - 1].b) ck[n++] = ck[j];
    if (n > limit) {
        seterr(err, CD_EINVAL, "too many contact slots: %lu (check points x shapes of the pairs), at most %lu",
               (unsigned long)n, (unsigned long)limit);
        st = CD_EINVAL;
        goto out;
    }
    for (j = 0; (size_t)j < n; j++) { k = ck[j].a; ck[j].a = ck[j].c; ck[j].c = k; } /* order first */
    if (n) qsort(ck, n, sizeof *ck, slot_key_cmp);
    m->slot_cp = malloc((n ? n : 1) * sizeof(int));
    m->slot_shape = malloc((n ? n : 1) * sizeof(int));
    m->slot_law = malloc((n ? n : 1) * sizeof(int));
    if (!m->slot_cp || !m->slot_shape || !m->slot_law) goto out;
    for (j = 0; (size_t)j < n; j++) {
        m->slot_cp[j] = ck[j].b;
        m->slot_shape[j] = ck[j].c;
        m->slot_law[j] = m->pair_law[ck[j].i];
    }
    m->nslot = (int)n;
    st = CD_OK;
out:
    if (st == CD_ENOMEM) seterr(err, CD_ENOMEM, "out of memory");
    free(skip); free(pk); free(ck); free(body_adr); free(body_cp); free(sys_adr); free(sys_cp);
    return st;
}

cd_status cd_model_finalize(cd_model *m, cd_error *err)
{
    int s, b, i, k, nslot = 0, ny = 0, nv = 0;
    if (!m) { seterr(err, CD_EINVAL, "model is NULL"); return CD_EINVAL; }
    if (m->finalized) return CD_OK;
    if (m->nsys == 0) { seterr(err, CD_EINVAL, "model has no system"); return CD_EINVAL; }
    if (!finite_n(m->gravity, 3)) { seterr(err, CD_EINVAL, "gravity is not finite"); return CD_EINVAL; }
    if (cd_options_check(&m->opt, err) != CD_OK) return CD_EINVAL;
    /* layout: per system [pos block | vel block], then 3 per slot */
    for (s = 0; s < m->nsys; s++) {
        int nj = m->sys_nbody[s] - 1, base = m->sys_base_type[s] == CD_BASE_FREE ? 6 : 0;
        m->sys_ndof[s] = base + nj;
        m->sys_v_adr[s] = nv;
        m->sys_y_adr[s] = ny;
        k = 0;
        for (b = m->sys_body_adr[s] + 1; b < m->sys_body_adr[s] + m->sys_nbody[s]; b++)
            m->body_dof[b] = nv + base + k++;
        nv += m->sys_ndof[s];
        ny += (base ? 7 : 0) + nj + m->sys_ndof[s];
    }
    /* slots: every check point of a pair's system/body x the pair's shape,
     * except, inside one system, check points on the shape's own body and on
     * the bodies jointed to it (they touch at the joint by construction);
     * later pairs do not duplicate a slot (build_slots) */
    free(m->shape_face_adr); free(m->shape_face_num); free(m->face_vert); free(m->face_plane);
    m->shape_face_adr = m->shape_face_num = m->face_vert = NULL;
    m->face_plane = NULL;
    {
        cd_status sst = build_slots(m, ny, err);
        if (sst != CD_OK) return sst;
    }
    nslot = m->nslot;
    /* hull faces of the convex shapes */
    m->shape_face_adr = calloc((size_t)(m->nshape ? m->nshape : 1), sizeof(int));
    m->shape_face_num = calloc((size_t)(m->nshape ? m->nshape : 1), sizeof(int));
    if (!m->shape_face_adr || !m->shape_face_num) { seterr(err, CD_ENOMEM, "out of memory"); return CD_ENOMEM; }
    m->nface = 0;
    for (i = 0; i < m->nshape; i++)
        if (m->shape_type[i] == CD_SHAPE_CONVEX) {
            m->shape_face_adr[i] = m->nface;
            m->shape_face_num[i] = hull_faces(m, i, 0, 0);
            if (m->shape_face_num[i] < 4) { /* flat (-1) or degenerate */
                seterr(err, CD_EINVAL, "convex shape %d on body '%s': its vertices span no volume", i,
                       m->body_name[m->shape_body[i]]);
                return CD_EINVAL;
            }
            m->nface += m->shape_face_num[i];
        }
    m->face_vert = malloc((size_t)(m->nface ? m->nface : 1) * 3 * sizeof(int));
    m->face_plane = malloc((size_t)(m->nface ? m->nface : 1) * 4 * sizeof(double));
    if (!m->face_vert || !m->face_plane) { seterr(err, CD_ENOMEM, "out of memory"); return CD_ENOMEM; }
    for (i = 0; i < m->nshape; i++)
        if (m->shape_type[i] == CD_SHAPE_CONVEX) hull_faces(m, i, 1, m->shape_face_adr[i]);
    m->nv = nv;
    m->ny_slot_adr = ny;
    m->ny = ny + 3 * nslot;
    m->finalized = 1;
    return CD_OK;
}
