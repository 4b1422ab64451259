/* cd_model: builder, validation and layout. Allocation happens only here and
 * in cd_data_create; once finalized the model is never written again. */
#include "capdyn/model.h"
#include "../math/cd_math.h"

#include <float.h>
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
    case CD_EBUDGET: return "evaluation budget spent";
    }
    return "unknown status";
}

const char *cd_version(void) { return CD_VERSION_STRING; }

static const char *shape_names[CD_SHAPE_NTYPES] = {
    "plane", "sphere", "box", "cylinder", "capsule", "convex"};
static const char *stepper_names[CD_STEP_NTYPES] = {
    "rkf45", "rkck", "rk8pd", "rk4imp", "msbdf", "rk4", "ros34pw2", "auto", "rodas4"};

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
    o.stepper = CD_STEP_AUTO;
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
    o.max_evals = 0;
    o.jacobian = CD_JAC_MODEL;
    o.equilibrium_start = 0;
    o.broad_phase = 1;
    return o;
}

cd_status cd_options_check(const cd_options *o, cd_error *err)
{
    if (!o) {
        cd_error_set(err, CD_EINVAL, "cd_options_check: %s is NULL", "the options");
        return CD_EINVAL;
    }
    if (!o) { seterr(err, CD_EINVAL, "options are NULL"); return CD_EINVAL; }
    if (o->stepper < 0 || o->stepper >= CD_STEP_NTYPES) { seterr(err, CD_EINVAL, "unknown stepper %d", (int)o->stepper); return CD_EINVAL; }
    if (!(isfinite(o->rtol) && isfinite(o->atol) && o->rtol >= 0 && o->atol >= 0 && o->rtol + o->atol > 0)) {
        seterr(err, CD_EINVAL, "tolerances must be finite, >= 0 and not both zero (rtol %g, atol %g)", o->rtol, o->atol);
        return CD_EINVAL;
    }
    if (o->rtol > 0 && o->rtol < CD_RTOL_MIN) {
        /* below ~64 ulps of 1 no step can meet it: the step size collapses and a call never returns */
        seterr(err, CD_EINVAL, "rtol %g is below %g, which double precision cannot meet (use 0 for a pure atol)",
               o->rtol, CD_RTOL_MIN);
        return CD_EINVAL;
    }
    if (!(o->h_init > 0 && isfinite(o->h_init)) || !(o->h_max >= 0) || !(o->h_min >= 0) ||
        !(o->h_fixed > 0 && isfinite(o->h_fixed)) || o->max_steps < 1 || !(o->event_tol > 0) || !(o->dwell >= 0) ||
        !(o->v_reg > 0) || !(o->fd_eps > 0) || o->max_evals < 0 || (o->equilibrium_start != 0 && o->equilibrium_start != 1)) {
        seterr(err, CD_EINVAL, "integrator options out of range (steps, tolerances and budgets must be positive)");
        return CD_EINVAL;
    }
    if (o->jacobian != CD_JAC_MODEL && o->jacobian != CD_JAC_FD) {
        seterr(err, CD_EINVAL, "options: jacobian must be CD_JAC_MODEL (0) or CD_JAC_FD (1), got %d", o->jacobian);
        return CD_EINVAL;
    }
    if (o->broad_phase != 0 && o->broad_phase != 1) {
        seterr(err, CD_EINVAL, "option broad_phase must be 0 or 1, got %d", o->broad_phase);
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
    l.pt = 1.0; l.qt = 1.0;
    l.pull = 0;
    l.damping = CD_DAMP_LINEAR;
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

/* A body or link as messages name it: 'name' in quotes, or, unnamed, its
 * place ("the unnamed link 2 of system 'arm'", "body 3 (unnamed)"), so
 * that no message says "joint ''" (issue 24). */
static const char *body_label(const cd_model *m, int b, char *buf, size_t len)
{
    const char *n = b >= 0 && b < m->nbody ? m->body_name[b] : NULL;
    if (n && n[0]) snprintf(buf, len, "'%s'", n);
    else snprintf(buf, len, "body %d (unnamed)", b);
    return buf;
}
static const char *link_label(const cd_model *m, int sys, const char *name, char *buf, size_t len)
{
    if (name && name[0]) snprintf(buf, len, "'%s'", name);
    else if (sys >= 0 && sys < m->nsys)
        snprintf(buf, len, "the unnamed link %d of system '%s'", m->sys_nbody[sys], m->sys_name[sys]);
    else snprintf(buf, len, "an unnamed link");
    return buf;
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
    free(m->body_qd0); free(m->body_spring); free(m->body_damping); free(m->body_fric); free(m->body_limit);
    free(m->body_lim_id); free(m->body_fric_id); free(m->lim_body); free(m->fric_body); free(m->body_presc);
    free(m->body_presc_prm); free(m->body_wp_adr); free(m->body_wp_n);
    for (i = 0; i < m->nu; i++) free(m->act_name[i]);
    free(m->act_name); free(m->act_type); free(m->act_prm); free(m->act_motor); free(m->act_tbl_adr);
    free(m->act_tbl_n); free(m->act_trn_adr); free(m->act_trn_n); free(m->trn_body); free(m->trn_ratio);
    free(m->body_act); free(m->tbl_t); free(m->tbl_v); free(m->breaks);
    for (i = 0; i < m->nfinger; i++) free(m->finger_name[i]);
    free(m->finger_name); free(m->finger_type); free(m->finger_jnt_adr); free(m->finger_jnt_n); free(m->fjnt_body);
    free(m->fjnt_sync); free(m->fjnt_ratio); free(m->finger_prm); free(m->finger_tbl_adr); free(m->finger_tbl_n);
    free(m->cp_body); free(m->cp_pos); free(m->cp_radius);
    free(m->shape_body); free(m->shape_type); free(m->shape_pos); free(m->shape_rot);
    free(m->shape_size); free(m->shape_vert_adr); free(m->shape_vert_num); free(m->vert); free(m->shape_rbound);
    free(m->shape_face_adr); free(m->shape_face_num); free(m->face_vert); free(m->face_plane); free(m->face_run);
    free(m->law); free(m->pair_sys); free(m->pair_body); free(m->pair_shape); free(m->pair_law);
    free(m->group_adr); free(m->group_num); free(m->group_pos); free(m->group_radius);
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

/* A body's mass: positive, finite and not subnormal (a subnormal mass has
 * lost its precision, and 1/m is inf). Returns NULL if valid, else a reason. */
static const char *mass_problem(double mass)
{
    if (mass > 0 && mass < DBL_MIN) return "mass must not be below 2.2e-308 (subnormal)";
    if (!(mass > 0) || !isfinite(mass)) return "mass must be a positive finite number";
    return NULL;
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
    ok |= RS(m->body_qd0, n); ok |= RS(m->body_spring, 2 * n); ok |= RS(m->body_damping, n);
    ok |= RS(m->body_fric, 3 * n); ok |= RS(m->body_limit, 6 * n); ok |= RS(m->body_lim_id, n);
    ok |= RS(m->body_fric_id, n); ok |= RS(m->body_presc, n); ok |= RS(m->body_presc_prm, 6 * n);
    ok |= RS(m->body_wp_adr, n); ok |= RS(m->body_wp_n, n); ok |= RS(m->body_act, n);
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
    memset(m->body_spring + 2 * b, 0, 2 * sizeof(double));
    m->body_damping[b] = 0;
    memset(m->body_fric + 3 * b, 0, 3 * sizeof(double));
    memset(m->body_limit + 6 * b, 0, 6 * sizeof(double));
    m->body_lim_id[b] = m->body_fric_id[b] = -1;
    m->body_presc[b] = CD_PRESCRIBE_NONE;
    memset(m->body_presc_prm + 6 * b, 0, 6 * sizeof(double));
    m->body_wp_adr[b] = m->body_wp_n[b] = 0;
    m->body_act[b] = -1;
    m->nbody++;
    return b;
}

int cd_model_add_system(cd_model *m, const cd_system_desc *s, cd_error *err)
{
    int id, n, ok = 0, b;
    const char *why;
    double z3[3] = {0, 0, 0}, R[9], ax[3] = {0, 0, 1}, qs[4];
    FROZEN_CHECK(-1);
    if (!s) { seterr(err, CD_EINVAL, "system description is NULL"); return -1; }
    if (s->type != CD_BASE_FREE && s->type != CD_BASE_FIXED) {
        seterr(err, CD_EINVAL, "system '%s': base type must be free or fixed", s->name ? s->name : "");
        return -1;
    }
    if ((why = mass_problem(s->mass)) != NULL) {
        seterr(err, CD_EINVAL, "system '%s': base %s, got %g", s->name ? s->name : "", why, s->mass);
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
    memcpy(qs, s->quat, sizeof qs);
    if (!cd_quat_normalize(qs)) {
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
    memcpy(m->sys_quat0 + 4 * id, qs, sizeof qs);
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
    char nmbuf[160];
    const char *why, *nm;
    double ax[3];
    int b;
    FROZEN_CHECK(-1);
    if (!l) { seterr(err, CD_EINVAL, "link description is NULL"); return -1; }
    nm = link_label(m, sys, l->name, nmbuf, sizeof nmbuf);
    if (sys < 0 || sys >= m->nsys) { seterr(err, CD_EINVAL, "link %s: no system %d", nm, sys); return -1; }
    if (sys != m->nsys - 1) {
        seterr(err, CD_EINVAL, "link %s: links must be added to the most recently added system", nm);
        return -1;
    }
    if (l->parent < m->sys_body_adr[sys] || l->parent >= m->nbody) {
        seterr(err, CD_EINVAL, "link %s: parent %d is not an existing body of system '%s'", nm,
               l->parent, m->sys_name[sys]);
        return -1;
    }
    if (l->type != CD_JOINT_REVOLUTE && l->type != CD_JOINT_PRISMATIC) {
        seterr(err, CD_EINVAL, "link %s: joint type must be revolute or prismatic", nm);
        return -1;
    }
    if ((why = mass_problem(l->mass)) != NULL) {
        seterr(err, CD_EINVAL, "link %s: %s, got %g", nm, why, l->mass);
        return -1;
    }
    if ((why = inertia_problem(l->inertia)) != NULL) {
        seterr(err, CD_EINVAL, "link %s: %s", nm, why);
        return -1;
    }
    if (!finite_n(l->pos, 3) || !finite_n(l->com, 3) || !finite_n(l->rot, 9) || !finite_n(l->axis, 3) ||
        !isfinite(l->q0) || !isfinite(l->qd0)) {
        seterr(err, CD_EINVAL, "link %s: non-finite value in position, axis, CoM or initial state", nm);
        return -1;
    }
    if (!is_rotation(l->rot)) {
        seterr(err, CD_EINVAL, "link %s: joint frame rotation is not a proper rotation", nm);
        return -1;
    }
    cd_v3_copy(ax, l->axis);
    if (cd_v3_normalize(ax) < 1e-12) {
        seterr(err, CD_EINVAL, "link %s: joint axis is zero", nm);
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
    ok |= RS(m->shape_vert_num, n); ok |= RS(m->shape_rbound, n);
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
    /* bounding sphere about the shape origin (broad phase of open slots, contact.c) */
    switch (type) {
    case CD_SHAPE_SPHERE: m->shape_rbound[id] = sz[0]; break;
    case CD_SHAPE_BOX: m->shape_rbound[id] = cd_v3_norm(sz); break;
    case CD_SHAPE_CYLINDER: m->shape_rbound[id] = sqrt(sz[0] * sz[0] + sz[1] * sz[1]); break;
    case CD_SHAPE_CAPSULE: m->shape_rbound[id] = sz[0] + sz[1]; break;
    case CD_SHAPE_CONVEX:
        m->shape_rbound[id] = 0;
        for (i = 0; i < nvert; i++) {
            double r = cd_v3_norm(verts + 3 * i);
            if (r > m->shape_rbound[id]) m->shape_rbound[id] = r;
        }
        break;
    default: m->shape_rbound[id] = HUGE_VAL; break;
    }
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
    if (!(l->pt >= 1) || !isfinite(l->pt)) { seterr(err, CD_EINVAL, "contact law: p_t must be >= 1, got %g", l->pt); return -1; }
    if (!(l->qt > 0) || !isfinite(l->qt)) { seterr(err, CD_EINVAL, "contact law: q_t must be > 0, got %g", l->qt); return -1; }
    if (l->pull != 0 && l->pull != 1) { seterr(err, CD_EINVAL, "contact law: pull must be 0 or 1, got %d", l->pull); return -1; }
    if (l->damping != CD_DAMP_LINEAR && l->damping != CD_DAMP_HUNT_CROSSLEY) {
        seterr(err, CD_EINVAL, "contact law: damping must be CD_DAMP_LINEAR (0) or CD_DAMP_HUNT_CROSSLEY (1), got %d",
               l->damping);
        return -1;
    }
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

cd_actuator_desc cd_actuator_desc_default(void)
{
    cd_actuator_desc a;
    memset(&a, 0, sizeof a);
    a.type = CD_ACT_NONE;
    return a;
}

cd_joint_props cd_joint_props_default(void)
{
    cd_joint_props p;
    memset(&p, 0, sizeof p);
    p.prescribe = CD_PRESCRIBE_NONE;
    return p;
}

/* appends n (t, v) rows to the shared time tables; returns their address or -1 */
static int add_rows(cd_model *m, const double *t, const double *v, int n)
{
    int at = m->ntbl;
    if (RS(m->tbl_t, m->ntbl + n) || RS(m->tbl_v, m->ntbl + n)) return -1;
    memcpy(m->tbl_t + at, t, (size_t)n * sizeof(double));
    memcpy(m->tbl_v + at, v, (size_t)n * sizeof(double));
    m->ntbl += n;
    return at;
}

static int rows_ok(const double *t, const double *v, int n)
{
    int i;
    for (i = 0; i < n; i++)
        if (!isfinite(t[i]) || !isfinite(v[i]) || (i > 0 && !(t[i] > t[i - 1]))) return i;
    return -1;
}

static int is_joint(const cd_model *m, int body) { return body >= 0 && body < m->nbody && m->body_parent[body] >= 0; }

/* validates an actuator description; "what" names it in messages */
static cd_status actuator_check(const cd_model *m, const cd_actuator_desc *a, const char *what, cd_error *err)
{
    int i, j, bad;
    if (!a || a->type < CD_ACT_NONE || a->type >= CD_ACT_NTYPES) {
        seterr(err, CD_EINVAL, "actuator %s: unknown type", what);
        return CD_EINVAL;
    }
    if (!isfinite(a->tau0) || !isfinite(a->kp) || !isfinite(a->kd) || !isfinite(a->qref)) {
        seterr(err, CD_EINVAL, "actuator %s: non-finite parameter", what);
        return CD_EINVAL;
    }
    if (a->type == CD_ACT_TABLE || a->type == CD_ACT_STEPS) {
        if (!a->tbl_t || !a->tbl_v || a->ntbl < 1) {
            seterr(err, CD_EINVAL, "actuator %s: a table needs at least one (t, value) row", what);
            return CD_EINVAL;
        }
        if ((bad = rows_ok(a->tbl_t, a->tbl_v, a->ntbl)) >= 0) {
            seterr(err, CD_EINVAL, "actuator %s: table row %d: times must be finite and strictly increasing", what, bad);
            return CD_EINVAL;
        }
    }
    if (a->ntrn < 1 || !a->trn_body || !a->trn_ratio) {
        seterr(err, CD_EINVAL, "actuator %s: needs at least one joint in its transmission", what);
        return CD_EINVAL;
    }
    for (i = 0; i < a->ntrn; i++) {
        if (!is_joint(m, a->trn_body[i])) {
            seterr(err, CD_EINVAL, "actuator %s: transmission entry %d: body %d is not a joint body", what, i, a->trn_body[i]);
            return CD_EINVAL;
        }
        if (!isfinite(a->trn_ratio[i])) {
            seterr(err, CD_EINVAL, "actuator %s: transmission ratio %d is not finite", what, i);
            return CD_EINVAL;
        }
        for (j = 0; j < i; j++)
            if (a->trn_body[j] == a->trn_body[i]) {
                seterr(err, CD_EINVAL, "actuator %s: joint '%s' appears twice in the transmission", what,
                       m->body_name[a->trn_body[i]]);
                return CD_EINVAL;
            }
    }
    if (!(a->stall_torque >= 0) || !isfinite(a->stall_torque) || !(a->noload_speed >= 0) || !isfinite(a->noload_speed) ||
        ((a->stall_torque > 0) != (a->noload_speed > 0))) {
        seterr(err, CD_EINVAL, "actuator %s: motor model needs stall_torque > 0 and noload_speed > 0 together (got %g, %g)",
               what, a->stall_torque, a->noload_speed);
        return CD_EINVAL;
    }
    return CD_OK;
}

/* writes actuator id (id == nu appends) */
static int actuator_store(cd_model *m, int id, const cd_actuator_desc *a, cd_error *err)
{
    int n = m->nu + 1, ok = 0, adr = 0;
    if (id == m->nu) {
        ok |= RS(m->act_name, n); ok |= RS(m->act_type, n); ok |= RS(m->act_prm, 4 * n);
        ok |= RS(m->act_motor, 2 * n); ok |= RS(m->act_tbl_adr, n); ok |= RS(m->act_tbl_n, n);
        ok |= RS(m->act_trn_adr, n); ok |= RS(m->act_trn_n, n);
        if (ok) goto nomem;
        m->act_name[id] = NULL;
    }
    if (a->type == CD_ACT_TABLE || a->type == CD_ACT_STEPS) {
        adr = add_rows(m, a->tbl_t, a->tbl_v, a->ntbl);
        if (adr < 0) goto nomem;
    }
    if (RS(m->trn_body, m->ntrn + a->ntrn) || RS(m->trn_ratio, m->ntrn + a->ntrn)) goto nomem;
    free(m->act_name[id]);
    m->act_name[id] = dupstr(a->name);
    if (!m->act_name[id]) goto nomem;
    /* (a replaced actuator's old rows stay unused in the tables: building is one-off) */
    memcpy(m->trn_body + m->ntrn, a->trn_body, (size_t)a->ntrn * sizeof(int));
    memcpy(m->trn_ratio + m->ntrn, a->trn_ratio, (size_t)a->ntrn * sizeof(double));
    m->act_trn_adr[id] = m->ntrn;
    m->act_trn_n[id] = a->ntrn;
    m->ntrn += a->ntrn;
    m->act_type[id] = a->type;
    m->act_prm[4 * id] = a->tau0;
    m->act_prm[4 * id + 1] = a->kp;
    m->act_prm[4 * id + 2] = a->kd;
    m->act_prm[4 * id + 3] = a->qref;
    m->act_motor[2 * id] = a->stall_torque;
    m->act_motor[2 * id + 1] = a->noload_speed;
    m->act_tbl_adr[id] = adr;
    m->act_tbl_n[id] = (a->type == CD_ACT_TABLE || a->type == CD_ACT_STEPS) ? a->ntbl : 0;
    if (id == m->nu) m->nu++;
    return id;
nomem:
    seterr(err, CD_ENOMEM, "out of memory");
    return -1;
}

int cd_model_add_actuator(cd_model *m, const cd_actuator_desc *a, cd_error *err)
{
    FROZEN_CHECK(-1);
    if (actuator_check(m, a, a && a->name ? a->name : "", err) != CD_OK) return -1;
    return actuator_store(m, m->nu, a, err);
}

cd_status cd_model_set_actuator(cd_model *m, int body, const cd_actuator *a, cd_error *err)
{
    if (!m) { /* (a NULL actuator is refused below, naming the joint) */
        cd_error_set(err, CD_EINVAL, "cd_model_set_actuator: %s is NULL", "the model");
        return CD_EINVAL;
    }
    cd_actuator_desc d = cd_actuator_desc_default();
    double one = 1.0;
    char what[160];
    int id;
    FROZEN_CHECK(CD_EINVAL);
    if (!is_joint(m, body)) {
        seterr(err, CD_EINVAL, "actuator: body %d is not a joint body", body);
        return CD_EINVAL;
    }
    if (!a) { seterr(err, CD_EINVAL, "actuator on '%s': unknown type (description is NULL)", m->body_name[body]); return CD_EINVAL; }
    d.name = m->body_name[body];
    d.type = a->type;
    d.tau0 = a->tau0; d.kp = a->kp; d.kd = a->kd; d.qref = a->qref;
    d.tbl_t = a->tbl_t; d.tbl_v = a->tbl_v; d.ntbl = a->ntbl;
    d.ntrn = 1; d.trn_body = &body; d.trn_ratio = &one;
    snprintf(what, sizeof what, "on '%s'", m->body_name[body]);
    if (actuator_check(m, &d, what, err) != CD_OK) return CD_EINVAL;
    id = actuator_store(m, m->body_act[body] >= 0 ? m->body_act[body] : m->nu, &d, err);
    if (id < 0) return CD_ENOMEM;
    m->body_act[body] = id;
    return CD_OK;
}

cd_finger_desc cd_finger_desc_default(void)
{
    cd_finger_desc f;
    memset(&f, 0, sizeof f);
    f.type = CD_FINGER_SPACE;
    return f;
}

int cd_model_add_finger(cd_model *m, const cd_finger_desc *f, cd_error *err)
{
    int id, n, i, j, ok = 0, bad;
    const char *nm;
    FROZEN_CHECK(-1);
    if (!f) { seterr(err, CD_EINVAL, "finger: description is NULL"); return -1; }
    nm = f->name ? f->name : "";
    if (f->type < 0 || f->type >= CD_FINGER_NTYPES) { seterr(err, CD_EINVAL, "finger '%s': unknown type", nm); return -1; }
    if (f->njoint < 1 || !f->joint_body) { seterr(err, CD_EINVAL, "finger '%s': needs at least one joint", nm); return -1; }
    for (i = 0; i < f->njoint; i++) {
        if (!is_joint(m, f->joint_body[i])) {
            seterr(err, CD_EINVAL, "finger '%s': joint %d (body %d) is not a joint body", nm, i, f->joint_body[i]);
            return -1;
        }
        for (j = 0; j < i; j++)
            if (f->joint_body[j] == f->joint_body[i]) { seterr(err, CD_EINVAL, "finger '%s': a joint appears twice", nm); return -1; }
        if ((f->sync && !isfinite(f->sync[i])) || (f->ratio && !isfinite(f->ratio[i]))) {
            seterr(err, CD_EINVAL, "finger '%s': non-finite sync gain or ratio", nm);
            return -1;
        }
    }
    if (!(f->wire_K > 0) || !isfinite(f->wire_K) || !(f->wire_D >= 0) || !isfinite(f->wire_D) || !(f->threshold > 0) ||
        !isfinite(f->threshold) || !isfinite(f->grasp_torque) || !(f->torque_limit >= 0) || !isfinite(f->torque_limit) ||
        !(f->open_at >= 0) || !isfinite(f->open_at)) {
        seterr(err, CD_EINVAL, "finger '%s': needs wire_K > 0, wire_D >= 0, threshold > 0, torque_limit >= 0, open_at >= 0, all finite", nm);
        return -1;
    }
    if (!f->sched_t || !f->sched_q || f->nsched < 1) { seterr(err, CD_EINVAL, "finger '%s': needs a closing schedule", nm); return -1; }
    if ((bad = rows_ok(f->sched_t, f->sched_q, f->nsched)) >= 0) {
        seterr(err, CD_EINVAL, "finger '%s': schedule row %d: times must be finite and strictly increasing", nm, bad);
        return -1;
    }
    id = m->nfinger;
    n = id + 1;
    ok |= RS(m->finger_name, n); ok |= RS(m->finger_type, n); ok |= RS(m->finger_jnt_adr, n); ok |= RS(m->finger_jnt_n, n);
    ok |= RS(m->finger_prm, 6 * n); ok |= RS(m->finger_tbl_adr, n); ok |= RS(m->finger_tbl_n, n);
    ok |= RS(m->fjnt_body, m->nfjnt + f->njoint); ok |= RS(m->fjnt_sync, m->nfjnt + f->njoint);
    ok |= RS(m->fjnt_ratio, m->nfjnt + f->njoint);
    if (ok) { seterr(err, CD_ENOMEM, "out of memory"); return -1; }
    m->finger_name[id] = dupstr(f->name);
    if (!m->finger_name[id]) { seterr(err, CD_ENOMEM, "out of memory"); return -1; }
    m->finger_tbl_adr[id] = add_rows(m, f->sched_t, f->sched_q, f->nsched);
    if (m->finger_tbl_adr[id] < 0) { free(m->finger_name[id]); seterr(err, CD_ENOMEM, "out of memory"); return -1; }
    m->finger_tbl_n[id] = f->nsched;
    m->finger_type[id] = f->type;
    m->finger_jnt_adr[id] = m->nfjnt;
    m->finger_jnt_n[id] = f->njoint;
    for (i = 0; i < f->njoint; i++) {
        double r = (double)(f->njoint - i);
        m->fjnt_body[m->nfjnt + i] = f->joint_body[i];
        m->fjnt_sync[m->nfjnt + i] = f->sync ? f->sync[i] : 1.0;
        m->fjnt_ratio[m->nfjnt + i] = f->ratio ? f->ratio[i] : r * r; /* quadratic from the tip (1) to the base (n^2) */
    }
    m->nfjnt += f->njoint;
    m->finger_prm[6 * id] = f->wire_K;
    m->finger_prm[6 * id + 1] = f->wire_D;
    m->finger_prm[6 * id + 2] = f->threshold;
    m->finger_prm[6 * id + 3] = f->grasp_torque;
    m->finger_prm[6 * id + 4] = f->torque_limit;
    m->finger_prm[6 * id + 5] = f->open_at;
    m->nfinger++;
    return id;
}

cd_status cd_model_set_joint(cd_model *m, int b, const cd_joint_props *p, cd_error *err)
{
    char nmbuf[160];
    if (!m || !p) {
        cd_error_set(err, CD_EINVAL, "cd_model_set_joint: %s is NULL", !m ? "the model" : "the joint properties");
        return CD_EINVAL;
    }
    const char *nm;
    int bad;
    FROZEN_CHECK(CD_EINVAL);
    if (!is_joint(m, b)) { seterr(err, CD_EINVAL, "joint properties: body %d is not a joint body", b); return CD_EINVAL; }
    nm = body_label(m, b, nmbuf, sizeof nmbuf);
    if (!p) { seterr(err, CD_EINVAL, "joint %s: properties are NULL", nm); return CD_EINVAL; }
    if (!(p->stiffness >= 0) || !isfinite(p->stiffness) || !isfinite(p->rest) || !(p->damping >= 0) ||
        !isfinite(p->damping) || !(p->friction >= 0) || !isfinite(p->friction) || !(p->friction_k >= 0) ||
        !isfinite(p->friction_k) || !(p->friction_d >= 0) || !isfinite(p->friction_d)) {
        seterr(err, CD_EINVAL, "joint %s: stiffness, damping and friction must be finite and >= 0", nm);
        return CD_EINVAL;
    }
    if (p->limited) {
        if (!isfinite(p->lower) || !isfinite(p->upper) || !(p->lower < p->upper)) {
            seterr(err, CD_EINVAL, "joint %s: limits must be finite with lower < upper (got %g, %g)", nm, p->lower, p->upper);
            return CD_EINVAL;
        }
        if (!(p->stop_K >= 0) || !isfinite(p->stop_K) || !(p->stop_D >= 0) || !isfinite(p->stop_D) ||
            !(p->stop_p == 0 || p->stop_p >= 1) || !isfinite(p->stop_p) || !(p->stop_q >= 0) || !isfinite(p->stop_q)) {
            seterr(err, CD_EINVAL, "joint %s: stop law needs K, D >= 0, p >= 1, q > 0 (0 = default)", nm);
            return CD_EINVAL;
        }
    }
    if (p->prescribe < CD_PRESCRIBE_NONE || p->prescribe > CD_PRESCRIBE_WAYPOINTS) {
        seterr(err, CD_EINVAL, "joint %s: unknown prescribed-motion type", nm);
        return CD_EINVAL;
    }
    if (p->prescribe == CD_PRESCRIBE_VELOCITY && (!isfinite(p->presc_v) || !isfinite(p->presc_t0))) {
        seterr(err, CD_EINVAL, "joint %s: prescribed velocity and start time must be finite", nm);
        return CD_EINVAL;
    }
    if (p->prescribe == CD_PRESCRIBE_WAYPOINTS) {
        if (!p->presc_t || !p->presc_q || p->npresc < 1) {
            seterr(err, CD_EINVAL, "joint %s: prescribed waypoints need at least one (t, q) row", nm);
            return CD_EINVAL;
        }
        if ((bad = rows_ok(p->presc_t, p->presc_q, p->npresc)) >= 0) {
            seterr(err, CD_EINVAL, "joint %s: waypoint %d: times must be finite and strictly increasing", nm, bad);
            return CD_EINVAL;
        }
        m->body_wp_adr[b] = add_rows(m, p->presc_t, p->presc_q, p->npresc);
        if (m->body_wp_adr[b] < 0) { seterr(err, CD_ENOMEM, "out of memory"); return CD_ENOMEM; }
        m->body_wp_n[b] = p->npresc;
    }
    m->body_spring[2 * b] = p->stiffness;
    m->body_spring[2 * b + 1] = p->rest;
    m->body_damping[b] = p->damping;
    m->body_fric[3 * b] = p->friction;
    m->body_fric[3 * b + 1] = p->friction_k;
    m->body_fric[3 * b + 2] = p->friction_d;
    m->body_lim_id[b] = p->limited ? 0 : -1; /* numbered at finalize */
    m->body_limit[6 * b] = p->lower;
    m->body_limit[6 * b + 1] = p->upper;
    m->body_limit[6 * b + 2] = p->stop_K;
    m->body_limit[6 * b + 3] = p->stop_D;
    m->body_limit[6 * b + 4] = p->stop_p;
    m->body_limit[6 * b + 5] = p->stop_q;
    m->body_presc[b] = p->prescribe;
    m->body_presc_prm[6 * b] = p->presc_v;
    m->body_presc_prm[6 * b + 1] = p->presc_t0;
    return CD_OK;
}

cd_status cd_model_prescribe_base(cd_model *m, int sys, const double v[3], const double w[3], cd_error *err)
{
    if (!m || !v || !w) {
        cd_error_set(err, CD_EINVAL, "cd_model_prescribe_base: %s is NULL", !m ? "the model" : !v ? "v" : "w");
        return CD_EINVAL;
    }
    int b;
    FROZEN_CHECK(CD_EINVAL);
    if (sys < 0 || sys >= m->nsys || m->sys_base_type[sys] != CD_BASE_FREE) {
        seterr(err, CD_EINVAL, "prescribed base: system %d is not a free-floating system", sys);
        return CD_EINVAL;
    }
    if (!v || !w || !finite_n(v, 3) || !finite_n(w, 3)) {
        seterr(err, CD_EINVAL, "prescribed base of '%s': velocities must be finite", m->sys_name[sys]);
        return CD_EINVAL;
    }
    b = m->sys_body_adr[sys];
    m->body_presc[b] = CD_PRESCRIBE_VELOCITY;
    cd_v3_copy(m->body_presc_prm + 6 * b, v);
    cd_v3_copy(m->body_presc_prm + 6 * b + 3, w);
    /* the initial velocities follow the prescription */
    cd_v3_copy(m->sys_vel0 + 3 * sys, v);
    cd_v3_copy(m->sys_angvel0 + 3 * sys, w);
    return CD_OK;
}

cd_status cd_model_set_user_switches(cd_model *m, int n, cd_error *err)
{
    if (!m) {
        cd_error_set(err, CD_EINVAL, "cd_model_set_user_switches: %s is NULL", "the model");
        return CD_EINVAL;
    }
    FROZEN_CHECK(CD_EINVAL);
    if (n < 0 || n > 1000000) { seterr(err, CD_EINVAL, "user switches: count %d out of range [0, 1e6]", n); return CD_EINVAL; }
    m->nuser = n;
    return CD_OK;
}

int cd_model_actuator_id(const cd_model *m, const char *name)
{
    int i;
    for (i = 0; m && name && i < m->nu; i++)
        if (m->act_name[i] && strcmp(m->act_name[i], name) == 0) return i;
    return -1;
}

/* Moment of inertia of the subtree rooted at joint body b about its joint
 * axis at the initial configuration (the other joints at q0): the scale for
 * the default damping of its stop and its friction's stick spring. */
static double subtree_axis_inertia(const cd_model *m, int b)
{
    int s = m->body_sys[b], end = m->sys_body_adr[s] + m->sys_nbody[s], i, k;
    double *R = NULL, *x = NULL, I = 0, ax[3];
    R = malloc((size_t)(end - b) * 9 * sizeof(double));
    x = malloc((size_t)(end - b) * 3 * sizeof(double));
    if (!R || !x) { free(R); free(x); return -1.0; } /* out of memory: finalize reports it */
    /* frames relative to b's joint frame at q = q0 */
    cd_m3_identity(R);
    cd_v3_zero(x);
    cd_v3_copy(ax, m->body_axis + 3 * b);
    for (i = b; i < end; i++) {
        double Rq[9], Rf[9], t[3], c[3], r[3], Iw[9], Ia[3];
        int in = (i == b), p = m->body_parent[i];
        if (!in) {
            for (k = p; k > b; k = m->body_parent[k]) {}
            if (k != b) continue; /* not in the subtree */
            cd_m3_mulv(t, R + 9 * (p - b), m->body_jnt_pos + 3 * i);
            cd_v3_add(x + 3 * (i - b), x + 3 * (p - b), t);
            cd_m3_mul(Rf, R + 9 * (p - b), m->body_jnt_rot + 9 * i);
            if (m->body_jnt_type[i] == CD_JOINT_REVOLUTE) {
                cd_m3_axis_angle(Rq, m->body_axis + 3 * i, m->body_q0[i]);
                cd_m3_mul(R + 9 * (i - b), Rf, Rq);
            } else {
                cd_m3_copy(R + 9 * (i - b), Rf);
                cd_m3_mulv(t, Rf, m->body_axis + 3 * i);
                cd_v3_axpy(x + 3 * (i - b), m->body_q0[i], t);
            }
        }
        cd_m3_mulv(t, R + 9 * (i - b), m->body_com + 3 * i);
        cd_v3_add(c, x + 3 * (i - b), t);
        if (m->body_jnt_type[b] == CD_JOINT_PRISMATIC) { I += m->body_mass[i]; continue; } /* a slider: its mass */
        cd_m3_rotsym(Iw, R + 9 * (i - b), m->body_inertia + 9 * i);
        cd_m3_mulv(Ia, Iw, ax);
        cd_v3_cross(r, c, ax);
        I += cd_v3_dot(ax, Ia) + m->body_mass[i] * cd_v3_dot(r, r);
    }
    free(R);
    free(x);
    return I;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Finalize's joint part: numbers the stops and frictions, resolves their
 * default laws, checks q0 against the limits and collects the schedule's
 * breakpoints. */
static cd_status finalize_joints(cd_model *m, cd_error *err)
{
    int b, nl = 0, nf = 0, np = 0, a, i, nb = 0;
    for (b = 0; b < m->nbody; b++) {
        if (m->body_presc[b] != CD_PRESCRIBE_NONE) np++;
        if (m->body_parent[b] < 0) continue;
        if (m->body_lim_id[b] >= 0) {
            double *L = m->body_limit + 6 * b, Ia = subtree_axis_inertia(m, b);
            if (Ia < 0) { seterr(err, CD_ENOMEM, "out of memory"); return CD_ENOMEM; }
            if (m->body_q0[b] < L[0] || m->body_q0[b] > L[1]) {
                char lb[160];
                seterr(err, CD_EINVAL, "joint %s: initial position %g is outside its limits [%g, %g]",
                       body_label(m, b, lb, sizeof lb),
                       m->body_q0[b], L[0], L[1]);
                return CD_EINVAL;
            }
            if (L[2] == 0) L[2] = 1e3;
            if (L[4] == 0) L[4] = 1.0;
            if (L[5] == 0) L[5] = 1.0;
            if (L[3] == 0) L[3] = 2.0 * sqrt(L[2] * Ia);
            m->body_lim_id[b] = nl++;
        }
        if (m->body_fric[3 * b] > 0) {
            double *F = m->body_fric + 3 * b;
            if (F[1] == 0) F[1] = F[0] / 1e-4;
            if (F[2] == 0) {
                double Ia = subtree_axis_inertia(m, b);
                if (Ia < 0) { seterr(err, CD_ENOMEM, "out of memory"); return CD_ENOMEM; }
                F[2] = 2.0 * sqrt(F[1] * Ia);
            }
            m->body_fric_id[b] = nf++;
        } else {
            m->body_fric_id[b] = -1;
        }
    }
    free(m->lim_body); free(m->fric_body); free(m->breaks);
    m->lim_body = malloc((size_t)(nl ? nl : 1) * sizeof(int));
    m->fric_body = malloc((size_t)(nf ? nf : 1) * sizeof(int));
    m->breaks = malloc((size_t)(m->ntbl + m->nbody + 1) * sizeof(double));
    if (!m->lim_body || !m->fric_body || !m->breaks) { seterr(err, CD_ENOMEM, "out of memory"); return CD_ENOMEM; }
    for (b = 0; b < m->nbody; b++) {
        if (m->body_parent[b] >= 0 && m->body_lim_id[b] >= 0) m->lim_body[m->body_lim_id[b]] = b;
        if (m->body_fric_id[b] >= 0) m->fric_body[m->body_fric_id[b]] = b;
        if (m->body_presc[b] == CD_PRESCRIBE_WAYPOINTS)
            for (i = 0; i < m->body_wp_n[b]; i++) m->breaks[nb++] = m->tbl_t[m->body_wp_adr[b] + i];
        if (m->body_presc[b] == CD_PRESCRIBE_VELOCITY && m->body_parent[b] >= 0) m->breaks[nb++] = m->body_presc_prm[6 * b + 1];
    }
    for (a = 0; a < m->nu; a++)
        for (i = 0; i < m->act_tbl_n[a]; i++) m->breaks[nb++] = m->tbl_t[m->act_tbl_adr[a] + i];
    for (a = 0; a < m->nfinger; a++)
        for (i = 0; i < m->finger_tbl_n[a]; i++) m->breaks[nb++] = m->tbl_t[m->finger_tbl_adr[a] + i];
    qsort(m->breaks, (size_t)nb, sizeof(double), cmp_double);
    for (i = 0, a = 0; i < nb; i++)
        if (a == 0 || m->breaks[i] != m->breaks[a - 1]) m->breaks[a++] = m->breaks[i];
    m->nbreak = a;
    m->nlim = nl;
    m->nfric = nf;
    m->npresc = np;
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

/* Is (i, j, k) a non-collinear triple of vertex indices (1e-12 of size^2)? */
static int hull_triple(const double *v, int i, int j, int k, double size, double n[3])
{
    double a[3], b[3], len;
    cd_v3_sub(a, v + 3 * j, v + 3 * i);
    cd_v3_sub(b, v + 3 * k, v + 3 * i);
    cd_v3_cross(n, a, b);
    len = cd_v3_norm(n);
    if (!(len > 1e-12 * size * size)) return 0;
    cd_v3_scale(n, n, 1.0 / len);
    return 1;
}

/* Faces of the convex hull of shape sh's vertices, by brute force over
 * vertex triples: a triple spans a face plane when every vertex lies on one
 * side of it (within 1e-9 of the hull's size). Each face plane is emitted
 * once, from the first non-collinear triple of its vertices (in index
 * order), as a fan of triangles over the 2-D convex hull of every vertex on
 * it (Andrew's monotone chain; vertices inside the face or on its edges add
 * no triangle), wound counter-clockwise seen from outside. Every triangle of
 * a face stores the same plane. A pentagonal prism gives 16 triangles, not
 * the 40 overlapping ones of every coplanar triple. O(n^4): meant for hulls
 * of tens of vertices, run once. With store == 0 only counts. Returns the
 * number of triangles, -1 if all vertices lie in one plane (no volume), -2
 * if out of memory. */
static int hull_faces(cd_model *m, int sh, int store, int at)
{
    const double *v = m->vert + 3 * m->shape_vert_adr[sh];
    int nv = m->shape_vert_num[sh], i, j, k, l, nf = 0;
    double size = 0, c[3] = {0, 0, 0};
    int *on, *ch;
    double *q;
    for (i = 0; i < nv; i++) cd_v3_axpy(c, 1.0 / nv, v + 3 * i);
    for (i = 0; i < nv; i++) {
        double t[3], r;
        cd_v3_sub(t, v + 3 * i, c);
        r = cd_v3_norm(t);
        if (r > size) size = r;
    }
    on = malloc((size_t)(nv > 0 ? nv : 1) * sizeof(int));
    ch = malloc((size_t)(2 * nv + 1) * sizeof(int));
    q = malloc((size_t)(nv > 0 ? nv : 1) * 2 * sizeof(double));
    if (!on || !ch || !q) { free(on); free(ch); free(q); return -2; }
    for (i = 0; i < nv; i++)
        for (j = i + 1; j < nv; j++)
            for (k = j + 1; k < nv; k++) {
                double n[3], o, e1[3], e2[3];
                int pos = 0, neg = 0, non = 0, first = 0, a, b, cc, nh, lo;
                if (!hull_triple(v, i, j, k, size, n)) continue; /* collinear */
                o = cd_v3_dot(n, v + 3 * i);
                for (l = 0; l < nv && !(pos && neg); l++) {
                    double h = cd_v3_dot(n, v + 3 * l) - o;
                    if (h > 1e-9 * size) pos = 1;
                    if (h < -1e-9 * size) neg = 1;
                }
                if (pos && neg) continue;
                if (!pos && !neg) { free(on); free(ch); free(q); return -1; } /* a flat hull */
                if (pos) { cd_v3_scale(n, n, -1.0); o = -o; }
                /* the vertices on this plane; emit the face only from its first triple */
                for (l = 0; l < nv; l++)
                    if (fabs(cd_v3_dot(n, v + 3 * l) - o) <= 1e-9 * size) on[non++] = l;
                for (a = 0; a < non && !first; a++)
                    for (b = a + 1; b < non && !first; b++)
                        for (cc = b + 1; cc < non && !first; cc++) {
                            double t[3];
                            if (hull_triple(v, on[a], on[b], on[cc], size, t))
                                first = (on[a] == i && on[b] == j && on[cc] == k) ? 1 : -1;
                        }
                if (first != 1) continue;
                /* in-plane coordinates (e1, e2, n right-handed), sorted by (x, y) */
                cd_v3_sub(e1, v + 3 * j, v + 3 * i);
                cd_v3_normalize(e1);
                cd_v3_cross(e2, n, e1);
                for (a = 0; a < non; a++) {
                    double t[3];
                    cd_v3_sub(t, v + 3 * on[a], v + 3 * i);
                    q[2 * a] = cd_v3_dot(t, e1);
                    q[2 * a + 1] = cd_v3_dot(t, e2);
                }
                for (a = 1; a < non; a++) /* insertion sort: a face has few vertices */
                    for (b = a; b > 0 && (q[2 * b] < q[2 * b - 2] ||
                                          (q[2 * b] == q[2 * b - 2] && q[2 * b + 1] < q[2 * b - 1])); b--) {
                        double tx = q[2 * b], ty = q[2 * b + 1];
                        int ti = on[b];
                        q[2 * b] = q[2 * b - 2]; q[2 * b + 1] = q[2 * b - 1]; on[b] = on[b - 1];
                        q[2 * b - 2] = tx; q[2 * b - 1] = ty; on[b - 1] = ti;
                    }
                /* monotone chain, counter-clockwise; strict turns only */
#define HULL_TURN(A, B, C) ((q[2 * (B)] - q[2 * (A)]) * (q[2 * (C) + 1] - q[2 * (A) + 1]) - \
                            (q[2 * (B) + 1] - q[2 * (A) + 1]) * (q[2 * (C)] - q[2 * (A)]))
                nh = 0;
                for (a = 0; a < non; a++) {
                    while (nh >= 2 && !(HULL_TURN(ch[nh - 2], ch[nh - 1], a) > 1e-12 * size * size)) nh--;
                    ch[nh++] = a;
                }
                lo = nh + 1;
                for (a = non - 2; a >= 0; a--) {
                    while (nh >= lo && !(HULL_TURN(ch[nh - 2], ch[nh - 1], a) > 1e-12 * size * size)) nh--;
                    ch[nh++] = a;
                }
#undef HULL_TURN
                nh--; /* the last point repeats the first */
                for (a = 1; a + 1 < nh; a++) {
                    if (store) {
                        int f = at + nf;
                        m->face_vert[3 * f] = m->shape_vert_adr[sh] + on[ch[0]];
                        m->face_vert[3 * f + 1] = m->shape_vert_adr[sh] + on[ch[a]];
                        m->face_vert[3 * f + 2] = m->shape_vert_adr[sh] + on[ch[a + 1]];
                        cd_v3_copy(m->face_plane + 4 * f, n);
                        m->face_plane[4 * f + 3] = o;
                        m->face_run[f] = a == 1 ? nh - 2 : 0;
                    }
                    nf++;
                }
            }
    free(on); free(ch); free(q);
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

/* The broad phase's slot groups (docs/contact.md): runs of consecutive
 * slots with the same check-point body and shape, each with a sphere about
 * the middle of its check points' box holding every check point's sphere
 * (a single check point: its own centre and radius, exactly). */
static cd_status build_groups(cd_model *m)
{
    int k, g, n = 0;
    free(m->group_adr); free(m->group_num); free(m->group_pos); free(m->group_radius);
    m->group_adr = m->group_num = NULL;
    m->group_pos = m->group_radius = NULL;
    m->ngroup = 0;
    for (k = 0; k < m->nslot; k++)
        if (k == 0 || m->slot_shape[k] != m->slot_shape[k - 1] ||
            m->cp_body[m->slot_cp[k]] != m->cp_body[m->slot_cp[k - 1]])
            n++;
    m->group_adr = malloc((size_t)(n ? n : 1) * sizeof(int));
    m->group_num = malloc((size_t)(n ? n : 1) * sizeof(int));
    m->group_pos = malloc((size_t)(n ? n : 1) * 3 * sizeof(double));
    m->group_radius = malloc((size_t)(n ? n : 1) * sizeof(double));
    if (!m->group_adr || !m->group_num || !m->group_pos || !m->group_radius) return CD_ENOMEM;
    for (g = -1, k = 0; k < m->nslot; k++) {
        if (k == 0 || m->slot_shape[k] != m->slot_shape[k - 1] ||
            m->cp_body[m->slot_cp[k]] != m->cp_body[m->slot_cp[k - 1]]) {
            m->group_adr[++g] = k;
            m->group_num[g] = 0;
        }
        m->group_num[g]++;
    }
    m->ngroup = n;
    for (g = 0; g < n; g++) {
        double lo[3], hi[3], *c = m->group_pos + 3 * g, R = 0;
        int i, j;
        for (i = 0; i < 3; i++) lo[i] = hi[i] = m->cp_pos[3 * m->slot_cp[m->group_adr[g]] + i];
        for (j = 1; j < m->group_num[g]; j++)
            for (i = 0; i < 3; i++) {
                double p = m->cp_pos[3 * m->slot_cp[m->group_adr[g] + j] + i];
                if (p < lo[i]) lo[i] = p;
                if (p > hi[i]) hi[i] = p;
            }
        for (i = 0; i < 3; i++) c[i] = 0.5 * (lo[i] + hi[i]);
        for (j = 0; j < m->group_num[g]; j++) {
            int cp = m->slot_cp[m->group_adr[g] + j];
            const double *p = m->cp_pos + 3 * cp;
            double e[3], r;
            for (i = 0; i < 3; i++) e[i] = p[i] - c[i];
            r = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]) + m->cp_radius[cp];
            if (r > R) R = r;
        }
        /* round-off of the distances above: a group sphere never smaller than
         * a member's (a single member: exactly its radius) */
        m->group_radius[g] = m->group_num[g] == 1 ? m->cp_radius[m->slot_cp[m->group_adr[g]]] : R * (1.0 + 1e-12);
    }
    return CD_OK;
}

cd_status cd_model_finalize(cd_model *m, cd_error *err)
{
    if (!m) {
        cd_error_set(err, CD_EINVAL, "cd_model_finalize: %s is NULL", "the model");
        return CD_EINVAL;
    }
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
    free(m->shape_face_adr); free(m->shape_face_num); free(m->face_vert); free(m->face_plane); free(m->face_run);
    m->shape_face_adr = m->shape_face_num = m->face_vert = NULL;
    m->face_plane = NULL;
    m->face_run = NULL;
    {
        cd_status sst = build_slots(m, ny, err);
        if (sst != CD_OK) return sst;
    }
    nslot = m->nslot;
    if (build_groups(m) != CD_OK) { seterr(err, CD_ENOMEM, "out of memory"); return CD_ENOMEM; }
    /* hull faces of the convex shapes */
    m->shape_face_adr = calloc((size_t)(m->nshape ? m->nshape : 1), sizeof(int));
    m->shape_face_num = calloc((size_t)(m->nshape ? m->nshape : 1), sizeof(int));
    if (!m->shape_face_adr || !m->shape_face_num) { seterr(err, CD_ENOMEM, "out of memory"); return CD_ENOMEM; }
    m->nface = 0;
    for (i = 0; i < m->nshape; i++)
        if (m->shape_type[i] == CD_SHAPE_CONVEX) {
            m->shape_face_adr[i] = m->nface;
            m->shape_face_num[i] = hull_faces(m, i, 0, 0);
            if (m->shape_face_num[i] == -2) { seterr(err, CD_ENOMEM, "out of memory"); return CD_ENOMEM; }
            if (m->shape_face_num[i] < 4) { /* flat (-1) or degenerate */
                seterr(err, CD_EINVAL, "convex shape %d on body '%s': its vertices span no volume", i,
                       m->body_name[m->shape_body[i]]);
                return CD_EINVAL;
            }
            m->nface += m->shape_face_num[i];
        }
    m->face_vert = malloc((size_t)(m->nface ? m->nface : 1) * 3 * sizeof(int));
    m->face_plane = malloc((size_t)(m->nface ? m->nface : 1) * 4 * sizeof(double));
    m->face_run = malloc((size_t)(m->nface ? m->nface : 1) * sizeof(int));
    if (!m->face_vert || !m->face_plane || !m->face_run) { seterr(err, CD_ENOMEM, "out of memory"); return CD_ENOMEM; }
    for (i = 0; i < m->nshape; i++)
        if (m->shape_type[i] == CD_SHAPE_CONVEX && hull_faces(m, i, 1, m->shape_face_adr[i]) != m->shape_face_num[i]) {
            seterr(err, CD_ENOMEM, "out of memory");
            return CD_ENOMEM;
        }
    {
        cd_status st = finalize_joints(m, err);
        if (st != CD_OK) return st;
    }
    m->nv = nv;
    m->ny_slot_adr = ny;
    m->ny_fric_adr = ny + 3 * nslot;
    m->ny = m->ny_fric_adr + m->nfric;
    m->nsw = nslot + m->nlim + m->nfric + m->nfinger + m->nuser;
    m->finalized = 1;
    return CD_OK;
}
