/* Capture verdicts (include/capdyn/verdict.h, docs/grippers.md).
 *
 * Enclosure, in the fingers' plane: for a hand whose fingers all turn about
 * parallel axes (two opposed fingers), the object's centre of mass must lie
 * inside the polygon that runs up one finger (joint origins, then its tip:
 * the farthest check point of its last link), across, and down the other
 * fingers, closed by the palm between the finger bases (nonzero winding:
 * fingers that pass each other circle a wrapped bar twice). For other hands
 * (three fingers at 120 deg) in 3-D: the point must lie inside the convex
 * hull of the finger bases (the palm between them), every finger joint and
 * every fingertip: the region bounded by the palm and the fingers (GJK of
 * the point against that hull, libccd; no allocation). */
#include "capdyn/verdict.h"
#include "capdyn/analysis.h"
#include "capdyn/io.h"
#include "../math/cd_math.h"

#include <ccd/ccd.h>
#include <ccd/vec3.h>
#include <math.h>
#include <string.h>

const char *cd_verdict_name(cd_verdict v)
{
    switch (v) {
    case CD_VERDICT_CAPTURED: return "captured";
    case CD_VERDICT_ESCAPED: return "escaped";
    case CD_VERDICT_CAGED: return "caged";
    default: return "unresolved";
    }
}

cd_monitor_opts cd_monitor_opts_default(void)
{
    cd_monitor_opts o;
    o.hand = o.object = -1;
    o.v_max = 1e-3;
    o.w_max = 0.05;
    o.dwell = 0.2;
    o.workspace = 0;
    o.feature = -1;
    o.palm = -1;
    memset(o.palm_pos, 0, sizeof o.palm_pos);
    memset(o.palm_rot, 0, sizeof o.palm_rot);
    o.palm_rot[0] = o.palm_rot[4] = o.palm_rot[8] = 1.0;
    return o;
}

/* the palm body: the hand's base, or the link a gripper is mounted on */
static int palm_of(const cd_model *m, const cd_monitor_opts *o)
{
    return o->palm >= 0 ? o->palm : m->sys_body_adr[o->hand];
}

/* the palm frame, world */
static void palm_frame(const cd_model *m, const cd_data *d, const cd_monitor_opts *o, double x[3], double R[9])
{
    int pb = palm_of(m, o);
    double t[3];
    cd_m3_mulv(t, d->body_R + 9 * pb, o->palm_pos);
    cd_v3_add(x, d->body_x + 3 * pb, t);
    cd_m3_mul(R, d->body_R + 9 * pb, o->palm_rot);
}

/* 1 if body b hangs below body p (p excluded) */
static int below(const cd_model *m, int b, int p)
{
    for (b = m->body_parent[b]; b >= 0; b = m->body_parent[b])
        if (b == p) return 1;
    return 0;
}

/* the first link of each finger: the palm's direct children */
#define MAXF 16
static int fingers(const cd_model *m, const cd_monitor_opts *o, int *first)
{
    int hand = o->hand, b0 = m->sys_body_adr[hand], pb = palm_of(m, o), b, n = 0;
    for (b = pb + 1; b < b0 + m->sys_nbody[hand] && n < MAXF; b++)
        if (m->body_parent[b] == pb) first[n++] = b;
    return n;
}

/* the chain from a finger's first link to its tip (following the first child) */
static int chain(const cd_model *m, int hand, int first, int *out, int cap)
{
    int b0 = m->sys_body_adr[hand], end = b0 + m->sys_nbody[hand], n = 0, cur = first, b;
    while (cur >= 0 && n < cap) {
        int next = -1;
        out[n++] = cur;
        for (b = cur + 1; b < end; b++)
            if (m->body_parent[b] == cur) { next = b; break; }
        cur = next;
    }
    return n;
}

/* tip of a link: its farthest check point from the joint (world), else its CoM mirrored */
static void tip_of(const cd_model *m, const cd_data *d, int b, double tip[3])
{
    int k, best = -1;
    double dmax = -1, t[3];
    for (k = 0; k < m->ncp; k++)
        if (m->cp_body[k] == b) {
            double dd = cd_v3_norm(m->cp_pos + 3 * k) + m->cp_radius[k];
            if (dd > dmax) { dmax = dd; best = k; }
        }
    if (best >= 0) {
        double p[3];
        cd_v3_copy(p, m->cp_pos + 3 * best);
        if (cd_v3_norm(p) > 0) cd_v3_scale(p, p, (cd_v3_norm(p) + m->cp_radius[best]) / cd_v3_norm(p));
        cd_m3_mulv(t, d->body_R + 9 * b, p);
    } else {
        double c2[3];
        cd_v3_scale(c2, m->body_com + 3 * b, 2.0);
        cd_m3_mulv(t, d->body_R + 9 * b, c2);
    }
    cd_v3_add(tip, d->body_x + 3 * b, t);
}

/* nonzero winding number of the closed polygon about (x, y): fingers that
 * pass each other (hand = "two_interleaved") make the polygon cross itself,
 * and a bar wrapped by both is circled twice, which the even-odd rule would
 * call outside; for a simple polygon the two rules agree */
static int in_polygon(const double (*p)[2], int n, double x, double y)
{
    int i, j, w = 0;
    for (i = 0, j = n - 1; i < n; j = i++) {
        double cr = (p[i][0] - p[j][0]) * (y - p[j][1]) - (x - p[j][0]) * (p[i][1] - p[j][1]);
        if (p[j][1] <= y) {
            if (p[i][1] > y && cr > 0) w++;
        } else if (p[i][1] <= y && cr < 0) w--;
    }
    return w != 0;
}

/* the point set of a three-finger hand and the tested point, for libccd */
#define HULL_MAX (MAXF * 33)
typedef struct {
    double p[HULL_MAX][3];
    int n;
    double c[3];
} hull_pts;

static void point_support(const void *obj, const ccd_vec3_t *dir, ccd_vec3_t *out)
{
    const hull_pts *h = (const hull_pts *)obj;
    (void)dir;
    ccdVec3Set(out, h->c[0], h->c[1], h->c[2]);
}

static void hull_support(const void *obj, const ccd_vec3_t *dir, ccd_vec3_t *out)
{
    const hull_pts *h = (const hull_pts *)obj;
    int k, best = 0;
    double dmax = -HUGE_VAL;
    for (k = 0; k < h->n; k++) {
        double dd = h->p[k][0] * ccdVec3X(dir) + h->p[k][1] * ccdVec3Y(dir) + h->p[k][2] * ccdVec3Z(dir);
        if (dd > dmax) { dmax = dd; best = k; }
    }
    ccdVec3Set(out, h->p[best][0], h->p[best][1], h->p[best][2]);
}

static int enclosed(const cd_model *m, const cd_data *d, const cd_monitor_opts *o, const double c[3])
{
    int hand = o->hand, first[MAXF], nf = fingers(m, o, first), f, k, parallel = 1;
    double ax0[3];
    if (nf < 2) return 0;
    cd_v3_copy(ax0, d->body_axisw + 3 * first[0]);
    for (f = 1; f < nf; f++)
        if (fabs(fabs(cd_v3_dot(ax0, d->body_axisw + 3 * first[f])) - 1.0) > 1e-6) parallel = 0;
    if (parallel) {
        /* the polygon up finger 0, down finger 1 (.. and the others), in the plane normal to the axis */
        double u[3], v[3], poly[2 * 64][2], tip[3], r[3];
        int np = 0, ch[32], nc;
        u[0] = 1; u[1] = 0; u[2] = 0;
        if (fabs(ax0[0]) > 0.9) { u[0] = 0; u[1] = 1; }
        cd_v3_cross(v, ax0, u);
        cd_v3_normalize(v);
        cd_v3_cross(u, v, ax0);
        for (f = 0; f < nf && f < 2; f++) {
            double pts[33][3];
            int np0 = 0;
            nc = chain(m, hand, first[f], ch, 32);
            for (k = 0; k < nc; k++) cd_v3_copy(pts[np0++], d->body_x + 3 * ch[k]);
            tip_of(m, d, ch[nc - 1], tip);
            cd_v3_copy(pts[np0++], tip);
            for (k = 0; k < np0; k++) {
                const double *q = f == 0 ? pts[k] : pts[np0 - 1 - k];
                cd_v3_sub(r, q, c);
                poly[np][0] = cd_v3_dot(r, u);
                poly[np][1] = cd_v3_dot(r, v);
                np++;
            }
        }
        return in_polygon((const double (*)[2])poly, np, 0.0, 0.0);
    }
    {
        /* 3-D: inside the convex hull of the finger bases (the palm between
         * them), every finger joint and every fingertip (GJK, libccd) */
        hull_pts h;
        ccd_t ccd;
        h.n = 0;
        for (f = 0; f < nf; f++) {
            int ch[32], nc = chain(m, hand, first[f], ch, 32);
            for (k = 0; k < nc && h.n < HULL_MAX; k++) cd_v3_copy(h.p[h.n++], d->body_x + 3 * ch[k]);
            if (h.n < HULL_MAX) tip_of(m, d, ch[nc - 1], h.p[h.n++]);
        }
        cd_v3_copy(h.c, c);
        CCD_INIT(&ccd);
        ccd.support1 = point_support;
        ccd.support2 = hull_support;
        ccd.max_iterations = 100;
        ccd.epa_tolerance = 1e-12;
        return ccdGJKIntersect(&h, &h, &ccd) ? 1 : 0;
    }
}

cd_monitor_opts cd_scenario_monitor_opts(const cd_scenario *sc)
{
    cd_monitor_opts o = cd_monitor_opts_default();
    o.hand = sc->capture_hand;
    o.object = sc->capture_object;
    o.feature = sc->capture_feature;
    o.v_max = sc->capture_v_max;
    o.w_max = sc->capture_w_max;
    o.dwell = sc->capture_dwell;
    o.workspace = sc->capture_workspace;
    o.palm = sc->capture_palm;
    memcpy(o.palm_pos, sc->capture_palm_pos, sizeof o.palm_pos);
    memcpy(o.palm_rot, sc->capture_palm_rot, sizeof o.palm_rot);
    return o;
}

cd_status cd_monitor_init(cd_monitor *mo, const cd_model *m, const cd_data *d, const cd_monitor_opts *opt,
                          cd_error *err)
{
    if (!mo || !m || !d) {
        cd_error_set(err, CD_EINVAL, "cd_monitor_init: %s is NULL", !mo ? "the monitor" : !m ? "the model" : "the data");
        return CD_EINVAL;
    }
    int first[MAXF], nf, f, k, hb;
    double reach = 0, xp[3], Rp[9];
    memset(mo, 0, sizeof *mo);
    mo->opt = opt ? *opt : cd_monitor_opts_default();
    if (mo->opt.hand < 0 || mo->opt.hand >= m->nsys || mo->opt.object < 0 || mo->opt.object >= m->nsys ||
        mo->opt.hand == mo->opt.object) {
        cd_error_set(err, CD_EINVAL, "verdict: hand %d and object %d must be two systems of the model", mo->opt.hand,
                     mo->opt.object);
        return CD_EINVAL;
    }
    if (mo->opt.feature >= m->nshape || (mo->opt.feature >= 0 && m->body_sys[m->shape_body[mo->opt.feature]] != mo->opt.object)) {
        cd_error_set(err, CD_EINVAL, "verdict: the grasp feature (shape %d) is not a shape of the object", mo->opt.feature);
        return CD_EINVAL;
    }
    if (m->sys_base_type[mo->opt.object] != CD_BASE_FREE) {
        cd_error_set(err, CD_EINVAL, "verdict: the object '%s' must be free-floating", m->sys_name[mo->opt.object]);
        return CD_EINVAL;
    }
    if (mo->opt.palm >= m->nbody || (mo->opt.palm >= 0 && m->body_sys[mo->opt.palm] != mo->opt.hand)) {
        cd_error_set(err, CD_EINVAL, "verdict: the palm (body %d) is not a body of the hand", mo->opt.palm);
        return CD_EINVAL;
    }
    hb = palm_of(m, &mo->opt);
    palm_frame(m, d, &mo->opt, xp, Rp);
    nf = fingers(m, &mo->opt, first);
    for (f = 0; f < nf; f++) {
        int ch[32], nc = chain(m, mo->opt.hand, first[f], ch, 32);
        double tip[3], r[3];
        tip_of(m, d, ch[nc - 1], tip);
        cd_v3_sub(r, tip, xp);
        if (cd_v3_norm(r) > reach) reach = cd_v3_norm(r);
    }
    for (k = 0; k < m->nshape; k++)
        if (m->shape_body[k] == hb) {
            double s = cd_v3_norm(m->shape_size + 3 * k);
            if (s > reach) reach = s;
        }
    mo->reach = reach;
    if (mo->opt.workspace <= 0) {
        /* the default escape radius: the palm of a hand mounted on an arm is
         * carried by the arm, so an object may still be grasped as far from
         * the palm as the arm reaches (the joint-origin offsets from the
         * first arm joint to the palm centre, summed: its fully stretched
         * length) plus the hand's reach; never less than the object's CoM
         * distance from the palm at the start (an object does not escape at
         * t = 0); margin 1.5 (docs/grippers.md) */
        double arm = 0, r0[3], d0;
        int b0 = m->sys_body_adr[mo->opt.hand];
        if (hb != b0) {
            arm = cd_v3_norm(mo->opt.palm_pos);
            for (k = hb; k >= 0 && m->body_parent[k] >= 0 && m->body_parent[k] != b0; k = m->body_parent[k])
                arm += cd_v3_norm(m->body_jnt_pos + 3 * k);
        }
        cd_v3_sub(r0, d->body_c + 3 * m->sys_body_adr[mo->opt.object], xp);
        d0 = cd_v3_norm(r0);
        mo->opt.workspace = 1.5 * (reach + arm > d0 ? reach + arm : d0);
    }
    mo->verdict = CD_VERDICT_UNRESOLVED;
    mo->t_capture = mo->t_escape = mo->t_cage = mo->epsilon = mo->t_judged = NAN;
    mo->t_set = d->t;
    mo->set_hash = 0;
    return CD_OK;
}

void cd_monitor_update(cd_monitor *mo, const cd_model *m, const cd_data *d)
{
    if (!mo || !m || !d) return;
    int hand = mo->opt.hand, obj = mo->opt.object, hb = palm_of(m, &mo->opt), ob = m->sys_body_adr[obj], k, b;
    int hend = m->sys_body_adr[hand] + m->sys_nbody[hand];
    unsigned long h = 1469598103UL;
    double c[3], r[3], vp[3], t3[3], wrel[3], xp[3], Rp[9];
    int ncontact = 0;
    mo->n_stick = mo->n_slip = 0;
    for (k = 0; k < m->nslot; k++) {
        int a = m->cp_body[m->slot_cp[k]], s = m->shape_body[m->slot_shape[k]];
        if (m->body_sys[a] != obj && m->body_sys[s] != obj) continue;
        if (d->slot_mode[k] == CD_MODE_OPEN) continue;
        ncontact++;
        h = (h ^ (unsigned long)k) * 16777619UL;
        if (d->slot_mode[k] == CD_MODE_STICK) mo->n_stick++; else mo->n_slip++;
        if (d->slot_fn[k] > mo->peak_fn) mo->peak_fn = d->slot_fn[k];
    }
    if (h != mo->set_hash) { mo->set_hash = h; mo->t_set = d->t; }
    mo->qd_max = 0;
    for (b = hb + 1; b < hend; b++) {
        int v = m->body_dof[b];
        if (!below(m, b, hb)) continue; /* the hand's joints only: the palm's subtree */
        double tau = fabs(d->qfrc_actuator[v] + d->qfrc_passive[v]), qd = fabs(cd_joint_qd(m, d, b));
        if (tau > mo->peak_tau) mo->peak_tau = tau;
        if (qd > mo->qd_max) mo->qd_max = qd;
    }
    palm_frame(m, d, &mo->opt, xp, Rp);
    cd_v3_copy(c, d->body_c + 3 * ob);
    cd_v3_sub(r, c, xp);
    cd_m3_tmulv(mo->offset, Rp, r);
    mo->offset_norm = cd_v3_norm(r);
    /* velocity relative to the palm at the object's CoM */
    cd_v3_sub(t3, c, d->body_c + 3 * hb);
    cd_v3_cross(vp, d->body_w + 3 * hb, t3);
    cd_v3_add(vp, vp, d->body_v + 3 * hb);
    cd_v3_sub(vp, d->body_v + 3 * ob, vp);
    cd_v3_sub(wrel, d->body_w + 3 * ob, d->body_w + 3 * hb);
    mo->v_rel = cd_v3_norm(vp);
    mo->w_rel = cd_v3_norm(wrel);
    if (mo->opt.feature >= 0) { /* the feature's centre, world */
        int sb = m->shape_body[mo->opt.feature];
        double t[3];
        cd_m3_mulv(t, d->body_R + 9 * sb, m->shape_pos + 3 * mo->opt.feature);
        cd_v3_add(c, d->body_x + 3 * sb, t);
    }
    mo->enclosed = enclosed(m, d, &mo->opt, c);
    cd_v3_sub(t3, c, xp);
    cd_m3_tmulv(mo->point, Rp, t3);
    if (mo->verdict == CD_VERDICT_CAPTURED || mo->verdict == CD_VERDICT_ESCAPED) return; /* final */
    if (mo->offset_norm > mo->opt.workspace) {
        mo->verdict = CD_VERDICT_ESCAPED;
        mo->t_escape = d->t;
        return;
    }
    /* the capture conditions: enclosed, at rest relative to the palm, the
     * fingers stopped, the contact set settled; then the grip is judged once
     * per settled contact set (a new set restarts the dwell): force closure
     * with epsilon > 0 is captured, anything less is caged (docs/capture.md,
     * "Verdicts": an enclosure without closure holds the object only up to
     * the play of the cage) */
    if (mo->enclosed && ncontact > 0 && mo->v_rel < mo->opt.v_max && mo->w_rel < mo->opt.w_max &&
        mo->qd_max < mo->opt.w_max && d->t - mo->t_set >= mo->opt.dwell && !(mo->t_judged == mo->t_set)) {
        double eps = 0;
        int closure = 0;
        cd_error qerr;
        mo->t_judged = mo->t_set;
        if (cd_monitor_quality(mo, m, d, &eps, &closure, &qerr) != CD_OK) { eps = NAN; closure = 0; }
        mo->epsilon = eps;
        if (closure && eps > 0) {
            mo->verdict = CD_VERDICT_CAPTURED;
            mo->t_capture = d->t;
        } else if (mo->verdict != CD_VERDICT_CAGED) {
            mo->verdict = CD_VERDICT_CAGED;
            mo->t_cage = d->t;
        }
    }
}

cd_status cd_monitor_quality(const cd_monitor *mo, const cd_model *m, const cd_data *d, double *eps, int *closure,
                             cd_error *err)
{
    if (!mo || !m || !d || !eps) {
        cd_error_set(err, CD_EINVAL, "cd_monitor_quality: %s is NULL", !mo ? "the monitor" : !m ? "the model" : !d ? "the data" : "eps");
        return CD_EINVAL;
    }
    enum { MAXC = 256 };
    cd_grasp_contact ct[MAXC];
    cd_grasp_options op = cd_grasp_options_default();
    cd_grasp_quality q;
    int k, n = 0, first[MAXF], nf = fingers(m, &mo->opt, first), f, parallel = nf >= 2, obj = mo->opt.object,
        hand = mo->opt.hand;
    cd_status st;
    *eps = 0;
    *closure = 0;
    for (k = 0; k < m->nslot && n < MAXC; k++) {
        int a = m->cp_body[m->slot_cp[k]], s = m->shape_body[m->slot_shape[k]], i;
        double sign;
        if (d->slot_mode[k] == CD_MODE_OPEN) continue;
        if (m->body_sys[s] == obj && m->body_sys[a] == hand) sign = -1.0; /* the normal points from the object's shape out */
        else if (m->body_sys[a] == obj && m->body_sys[s] == hand) sign = 1.0; /* the check point is the object's: into it */
        else continue; /* not the hand's grip (a fixture, another target) */
        for (i = 0; i < 3; i++) {
            ct[n].p[i] = d->slot_point[3 * k + i];
            ct[n].n[i] = sign * d->slot_normal[3 * k + i];
            ct[n].t[i] = 0.0;
        }
        ct[n].mu = m->law[m->slot_law[k]].mu_s;
        n++;
    }
    if (n == 0) return CD_OK;
    for (f = 1; f < nf; f++)
        if (fabs(fabs(cd_v3_dot(d->body_axisw + 3 * first[0], d->body_axisw + 3 * first[f])) - 1.0) > 1e-6) parallel = 0;
    if (parallel) {
        op.mode = CD_GRASP_PLANAR;
        cd_v3_copy(op.plane_normal, d->body_axisw + 3 * first[0]);
    }
    st = cd_grasp_quality_eval(ct, n, d->body_c + 3 * m->sys_body_adr[obj], &op, &q, err);
    if (st != CD_OK) return st;
    *eps = q.epsilon;
    *closure = q.force_closure;
    return CD_OK;
}
