/* Contact forces at every slot (check point x shape) and the switching
 * functions of the stick-slip automaton. See docs/contact.md.
 *
 * Per slot, with n the unit normal from the shape toward the check point:
 *   x     = r - dist                       penetration (>0 inside)
 *   c     = s - (x/2) n                     contact point: middle of the overlap
 *   v_rel = v_A(c) - v_B(c)                 relative velocity of the two bodies at c
 *   xdot  = -v_rel . n,  v_t = v_rel - (v_rel . n) n
 *   f_raw = K x^p + D xdot^q                eq. (3), x^p := |x|^p sign(x), same for xdot^q
 *   stick: f_t = -(K_t z_t + D_t v_t)       eq. (4), z the anchor deflection, kept in y
 *          in the axes of the shape's body B (z_B, z = R_B z_B, zdot_B = R_B^T v_t) so
 *          that a sticking pair turning together carries its held force along
 *   slip:  f_t = -mu_k f_n u/|u|, u = v_a + 2 v_reg s_t   eq. (5)
 * With a tangential damper (D_t > 0) the slip keeps the stick law's
 * spring-damper in series with the Coulomb slider (a saturated bristle):
 * with the trial force f_tr = K_t z_t^pt + D_t v_t^qt (the stick force it
 * would be), s_t = f_tr/|f_tr|, the deflection z (the state, as in stick)
 * obeys K_t z_t^pt + D_t zdot^qt = mu_k f_n s_t and the anchor slips at
 * v_a = v_t - zdot = (|f_tr| - mu_k f_n) s_t / D_t (qt = 1): stick -> slip at
 * |f_tr| = mu_s f_n and slip -> stick at |f_tr| = mu_k f_n - D_t v_reg are
 * one function of the state, so no switch is undone at its instant, and z
 * is kept through both (docs/contact.md, "Slip with a tangential damper").
 * With D_t = 0, s_t is the slip direction anchored at the last event
 * (projected on the tangent plane) and v_a the slip velocity. The contact point's motion
 * v_t is the slip of the anchor plus the rate of the elastic deflection that
 * the tangential spring keeps at the cone, z_el = mu_k f_n s / K_t, so
 *          v_a = v_t - (mu_k / K_t) fdot_n s_t,  fdot_n ~ K p x^(p-1) xdot
 * (the damper's share of fdot_n is left out: it needs the acceleration).
 * Without this, a contact whose cone shrinks (f_n falling) under a loaded
 * spring would see its elastic unloading as a reversed slip and flip between
 * stick and slip every few nanoseconds. In 1-D slip u/|u| = s_t exactly
 * (Coulomb without smoothing); in 3-D the 2 v_reg term keeps the direction
 * defined as v_a -> 0.
 * The force F = f_n n + f_t acts on the check-point body at c, -F on the shape's. */
#include "capdyn/sim.h"
#include "../math/cd_math.h"
#include "../kinematics/kinematics.h"
#include "geometry.h"
#include "contact.h"

/* world pose of every shape, once per evaluation (d->shape_R, shape_xw) */
static void shape_poses(const cd_model *m, cd_data *d)
{
    int sh;
    for (sh = 0; sh < m->nshape; sh++) {
        int b = m->shape_body[sh];
        double t[3];
        cd_m3_mul(d->shape_R + 9 * sh, d->body_R + 9 * b, m->shape_rot + 9 * sh);
        cd_m3_mulv(t, d->body_R + 9 * b, m->shape_pos + 3 * sh);
        cd_v3_add(d->shape_xw + 3 * sh, d->body_x + 3 * b, t);
    }
}

/* The query in the shape frame: exact (0), or, for a hull farther than
 * `beyond` from one of its face planes, that plane's distance (1: a lower
 * bound, cd_geom_hull); -1 for a rejected (non-finite) answer. */
static int shape_query(const cd_model *m, int sh, const double p[3], double beyond, double *dist, double n[3],
                       double s[3])
{
    int fa = m->shape_face_adr[sh];
    if (m->shape_type[sh] == CD_SHAPE_CONVEX)
        return cd_geom_hull(m->vert, m->face_vert + 3 * fa, m->face_plane + 4 * fa, m->face_run + fa,
                            m->shape_face_num[sh], p, beyond, dist, n, s);
    return cd_geom_analytic(m->shape_type[sh], m->shape_size + 3 * sh, p, dist, n, s);
}

/* a world point in shape sh's frame */
static void to_shape(const cd_data *d, int sh, const double pw[3], double pl[3])
{
    double t[3];
    cd_v3_sub(t, pw, d->shape_xw + 3 * sh);
    cd_m3_tmulv(pl, d->shape_R + 9 * sh, t);
}

/* The shape's query at a point pl of its frame (n, s in world); returns 0
 * (exact), 1 (a hull's plane bound beyond `beyond`, see shape_query) or -1
 * for a rejected answer */
static int query_local(const cd_model *m, const cd_data *d, int sh, const double pl[3], double beyond,
                       double *dist, double n[3], double s[3])
{
    const double *R = d->shape_R + 9 * sh, *x = d->shape_xw + 3 * sh;
    double t[3], nl[3], sl[3];
    int res = shape_query(m, sh, pl, beyond, dist, nl, sl);
    if (res >= 0) {
        cd_m3_mulv(n, R, nl);
        cd_m3_mulv(t, R, sl);
        cd_v3_add(s, x, t);
    }
    return res;
}


/* Broad phase of an OPEN slot: a check point (radius r) farther than
 * CD_BROAD_MARGIN from the shape's bounding sphere cannot touch it, so the
 * exact query is skipped and the gap to that sphere stands in: dist is a
 * lower bound of the true distance (x = r - dist stays below
 * -CD_BROAD_MARGIN: the slot stays open, its switching function positive,
 * exactly as with the true distance), n and s point from the sphere's centre
 * (left unset when n is NULL: a caller that needs only the gap).
 * Returns 1 when culled, 0 when the exact query is needed. */
#define CD_BROAD_MARGIN 1e-6
static int far_open(const cd_model *m, const cd_data *d, int sh, double px, double py, double pz, double r,
                    double *dist, double n[3], double s[3])
{
    const double *xs = d->shape_xw + 3 * sh;
    double t[3], dd, rb = m->shape_rbound[sh], lim = rb + r + CD_BROAD_MARGIN;
    if (!(rb < HUGE_VAL)) return 0;
    /* the point by value: it was just computed, and reading it back from
     * memory as a vector stalled on the store (store forwarding) */
    t[0] = px - xs[0];
    t[1] = py - xs[1];
    t[2] = pz - xs[2];
    dd = cd_v3_dot(t, t);
    /* clearly inside the culling distance: the decision below without its
     * square root (a margin of 1e-10 relative covers every rounding) */
    if (dd < lim * lim * (1.0 - 1e-10)) return 0;
    dd = sqrt(dd);
    if (!(dd - rb > r + CD_BROAD_MARGIN)) return 0;
    *dist = dd - rb;
    if (!n) return 1;
    cd_v3_scale(n, t, 1.0 / dd);
    cd_v3_copy(s, xs);
    cd_v3_axpy(s, rb, n);
    return 1;
}

int cd_shape_distance(const cd_model *m, int shape, const double p[3], double radius,
                      double *dist, double n[3], double s[3])
{
    if (!m || !p || !dist || !n || !s) return -1;
    (void)radius;
    return shape_query(m, shape, p, HUGE_VAL, dist, n, s);
}

int cd_shape_distance_ccd(const cd_model *m, int shape, const double p[3], double radius,
                          double *dist, double n[3], double s[3])
{
    if (!m || !p || !dist || !n || !s) return -1;
    if (m->shape_type[shape] == CD_SHAPE_PLANE) return -1;
    return cd_geom_ccd(m->shape_type[shape], m->shape_size + 3 * shape,
                       m->vert + 3 * m->shape_vert_adr[shape], m->shape_vert_num[shape], p, radius, 1,
                       1e-12, dist, n, s);
}

/* tangential projection of a onto the plane normal to n */
static void tangential(double r[3], const double a[3], const double n[3])
{
    double an = cd_v3_dot(a, n);
    cd_v3_copy(r, a);
    cd_v3_axpy(r, -an, n);
}

/* r = K |a|^p a/|a| (a vector law with a signed power; p = 1: K a) */
static void vpow(double r[3], const double a[3], double K, double p)
{
    double n;
    if (p == 1.0) { cd_v3_scale(r, a, K); return; }
    n = cd_v3_norm(a);
    cd_v3_scale(r, a, n > 0 ? K * pow(n, p - 1.0) : 0.0);
}

/* The free sphere free_sp (cd_data.slot_free: centre and radius in the
 * shape's frame) of a check point of radius r at pl (shape frame): 1 when
 * pl is inside it by more than r, with *x = r minus the bound of the
 * distance it gives (the signed distance is 1-Lipschitz, so dist(pl) >= its
 * radius minus how far pl is from its centre); 0 otherwise. */
static int inside_free(const double free_sp[4], const double pl[3], double r, double *x)
{
    double t[3], lb;
    cd_v3_sub(t, pl, free_sp);
    lb = free_sp[3] - cd_v3_norm(t);
    if (!(lb > r + CD_BROAD_MARGIN)) return 0;
    *x = r - lb;
    return 1;
}

/* Geometry of slot k at the evaluated pose: the check point's centre pw,
 * the penetration x, the normal n and the surface point s (world). An open
 * slot beyond the shape's bounding sphere gets the sphere's gap (far_open;
 * with x_only its n and s are left unset: x < 0 there, and a caller that
 * skips such a slot needs x alone). With free_sp (the slot's free sphere,
 * cd_data.slot_free: only the evaluation's broad phase, which skips an
 * apart slot) a check point inside it gets x = r minus its bound, n and s
 * unset, and an exact query leaves its own free sphere there. Returns 0, or
 * -1 for a rejected query (x, n, s then unset). */
static int slot_geometry(const cd_model *m, const cd_data *d, int k, int open, int x_only, double pw[3], double *x,
                         double n[3], double s[3], double *free_sp)
{
    int cp = m->slot_cp[k], sh = m->slot_shape[k], res;
    double r = m->cp_radius[cp], dist, pl[3];
    cd_body_point(d, m->cp_body[cp], m->cp_pos + 3 * cp, pw);
    if (open && (res = far_open(m, d, sh, pw[0], pw[1], pw[2], r, &dist, x_only ? NULL : n, s)) == 1) {
        *x = r - dist;
        return 0;
    }
    to_shape(d, sh, pw, pl);
    /* the free sphere of an earlier evaluation */
    if (free_sp && free_sp[3] > r + CD_BROAD_MARGIN && inside_free(free_sp, pl, r, x)) return 0;
    if ((res = query_local(m, d, sh, pl, open ? r + CD_BROAD_MARGIN : HUGE_VAL, &dist, n, s)) == 1) res = 0;
    if (res == 0) {
        *x = r - dist;
        if (free_sp) { /* dist (exact, or a face plane's bound) is a lower bound: a free sphere */
            cd_v3_copy(free_sp, pl);
            free_sp[3] = dist;
        }
    }
    return res;
}

/* The broad phase's two cheap tests of an open slot, the first part of
 * slot_geometry(open, x_only) by the same operations: 1 when its check point
 * is beyond the shape's bounding sphere (far_open) or inside the slot's free
 * sphere free_sp (may be NULL), with *x (< 0) bit for bit as slot_geometry
 * gives it; 0 when the exact query is needed. The evaluation calls it before
 * eval_slot, so that a slot apart costs its check point's world position and
 * one or two distances, not eval_slot's and slot_geometry's set-up (most
 * slots are apart at most evaluations: 40 of the Fig. 5 grasp's 44). */
static int open_apart(const cd_model *m, const cd_data *d, int k, const double *free_sp, double *x)
{
    int cp = m->slot_cp[k], sh = m->slot_shape[k];
    double r = m->cp_radius[cp], dist, pw[3];
    cd_body_point(d, m->cp_body[cp], m->cp_pos + 3 * cp, pw);
    if (far_open(m, d, sh, pw[0], pw[1], pw[2], r, &dist, NULL, NULL) == 1) {
        *x = r - dist;
        return 1;
    }
    if (free_sp && free_sp[3] > r + CD_BROAD_MARGIN) {
        double pl[3];
        to_shape(d, sh, pw, pl);
        return inside_free(free_sp, pl, r, x);
    }
    return 0;
}

/* The contact point c (middle of the overlap), the penetration rate xd and
 * the tangential relative velocity vt of slot k from its geometry. */
static void slot_rates(const cd_model *m, const cd_data *d, int k, double x, const double n[3], const double s[3],
                       double c[3], double *xd, double vt[3])
{
    int ba = m->cp_body[m->slot_cp[k]], bb = m->shape_body[m->slot_shape[k]];
    double va[3], vb[3], vrel[3], lb[3], t[3];
    cd_v3_copy(c, s);
    cd_v3_axpy(c, -0.5 * x, n);
    /* velocity of each body's material point at c */
    cd_v3_sub(t, c, d->body_c + 3 * ba);
    cd_v3_cross(va, d->body_w + 3 * ba, t);
    cd_v3_add(va, va, d->body_v + 3 * ba);
    cd_v3_sub(lb, c, d->body_c + 3 * bb);
    cd_v3_cross(vb, d->body_w + 3 * bb, lb);
    cd_v3_add(vb, vb, d->body_v + 3 * bb);
    cd_v3_sub(vrel, va, vb);
    *xd = -cd_v3_dot(vrel, n);
    tangential(vt, vrel, n);
}

/* Everything the full evaluation reports for an open slot, computed from
 * d's evaluated kinematics (shape poses included) by the same operations:
 * bit for bit what cd_contact_eval writes when it evaluates the slot. Used
 * for the slots it skipped (d->slot_far). Returns 0, or -1 if the query is
 * rejected (never for a skipped slot: it was accepted at the evaluation). */
static int open_outputs(const cd_model *m, const cd_data *d, int k, double *x, double *xd, double *fraw, double c[3],
                        double n[3], double vt[3])
{
    const cd_contact_law *L = &m->law[m->slot_law[k]];
    double pw[3], s[3];
    if (slot_geometry(m, d, k, 1, 0, pw, x, n, s, NULL) != 0) return -1;
    slot_rates(m, d, k, *x, n, s, c, xd, vt);
    *fraw = cd_law_normal(L, *x, *xd, NULL, NULL);
    return 0;
}

void cd_contact_slot_outputs(const cd_model *m, const cd_data *d, int k, double *x, double *xdot, double *fnraw,
                             double point[3], double normal[3], double vt[3])
{
    double lx, lxd, lf, lc[3], ln[3], lv[3];
    if (d->slot_far[k] && open_outputs(m, d, k, &lx, &lxd, &lf, lc, ln, lv) == 0) {
        if (x) *x = lx;
        if (xdot) *xdot = lxd;
        if (fnraw) *fnraw = lf;
        if (point) cd_v3_copy(point, lc);
        if (normal) cd_v3_copy(normal, ln);
        if (vt) cd_v3_copy(vt, lv);
        return;
    }
    if (x) *x = d->slot_x[k];
    if (xdot) *xdot = d->slot_xdot[k];
    if (fnraw) *fnraw = d->slot_fnraw[k];
    if (point) cd_v3_copy(point, d->slot_point + 3 * k);
    if (normal) cd_v3_copy(normal, d->slot_normal + 3 * k);
    if (vt) cd_v3_copy(vt, d->slot_vt + 3 * k);
}

void cd_contact_complete(const cd_model *m, cd_data *d)
{
    int k;
    for (k = 0; k < m->nslot; k++) {
        if (!d->slot_far[k]) continue;
        cd_contact_slot_outputs(m, d, k, d->slot_x + k, d->slot_xdot + k, d->slot_fnraw + k, d->slot_point + 3 * k,
                                d->slot_normal + 3 * k, d->slot_vt + 3 * k);
        d->slot_far[k] = 0;
    }
}

/* Broad phase of group g (a run of slots of one check-point body against
 * one shape, model.h): 1 if none of its check points can touch the shape,
 * with *xb an upper bound of their penetrations. The group's sphere (centre
 * cw, radius R holding every check point's sphere) is tested like one check
 * point: against the shape's bounding sphere, then by the exact query (the
 * signed distance is 1-Lipschitz, so x_k <= R - dist(cw)). A group of one
 * check point is that check point: the same operations and decision as its
 * slot's own (slot_geometry, then x < 0), so *xb is its x bit for bit; a
 * larger group must be apart by more than CD_BROAD_MARGIN (round-off of
 * the members' offsets). */
static int group_apart(const cd_model *m, const cd_data *d, int g, double *xb)
{
    int k0 = m->group_adr[g], sh = m->slot_shape[k0], single = m->group_num[g] == 1, res;
    double cw[3], cl[3], R = m->group_radius[g], dist, n[3], s[3];
    double *near = d->group_near + 4 * g;
    cd_body_point(d, m->cp_body[m->slot_cp[k0]], m->group_pos + 3 * g, cw);
    if (far_open(m, d, sh, cw[0], cw[1], cw[2], R, &dist, NULL, NULL) == 1) {
        *xb = R - dist;
        return 1;
    }
    to_shape(d, sh, cw, cl);
    /* the near sphere of an earlier query: the signed distance is
     * 1-Lipschitz, so here it is at most that query's distance plus how far
     * the centre moved; below R - CD_BROAD_MARGIN the query would find the
     * group not apart (dist <= R), a margin of a micrometre over its
     * rounding: the per-slot tests follow without it */
    if (near[3] < R - CD_BROAD_MARGIN) {
        double t[3];
        cd_v3_sub(t, cl, near);
        if (near[3] + cd_v3_norm(t) < R - CD_BROAD_MARGIN) return 0;
    }
    res = query_local(m, d, sh, cl, R + CD_BROAD_MARGIN, &dist, n, s);
    /* kept only when exact (res 0) and within the query's cut-off */
    near[3] = res == 0 && dist <= R + CD_BROAD_MARGIN ? dist : HUGE_VAL;
    if (res < 0) return 0;
    cd_v3_copy(near, cl);
    *xb = R - dist;
    return single ? *xb < 0 : *xb < -CD_BROAD_MARGIN;
}

/* An open slot skipped by the broad phase: no force, no anchor rate, x (or
 * an upper bound of it, < 0) and the mark; the rest on demand. zdot is the
 * data's own d->ydot (cd_forward), which only evaluations write: a slot
 * skipped by the last one already has its zeros there and in its forces. */
static void skip_slot(cd_data *d, int k, double x, double *zdot)
{
    d->slot_x[k] = x;
    if (d->slot_far[k]) return;
    d->slot_far[k] = 1;
    d->slot_geomfail[k] = 0;
    d->slot_fn[k] = 0;
    cd_v3_zero(d->slot_ft + 3 * k);
    zdot[3 * k] = zdot[3 * k + 1] = zdot[3 * k + 2] = 0.0;
}

static void eval_slot(const cd_model *m, cd_data *d, int k, double *zdot);

/* The slots of a group that is not apart, in their order. An open slot
 * whose check point is clearly beyond the shape's bounding sphere is
 * skipped first by a test in its body's frame: the sphere's centre is taken
 * into that frame once for the group, so the test costs a difference and a
 * dot product instead of the check point's world position (most of the
 * Fig. 5 grasp's slots are such at most evaluations; open_apart was 13 % of
 * its instructions). Its x is the bounding sphere's gap as it finds it, an
 * upper bound of the penetration like every skipped slot's (slot_x), which
 * only the rounding of the other frame tells from open_apart's; 1e-10
 * relative on the squared limit keeps the decision clear of that rounding.
 * Nothing the run computes from a skipped slot reads that x: the switching
 * functions and the outputs take the full evaluation's own (open_outputs,
 * cd_contact_switch_near), and its force is zero either way. Every other
 * open slot goes through open_apart's two tests (what eval_slot would find
 * first, by the same operations), the rest through eval_slot. */
static void group_slots(const cd_model *m, cd_data *d, int g, double *zdot)
{
    const int k0 = m->group_adr[g], k1 = k0 + m->group_num[g];
    const int sh = m->slot_shape[k0], b = m->cp_body[m->slot_cp[k0]];
    const double rb = m->shape_rbound[sh];
    double cb[3], t[3], xb;
    int k, pre = 0;
    if (rb < HUGE_VAL) {
        cd_v3_sub(t, d->shape_xw + 3 * sh, d->body_x + 3 * b);
        cd_m3_tmulv(cb, d->body_R + 9 * b, t);
        /* tried only where the group's centre is outside the bounding
         * sphere, where many of its check points are (a long shape's sphere
         * holds whole groups near it, whose check points would pay the test
         * and then open_apart's: the capture scenes' instructions rose by
         * 0.9 % with the test wherever any of the group's sphere was outside,
         * 0.7 % with this rule) */
        cd_v3_sub(t, m->group_pos + 3 * g, cb);
        pre = cd_v3_norm(t) > rb;
    }
    for (k = k0; k < k1; k++) {
        if (d->slot_mode[k] != CD_MODE_OPEN) {
            eval_slot(m, d, k, zdot);
            continue;
        }
        if (pre) {
            const int cp = m->slot_cp[k];
            const double r = m->cp_radius[cp], lim = rb + r + CD_BROAD_MARGIN, *p = m->cp_pos + 3 * cp;
            double dd;
            cd_v3_sub(t, p, cb);
            dd = cd_v3_dot(t, t);
            if (dd > lim * lim * (1.0 + 1e-10)) {
                skip_slot(d, k, r - (sqrt(dd) - rb), zdot);
                continue;
            }
        }
        if (open_apart(m, d, k, d->slot_free + 4 * k, &xb)) skip_slot(d, k, xb, zdot);
        else eval_slot(m, d, k, zdot);
    }
}

/* The trial force of a slot with a tangential damper (D_t > 0): what the
 * stick law would apply at this state, f_tr = K_t z_t^pt + D_t v_t^qt
 * (world, tangential; the force on A is -f_tr), and its direction s (the
 * slip direction of a slipping slot; `fallback` when f_tr = 0). */
static double trial_force(const cd_contact_law *L, const double RB[9], const double z[3], const double n[3],
                          const double vt[3], const double fallback[3], double s[3])
{
    double zw[3], zt[3], fk[3], fdv[3], ftr[3], nf;
    cd_m3_mulv(zw, RB, z);
    tangential(zt, zw, n);
    vpow(fk, zt, L->Kt, L->pt);
    vpow(fdv, vt, L->Dt, L->qt);
    cd_v3_add(ftr, fk, fdv);
    nf = cd_v3_norm(ftr);
    if (nf > 0) cd_v3_scale(s, ftr, 1.0 / nf);
    else { tangential(s, fallback, n); cd_v3_normalize(s); }
    return nf;
}

/* CD_CONTACT_SLIP_SMOOTH: contact.h */

/* The saturated bristle of a slipping slot (D_t > 0): its force
 * K_t z_t^pt + D_t zdot^qt equals mu_k f_n s (s the slip direction, unit,
 * tangential), which gives the deflection's rate zdot (world) and the
 * anchor's slip velocity va = v_t - zdot. z in the shape body's axes (RB). */
static void bristle_va(const cd_contact_law *L, const double RB[9], const double z[3], const double n[3],
                       const double vt[3], double fn, const double s[3], double va[3], double zd_out[3])
{
    double zw[3], zt[3], fk[3], w[3], zd[3], nw, fc = fn > 0 || (CD_CONTACT_SLIP_SMOOTH && !L->pull) ? fn : 0.0;
    cd_m3_mulv(zw, RB, z);
    tangential(zt, zw, n);
    vpow(fk, zt, L->Kt, L->pt);
    cd_v3_scale(w, s, L->mu_k * fc);
    cd_v3_sub(w, w, fk);
    nw = cd_v3_norm(w);
    if (L->qt == 1.0) cd_v3_scale(zd, w, 1.0 / L->Dt);
    else cd_v3_scale(zd, w, nw > 0 ? pow(nw / L->Dt, 1.0 / L->qt) / nw : 0.0);
    cd_v3_sub(va, vt, zd);
    if (zd_out) cd_v3_copy(zd_out, zd);
}

void cd_contact_cache_clear(const cd_model *m, cd_data *d)
{
    int g;
    memset(d->slot_free, 0, (size_t)m->nslot * 4 * sizeof(double)); /* a radius <= 0 holds nothing */
    for (g = 0; g < m->ngroup; g++) d->group_near[4 * g + 3] = HUGE_VAL;
}

void cd_contact_eval(const cd_model *m, cd_data *d, double *zdot)
{
    int g, k;
    shape_poses(m, d);
    for (g = 0; g < m->ngroup; g++) {
        int k0 = m->group_adr[g], k1 = k0 + m->group_num[g];
        double xb;
        for (k = k0; k < k1 && d->slot_mode[k] != CD_MODE_OPEN; k++) {}
        if (k < k1 && d->opt.broad_phase && group_apart(m, d, g, &xb)) {
            /* the whole group is apart: its open slots are skipped before any per-slot work */
            for (k = k0; k < k1; k++)
                if (d->slot_mode[k] == CD_MODE_OPEN) skip_slot(d, k, xb, zdot);
                else eval_slot(m, d, k, zdot);
        } else if (d->opt.broad_phase) {
            group_slots(m, d, g, zdot);
        } else {
            for (k = k0; k < k1; k++) eval_slot(m, d, k, zdot);
        }
    }
}

/* One slot in full (or, open and apart: skipped after its geometry). */
static void eval_slot(const cd_model *m, cd_data *d, int k, double *zdot)
{
    int cp = m->slot_cp[k], sh = m->slot_shape[k], mode = d->slot_mode[k];
    int ba = m->cp_body[cp], bb = m->shape_body[sh], res, open_bp = mode == CD_MODE_OPEN && d->opt.broad_phase;
    const cd_contact_law *L = &m->law[m->slot_law[k]];
    double pw[3], n[3], s[3], c[3], vt[3];
    double x, xd, fraw, fn = 0, ft[3] = {0, 0, 0}, F[6], arm[3];
    double *z = d->y + m->ny_slot_adr + 3 * k;
    /* with the broad phase an open slot found apart (beyond the bounding
     * sphere, or inside its free sphere) is skipped below, x a bound */
    res = slot_geometry(m, d, k, mode == CD_MODE_OPEN, open_bp, pw, &x, n, s, open_bp ? d->slot_free + 4 * k : NULL);
    if (res == 0 && open_bp && x < 0) {
        /* broad phase: an open slot apart from its shape (x < 0: its
         * switching function -min(K x, f_raw) > 0, it cannot switch here)
         * exerts no force and has no anchor rate; the rest of its outputs
         * (rate, point, normal, slip velocity, f_raw) is computed only
         * when asked for (cd_contact_slot_outputs, cd_contact_switch) */
        skip_slot(d, k, x, zdot);
        return;
    }
    d->slot_geomfail[k] = (res < 0);
    d->slot_far[k] = 0;
    zdot[3 * k] = zdot[3 * k + 1] = zdot[3 * k + 2] = 0.0;
    if (res != 0) {
        /* a rejected geometry answer: no force, reported by the integrator */
        x = 0.0;
        d->slot_x[k] = x;
        d->slot_xdot[k] = 0;
        d->slot_fnraw[k] = 0.0;
        d->slot_fn[k] = 0;
        cd_v3_zero(d->slot_ft + 3 * k);
        cd_v3_zero(d->slot_vt + 3 * k);
        cd_v3_copy(d->slot_point + 3 * k, pw);
        cd_v3_zero(d->slot_normal + 3 * k);
        return;
    }
    slot_rates(m, d, k, x, n, s, c, &xd, vt);
    /* eq. (3), or Hunt-Crossley (contact.h) */
    fraw = cd_law_normal(L, x, xd, NULL, NULL);
    if (mode != CD_MODE_OPEN) {
        fn = fraw; /* >= 0 between events (no pull): separation is located where it reaches 0;
                      with `pull` it may be negative until x returns to 0 */
        if (mode == CD_MODE_STICK) {
            double zw[3], zt[3];
            double fk[3], fd[3];
            cd_m3_mulv(zw, d->body_R + 9 * bb, z);
            tangential(zt, zw, n);
            /* eq. (4): f_t = -(K_t z_t^pt + D_t v_t^qt), signed vector powers */
            vpow(fk, zt, L->Kt, L->pt);
            vpow(fd, vt, L->Dt, L->qt);
            cd_v3_add(ft, fk, fd);
            cd_v3_scale(ft, ft, -1.0);
            cd_m3_tmulv(zdot + 3 * k, d->body_R + 9 * bb, vt);
        } else {
            double st[3], u[3], nu;
            tangential(st, d->slot_dir + 3 * k, n);
            cd_v3_normalize(st);
            double *va = d->slot_va + 3 * k;
            if (L->Dt > 0) {
                /* the bristle (K_t, D_t) saturated at the cone: its force
                 * K_t z_t^pt + D_t zdot^qt = mu_k f_n s_t sets the deflection's
                 * rate, and the anchor slips at v_a = v_t - zdot (header) */
                double zd[3], fb[3];
                cd_v3_copy(fb, st);
                (void)trial_force(L, d->body_R + 9 * bb, z, n, vt, fb, st);
                bristle_va(L, d->body_R + 9 * bb, z, n, vt, fn, st, va, zd);
                cd_m3_tmulv(zdot + 3 * k, d->body_R + 9 * bb, zd);
            } else {
                /* no tangential damper: the deflection sits on the cone,
                 * |z_el| = (mu_k f_n / K_t)^(1/pt), and moves at its rate */
                double fdot = L->K * L->p * (L->p == 1.0 ? 1.0 : pow(fabs(x), L->p - 1.0)) * xd, zrate;
                if (L->pt == 1.0) zrate = L->mu_k * fdot / L->Kt;
                else zrate = fn > 0 ? pow(L->mu_k / L->Kt, 1.0 / L->pt) * pow(fn, 1.0 / L->pt - 1.0) * fdot / L->pt : 0.0;
                cd_v3_copy(va, vt);
                cd_v3_axpy(va, -zrate, st);
            }
            cd_v3_copy(u, va);
            cd_v3_axpy(u, 2.0 * d->opt.v_reg, st);
            nu = cd_v3_norm(u);
            /* eq. (5): Coulomb, against the slip; none while a `pull` contact is in tension */
            if (nu > 0 && (fn > 0 || (CD_CONTACT_SLIP_SMOOTH && !L->pull))) cd_v3_scale(ft, u, -L->mu_k * fn / nu);
        }
    }
    if (d->slot_held[k] && mode != CD_MODE_OPEN) {
        /* switches suspended by the chattering guard (at most `dwell`):
         * keep the no-pull rule and the friction cone by clipping */
        double nft;
        if (fn < 0 && !L->pull) fn = 0;
        nft = cd_v3_norm(ft);
        if (fn < 0) { cd_v3_zero(ft); nft = 0; }
        if (nft > L->mu_s * fn) cd_v3_scale(ft, ft, nft > 0 ? L->mu_s * fn / nft : 0.0);
    }
    d->slot_x[k] = x;
    d->slot_xdot[k] = xd;
    d->slot_fnraw[k] = fraw;
    d->slot_fn[k] = fn;
    cd_v3_copy(d->slot_ft + 3 * k, ft);
    cd_v3_copy(d->slot_vt + 3 * k, vt);
    cd_v3_copy(d->slot_point + 3 * k, c);
    cd_v3_copy(d->slot_normal + 3 * k, n);
    if (mode == CD_MODE_OPEN) return;
    /* wrench on A about its system's reference point, reaction on B */
    cd_v3_scale(F + 3, n, fn);
    cd_v3_add(F + 3, F + 3, ft);
    cd_v3_sub(arm, c, d->sys_ref + 3 * m->body_sys[ba]);
    cd_v3_cross(F, arm, F + 3);
    for (res = 0; res < 6; res++) d->body_fext[6 * ba + res] += F[res];
    cd_v3_sub(arm, c, d->sys_ref + 3 * m->body_sys[bb]);
    cd_v3_cross(F, arm, F + 3);
    for (res = 0; res < 6; res++) d->body_fext[6 * bb + res] -= F[res];
}

/* Switching functions of slot k after cd_contact_eval, signed so that a
 * NEGATIVE value means "the slot must leave its mode":
 *   open:  -min(K x, f_raw)          onset when both penetration and f_raw > 0
 *          (pull: -K x, onset at x = 0)
 *   stick: min(K x, f_raw)           separation (pull: K x)
 *          mu_s f_n - |f_t|          stick -> slip
 *   slip:  min(K x, f_raw)           separation
 *          v_a . s_t + v_reg         slip -> stick (slip velocity reversed)
 * With forgive, zero-time re-checks pardon round-off in the friction
 * functions (e.g. slip -> stick with mu_s = mu_k lands exactly on the cone
 * and must not flip straight back). */
void cd_contact_switch(const cd_model *m, const cd_data *d, int k, int forgive, double g[2])
{
    const cd_contact_law *L = &m->law[m->slot_law[k]];
    double x = d->slot_x[k], f = d->slot_fnraw[k];
    int mode = d->slot_mode[k];
    if (d->slot_far[k]) {
        /* skipped by the broad phase: x and f_raw as the full evaluation gives them */
        double xd, c[3], n[3], vt[3];
        (void)open_outputs(m, d, k, &x, &xd, &f, c, n, vt);
    }
    /* min(K x, f_raw): the penetration scaled to a force so that min() compares like with like */
    double gn = L->pull ? x * L->K : ((x * L->K) < f ? x * L->K : f);
    g[1] = 1.0;
    if (mode == CD_MODE_OPEN) {
        g[0] = -gn;
        return;
    }
    g[0] = gn;
    if (mode == CD_MODE_STICK) {
        double fc = d->slot_fn[k] > 0 ? d->slot_fn[k] : 0.0; /* a pulling contact holds no friction */
        g[1] = L->mu_s * fc - cd_v3_norm(d->slot_ft + 3 * k);
        if (forgive && g[1] >= -1e-9 * L->mu_s * fc) g[1] = 0;
    } else {
        const double *n = d->slot_normal + 3 * k;
        double st[3];
        tangential(st, d->slot_dir + 3 * k, n);
        cd_v3_normalize(st);
        if (L->Dt > 0) {
            double fb[3];
            cd_v3_copy(fb, st);
            (void)trial_force(L, d->body_R + 9 * m->shape_body[m->slot_shape[k]], d->y + m->ny_slot_adr + 3 * k, n,
                              d->slot_vt + 3 * k, fb, st);
        }
        g[1] = cd_v3_dot(d->slot_va + 3 * k, st) + d->opt.v_reg;
        if (forgive && g[1] >= -1e-3 * d->opt.v_reg) g[1] = 0;
    }
}

/* An open slot apart by more than its check point's radius is left out of
 * the smallest switching function. Its functions are positive (-min(K x,
 * f_raw) >= -K x > 0, and 1), so leaving it out moves no zero of that
 * minimum and hides no switch; it spares the slip velocity and the law of
 * every slot the broad phase skipped, at every step end and locator
 * iteration (9 % of a capture run). The rule is on the evaluation's own x
 * (what the full evaluation gives: exact, the bounding sphere's gap, or a
 * hull face plane's bound), computed for a skipped slot by the same
 * operations (its stored x bounds the exact x but not that one), so it is
 * the same with and without the broad phase. The radius keeps the slot in
 * the minimum over the last r of its approach, where a touch is located,
 * so the root finder sees its function continuous there. */
int cd_contact_switch_near(const cd_model *m, const cd_data *d, int k, double g[2])
{
    double x = d->slot_x[k], r = m->cp_radius[m->slot_cp[k]];
    if (d->slot_mode[k] == CD_MODE_OPEN) {
        if (d->slot_far[k] && !open_apart(m, d, k, NULL, &x)) {
            double pw[3], n[3], s[3];
            if (slot_geometry(m, d, k, 1, 1, pw, &x, n, s, NULL) != 0) x = 0.0; /* (never: accepted at the evaluation) */
        }
        if (x < -r) return 0;
    }
    cd_contact_switch(m, d, k, 0, g);
    return 1;
}

static void any_tangent(double t[3], const double n[3])
{
    double a[3] = {1, 0, 0};
    if (fabs(n[0]) > 0.9) cd_v3_set(a, 0, 1, 0);
    cd_v3_cross(t, n, a);
    cd_v3_normalize(t);
}

int cd_contact_transition(const cd_model *m, cd_data *d, int k, int forgive, cd_event *ev)
{
    const cd_contact_law *L = &m->law[m->slot_law[k]];
    double g[2], *z = d->y + m->ny_slot_adr + 3 * k;
    const double *n = d->slot_normal + 3 * k, *ft = d->slot_ft + 3 * k, *vt = d->slot_vt + 3 * k;
    int from = d->slot_mode[k], to = from, kind = -1;
    cd_contact_switch(m, d, k, forgive, g);
    if (g[0] < 0) {
        if (from == CD_MODE_OPEN) { to = CD_MODE_STICK; kind = CD_EV_ONSET; }
        else { to = CD_MODE_OPEN; kind = CD_EV_SEPARATION; }
        cd_v3_zero(z);
    } else if (g[1] < 0 && from == CD_MODE_STICK) {
        double nf = cd_v3_norm(ft), *s = d->slot_dir + 3 * k;
        to = CD_MODE_SLIP;
        kind = CD_EV_STICK_SLIP;
        /* the slip goes where the stick spring is pulled: against f_t */
        if (nf > 0) cd_v3_scale(s, ft, -1.0 / nf);
        else if (cd_v3_norm(vt) > 0) { cd_v3_copy(s, vt); cd_v3_normalize(s); }
        else any_tangent(s, n);
    } else if (g[1] < 0 && from == CD_MODE_SLIP && L->Dt > 0) {
        /* the trial force fell back inside the cone (|f_tr| < mu_k f_n -
         * D_t v_reg): stick, keeping the bristle's deflection z, so that the
         * stick force -f_tr continues the slip's -mu_k f_n s up to D_t v_reg */
        to = CD_MODE_STICK;
        kind = CD_EV_SLIP_STICK;
    } else if (g[1] < 0 && from == CD_MODE_SLIP) {
        const double *vs = d->slot_va + 3 * k;
        double nv = cd_v3_norm(vs), st[3], perp[3];
        /* the slip velocity's part across the anchored direction: a 3-D slip
         * that turned past 90 deg at speed still has it; a slip that merely
         * reversed along the direction (it stopped, or the friction cone grew
         * faster than the contact point moves, so the spring left the cone)
         * has none and sticks. (Re-anchoring a reversal along the direction
         * would flip the anchor back and forth at one instant.) */
        tangential(st, d->slot_dir + 3 * k, n);
        cd_v3_normalize(st);
        cd_v3_copy(perp, vs);
        cd_v3_axpy(perp, -cd_v3_dot(vs, st), st);
        /* the cone's growth rate zrate (v_a = v_t - zrate s_t), and the slip
         * function after a re-anchoring to s' = v_a/|v_a|: it must be
         * positive, else no slip direction is consistent (the cone grows
         * faster than the point slips) and the contact sticks */
        double zrate = cd_v3_dot(vt, st) - cd_v3_dot(vs, st);
        double g_new = nv > 0 ? cd_v3_dot(vt, vs) / nv - zrate + d->opt.v_reg : -1.0;
        if (cd_v3_norm(perp) > 100.0 * d->opt.v_reg && g_new > 0) {
            /* 3-D slip that turned past 90 deg at speed: re-anchor, keep slipping */
            kind = CD_EV_SLIP_TURN;
            cd_v3_scale(d->slot_dir + 3 * k, vs, 1.0 / nv);
        } else {
            double zw[3], w[3], fd[3], nw;
            to = CD_MODE_STICK;
            kind = CD_EV_SLIP_STICK;
            /* anchor so that f_t is continuous: K_t z^pt = -f_t - D_t v_t^qt, stored
             * in the axes of the shape's body (see the header) */
            vpow(fd, vt, L->Dt, L->qt);
            cd_v3_add(w, ft, fd);
            cd_v3_scale(w, w, -1.0);
            nw = cd_v3_norm(w);
            if (L->pt == 1.0) cd_v3_scale(zw, w, 1.0 / L->Kt);
            else cd_v3_scale(zw, w, nw > 0 ? pow(nw / L->Kt, 1.0 / L->pt) / nw : 0.0);
            cd_m3_tmulv(z, d->body_R + 9 * m->shape_body[m->slot_shape[k]], zw);
        }
    }
    if (kind < 0) return 0;
    ev->kind = kind;
    ev->owner_kind = CD_OWNER_SLOT;
    ev->owner = k;
    ev->slot = k;
    ev->body_a = m->cp_body[m->slot_cp[k]];
    ev->body_b = m->shape_body[m->slot_shape[k]];
    ev->mode_from = from;
    ev->mode_to = to;
    ev->x = d->slot_x[k];
    ev->fn = d->slot_fn[k];
    ev->ft = cd_v3_norm(d->slot_ft + 3 * k);
    d->slot_mode[k] = to;
    return 1;
}
