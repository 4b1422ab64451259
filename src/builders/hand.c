/* The paper's hands as generators on the model builder (include/capdyn/build.h):
 * a palm box and fingers of capsule links with check points along them
 * (stage 1), their drive and contact pairs (stage 2). Moved from the scenario
 * loader's [gripper] table (docs/grippers.md), which now fills a cd_hand_desc
 * and calls these; the arithmetic is the loader's, operation for operation,
 * so that a scenario's results are unchanged. */
#include "capdyn/build.h"
#include "../math/cd_math.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

cd_hand_desc cd_hand_desc_default(void)
{
    cd_hand_desc h;
    int j;
    memset(&h, 0, sizeof h);
    h.name = "hand";
    h.type = CD_HAND_SPACE;
    h.layout = CD_HAND_TWO_OPPOSED;
    h.attach_body = -1;
    h.palm_size[0] = 0.12;
    h.palm_size[1] = 0.04;
    h.palm_size[2] = 0.04;
    h.palm_mass = 2.0;
    cd_m3_identity(h.palm_rot);
    h.nlink = 2;
    for (j = 0; j < CD_HAND_MAX_LINKS; j++) h.link_length[j] = 0.08;
    h.radius = 0.008;
    h.spacing = 0.1;
    h.torque = 0.2;
    h.close_time = 1.0;
    h.close_angle = 120.0 * CD_PI / 180.0;
    h.clutch_threshold = 0.05;
    h.wire_stiffness = 20.0;
    h.wire_damping = -1;
    return h;
}

static int nfinger_of(cd_hand_layout l)
{
    return l == CD_HAND_TWO_OPPOSED || l == CD_HAND_TWO_INTERLEAVED ? 2 : l == CD_HAND_THREE_120 ? 3 : 4;
}
static double cps_of(const cd_hand_desc *h) { return h->checkpoint_spacing > 0 ? h->checkpoint_spacing : h->radius; }
static double zoff_of(const cd_hand_desc *h)
{
    if (h->layout == CD_HAND_TWO_PAIRS) return h->pair_offset > 0 ? h->pair_offset : h->spacing / 2;
    if (h->layout == CD_HAND_TWO_INTERLEAVED) return h->pair_offset > 0 ? h->pair_offset : 1.5 * h->radius;
    return 0;
}

/* check points of a row from a to b (inclusive, 1e-12 slack) every step,
 * without making them: the loops below take the same points */
static double row_count(double a, double b, double step)
{
    double n = floor((b + 1e-12 - a) / step) + 1;
    return n > 0 ? n : 0;
}

/* the description checked (not the model-dependent parts); 0 or -1 */
static int desc_ok(const cd_hand_desc *h, cd_error *err)
{
    int j;
    if (!h) { cd_error_set(err, CD_EINVAL, "hand: the description is NULL"); return -1; }
    if ((int)h->type < 0 || h->type >= CD_HAND_NTYPES) { cd_error_set(err, CD_EINVAL, "hand: unknown type %d", (int)h->type); return -1; }
    if ((int)h->layout < 0 || h->layout >= CD_HAND_NLAYOUTS) { cd_error_set(err, CD_EINVAL, "hand: unknown layout %d", (int)h->layout); return -1; }
    if (h->nlink < 1 || h->nlink > CD_HAND_MAX_LINKS) {
        cd_error_set(err, CD_EINVAL, "hand: nlink must be 1..%d, got %d", CD_HAND_MAX_LINKS, h->nlink);
        return -1;
    }
    if (!(h->radius > 0) || !isfinite(h->radius) || !(h->spacing > 0) || !isfinite(h->spacing) ||
        !(h->checkpoint_spacing >= 0) || !isfinite(h->checkpoint_spacing) || !(h->pair_offset >= 0) || !isfinite(h->pair_offset)) {
        cd_error_set(err, CD_EINVAL, "hand: radius and spacing must be finite and > 0, checkpoint_spacing and pair_offset finite and >= 0");
        return -1;
    }
    for (j = 0; j < h->nlink; j++)
        if (!(h->link_length[j] > 0) || !isfinite(h->link_length[j]) || !(h->link_mass[j] >= 0) || !isfinite(h->link_mass[j])) {
            cd_error_set(err, CD_EINVAL, "hand: link %d: length must be finite and > 0, mass finite and >= 0", j);
            return -1;
        }
    if (h->layout == CD_HAND_TWO_INTERLEAVED && !(zoff_of(h) > h->radius)) {
        cd_error_set(err, CD_EINVAL, "hand: pair_offset must be more than the finger radius %g m (the fingers must pass each other), got %g",
                     h->radius, zoff_of(h));
        return -1;
    }
    return 0;
}

double cd_hand_checkpoint_count(const cd_hand_desc *h)
{
    double cps, n;
    int j;
    if (desc_ok(h, NULL) < 0) return -1;
    cps = cps_of(h);
    n = (h->layout == CD_HAND_TWO_PAIRS ? 2 : 1) * row_count(-h->spacing / 2 + cps, h->spacing / 2 - cps, cps);
    for (j = 0; j < h->nlink; j++) n += nfinger_of(h->layout) * row_count(cps, h->link_length[j], cps);
    return n;
}

/* a point of the palm frame on the palm body */
static void on_palm(const cd_hand_desc *h, const double pbpos[3], const double pl[3], double out[3])
{
    cd_m3_mulv(out, h->palm_rot, pl);
    cd_v3_add(out, out, pbpos);
}

/* the palm: a new fixed-base system or the mounting body; its box and the
 * palm-face check points (tops flush with the face y = +size_y/2) */
static int build_palm(cd_model *m, const cd_hand_desc *h, cd_hand *out, const double pbpos[3], cd_error *err)
{
    const double *ps = h->palm_size;
    double half[3], cps = cps_of(h), zoff = zoff_of(h), x;
    int row;
    if (h->attach_body < 0) {
        cd_system_desc sd = cd_system_desc_default();
        sd.name = h->name ? h->name : "hand";
        sd.type = CD_BASE_FIXED;
        sd.mass = h->palm_mass;
        sd.inertia[0] = h->palm_mass * (ps[1] * ps[1] + ps[2] * ps[2]) / 12.0;
        sd.inertia[4] = h->palm_mass * (ps[0] * ps[0] + ps[2] * ps[2]) / 12.0;
        sd.inertia[8] = h->palm_mass * (ps[0] * ps[0] + ps[1] * ps[1]) / 12.0;
        cd_v3_copy(sd.pos, h->palm_pos);
        out->sys = cd_model_add_system(m, &sd, err);
        if (out->sys < 0) return -1;
        out->palm = m->sys_body_adr[out->sys];
    } else {
        int b;
        if (h->attach_body >= m->nbody) { cd_error_set(err, CD_EINVAL, "hand: attach_body %d is not a body", h->attach_body); return -1; }
        for (b = h->attach_body + 1; b < m->nbody; b++)
            if (m->body_parent[b] == h->attach_body) {
                cd_error_set(err, CD_EINVAL, "hand: attach_body '%s' has a child link '%s' (the fingers become its only branches)",
                             m->body_name[h->attach_body], m->body_name[b]);
                return -1;
            }
        out->sys = m->body_sys[h->attach_body];
        out->palm = h->attach_body;
    }
    half[0] = ps[0] / 2;
    half[1] = ps[1] / 2;
    half[2] = ps[2] / 2;
    out->palm_shape = cd_model_add_shape(m, out->palm, CD_SHAPE_BOX, pbpos, h->palm_rot, half, NULL, 0, err);
    if (out->palm_shape < 0) return -1;
    for (row = 0; row < (h->layout == CD_HAND_TWO_PAIRS ? 2 : 1); row++)
        for (x = -h->spacing / 2 + cps; x <= h->spacing / 2 - cps + 1e-12; x += cps) {
            double pl[3], p[3];
            pl[0] = x;
            pl[1] = half[1] - h->radius;
            pl[2] = h->layout != CD_HAND_TWO_PAIRS ? 0.0 : row == 0 ? -zoff : zoff;
            on_palm(h, pbpos, pl, p);
            if (cd_model_add_checkpoint(m, out->palm, p, h->radius, err) < 0) return -1;
            out->ncp++;
        }
    return 0;
}

/* finger f: its links, capsules, check points and joint elements */
static int build_finger(cd_model *m, const cd_hand_desc *h, cd_hand *out, int f, const double pbpos[3], cd_error *err)
{
    const double rad = h->radius, cps = cps_of(h), zoff = zoff_of(h), *L = h->link_length;
    cd_hand_layout lay = h->layout;
    double phi = lay == CD_HAND_THREE_120 ? CD_PI / 2 + 2 * CD_PI * f / 3.0 : (f % 2 == 0 ? CD_PI : 0.0);
    double fz = lay == CD_HAND_TWO_PAIRS ? (f < 2 ? -zoff : zoff) : lay == CD_HAND_TWO_INTERLEAVED ? (f == 0 ? -zoff : zoff) : 0.0;
    /* radial direction e_r; the finger closes about e_r x y */
    double er[3], ax[3];
    int parent = out->palm, j;
    cd_joint_props fjp = cd_joint_props_default();
    int fj_any = h->joint_spring != 0 || h->joint_damping != 0 || h->joint_limited;
    fjp.stiffness = h->joint_spring;
    fjp.damping = h->joint_damping;
    fjp.limited = h->joint_limited ? 1 : 0;
    fjp.stop_p = h->joint_stop_p;
    fjp.stop_q = h->joint_stop_q;
    er[0] = cos(phi); er[1] = 0; er[2] = sin(phi);
    ax[0] = -er[2]; ax[1] = 0; ax[2] = er[0];
    for (j = 0; j < h->nlink; j++) {
        cd_link_desc d = cd_link_desc_default();
        char ln[32];
        double M = h->link_mass[j] > 0 ? h->link_mass[j] : 0.6 * L[j]; /* ~ an aluminium tube: 0.6 kg/m */
        double It, Ia, R[9], spos[3], ssz[3], y;
        int id, sh;
        snprintf(ln, sizeof ln, "f%d_l%d", f, j);
        d.name = ln;
        d.parent = parent;
        if (j == 0) {
            double pl[3];
            pl[0] = er[0] * h->spacing / 2;
            pl[1] = h->palm_size[1] / 2;
            pl[2] = er[2] * h->spacing / 2 + fz;
            on_palm(h, pbpos, pl, d.pos);
            cd_m3_copy(d.rot, h->palm_rot);
        } else d.pos[1] = L[j - 1];
        cd_v3_copy(d.axis, ax);
        d.mass = M;
        d.com[1] = L[j] / 2;
        d.q0 = h->q0[j];
        if (h->joint_limited) {
            fjp.lower = h->joint_lower[j];
            fjp.upper = h->joint_upper[j];
            fjp.stop_K = h->joint_stop_K[j];
            fjp.stop_D = h->joint_stop_D[j];
            if (d.q0 < fjp.lower - 1e-12 || d.q0 > fjp.upper + 1e-12) {
                cd_error_set(err, CD_EINVAL, "hand: link %d: initial angle %g rad outside its stops [%g, %g] rad", j, d.q0, fjp.lower, fjp.upper);
                return -1;
            }
        }
        It = M * (3 * rad * rad + L[j] * L[j]) / 12.0;
        Ia = M * rad * rad / 2;
        memset(d.inertia, 0, sizeof d.inertia);
        d.inertia[0] = It; d.inertia[4] = Ia; d.inertia[8] = It;
        id = cd_model_add_link(m, out->sys, &d, err);
        if (id < 0) return -1;
        spos[0] = 0; spos[1] = L[j] / 2; spos[2] = 0;
        ssz[0] = rad; ssz[1] = L[j] / 2; ssz[2] = 0;
        cd_m3_from_rpy(R, -CD_PI / 2, 0, 0);
        sh = cd_model_add_shape(m, id, CD_SHAPE_CAPSULE, spos, R, ssz, NULL, 0, err);
        if (sh < 0) return -1;
        for (y = cps; y <= L[j] + 1e-12; y += cps) {
            double p[3];
            p[0] = 0; p[1] = y; p[2] = 0;
            if (cd_model_add_checkpoint(m, id, p, rad, err) < 0) return -1;
            out->ncp++;
        }
        if (fj_any && cd_model_set_joint(m, id, &fjp, err) != CD_OK) return -1;
        out->finger_body[f][j] = id;
        parent = id;
    }
    return 0;
}

int cd_build_hand(cd_model *m, const cd_hand_desc *h, cd_hand *out, cd_error *err)
{
    double pbpos[3] = {0, 0, 0}, n, cps;
    int f, j;
    if (!m || !out) { cd_error_set(err, CD_EINVAL, "hand: model or output is NULL"); return -1; }
    memset(out, 0, sizeof *out);
    out->sys = out->palm = out->palm_shape = out->law = -1;
    if (desc_ok(h, err) < 0) return -1;
    if (m->finalized) { cd_error_set(err, CD_EINVAL, "hand: the model is finalized"); return -1; }
    /* bounded before anything is made: a tiny spacing would otherwise
     * make check points until memory runs out */
    n = cd_hand_checkpoint_count(h);
    if (!(n <= CD_HAND_MAX_CHECKPOINTS)) {
        cd_error_set(err, CD_EINVAL, "hand: %.3g check points (checkpoint_spacing %g m), expected at most %d", n, cps_of(h),
                     CD_HAND_MAX_CHECKPOINTS);
        return -1;
    }
    cps = cps_of(h);
    for (j = 0; j < h->nlink; j++)
        if (!(cps <= h->link_length[j] + 1e-12)) { /* the loop of build_finger makes none */
            cd_error_set(err, CD_EINVAL, "hand: finger link %d (%g m) gets no check point (checkpoint_spacing %g m is longer)", j,
                         h->link_length[j], cps);
            return -1;
        }
    if (h->attach_body >= 0) cd_v3_copy(pbpos, h->palm_pos);
    out->nfinger = nfinger_of(h->layout);
    out->nlink = h->nlink;
    if (build_palm(m, h, out, pbpos, err) < 0) return -1;
    for (f = 0; f < out->nfinger; f++)
        if (build_finger(m, h, out, f, pbpos, err) < 0) return -1;
    return out->sys;
}

/* SOFT (a motor per finger) and TAKO (one for all): torque steps through the ratios */
static int build_motors(cd_model *m, const cd_hand_desc *h, cd_hand *hand, const char *name, const double *ratio, cd_error *err)
{
    int n = h->nlink, nf = hand->nfinger, soft = h->type == CD_HAND_SOFT, f, j, k;
    double st[3], sv[3];
    int ns = 0, jb[CD_HAND_MAX_FINGERS * CD_HAND_MAX_LINKS], njb = 0;
    double jr[CD_HAND_MAX_FINGERS * CD_HAND_MAX_LINKS];
    if (h->close_start > 0) { st[ns] = 0.0; sv[ns++] = 0.0; } /* no torque before the closing starts */
    st[ns] = h->close_start; sv[ns++] = h->torque;
    if (h->open_at > 0) { st[ns] = h->open_at; sv[ns++] = -h->torque; }
    for (f = 0; f < nf; f++) {
        if (soft) njb = 0;
        for (j = 0; j < n; j++) { jb[njb] = hand->finger_body[f][j]; jr[njb++] = ratio[j]; }
        if (soft || f == nf - 1) {
            cd_actuator_desc a = cd_actuator_desc_default();
            char an[300];
            int aid;
            if (soft) snprintf(an, sizeof an, "%s/f%d_motor", name, f);
            else snprintf(an, sizeof an, "%s/motor", name);
            a.name = an;
            a.type = CD_ACT_STEPS;
            a.tbl_t = st; a.tbl_v = sv; a.ntbl = ns;
            if (h->close_on_trigger) { /* u = ctrl, from the controller's trigger */
                a.type = CD_ACT_NONE;
                a.ntbl = h->close_start > 0 ? ns : 0;
            }
            a.ntrn = njb; a.trn_body = jb; a.trn_ratio = jr;
            a.stall_torque = h->stall_torque; a.noload_speed = h->noload_speed;
            aid = cd_model_add_actuator(m, &a, err);
            if (aid < 0) return -1;
            k = hand->nact++;
            hand->act[k] = aid;
            hand->act_close_u[k] = h->torque;
        }
    }
    return 0;
}

/* SPACE and TORQUE_SWITCH: clutched fingers on a closing schedule */
static int build_clutched(cd_model *m, const cd_hand_desc *h, cd_hand *hand, const char *name, const double *ratio, cd_error *err)
{
    int n = h->nlink, f, j;
    double lim = h->torque_limit, ctime = h->close_time, cangle = h->close_angle, cstart = h->close_start;
    double st[5], sq[5];
    int ns = 0;
    if (h->stall_torque > 0 && lim == 0) lim = h->stall_torque; /* the motor's stall torque limits the coupling */
    if (lim > 0 && !(lim > h->clutch_threshold)) { /* the coupling could never reach the threshold */
        cd_error_set(err, CD_EINVAL,
                     "hand: the coupling torque limit %g N m (%s) must exceed the clutch threshold %g N m, "
                     "or the clutch never disengages",
                     lim, h->torque_limit > 0 ? "torque_limit" : "the motor's stall torque", h->clutch_threshold);
        return -1;
    }
    /* the motor turns the synchronising pulley: the closing cannot be
     * faster than its no-load speed */
    if (h->noload_speed > 0 && cangle / ctime > h->noload_speed) ctime = cangle / h->noload_speed;
    st[ns] = 0.0; sq[ns++] = 0.0;
    if (cstart > 0) { st[ns] = cstart; sq[ns++] = 0.0; }
    st[ns] = cstart + ctime; sq[ns++] = cangle;
    if (h->open_at > 0) { st[ns] = h->open_at; sq[ns++] = cangle; st[ns] = h->open_at + ctime; sq[ns++] = 0.0; }
    for (f = 0; f < hand->nfinger; f++) {
        cd_finger_desc fd = cd_finger_desc_default();
        char fname[300];
        /* the default wire damping: critical for the finger's links about the base joint */
        double I = 0, arm = 0;
        int fid;
        for (j = 0; j < n; j++) {
            double M = h->link_mass[j] > 0 ? h->link_mass[j] : 0.6 * h->link_length[j];
            I += M * (arm + h->link_length[j] / 2) * (arm + h->link_length[j] / 2);
            arm += h->link_length[j];
        }
        snprintf(fname, sizeof fname, "%s/f%d", name, f);
        fd.name = fname;
        fd.type = h->type == CD_HAND_SPACE ? CD_FINGER_SPACE : CD_FINGER_TORQUE_SWITCH;
        fd.njoint = n;
        fd.joint_body = hand->finger_body[f];
        fd.ratio = ratio;
        fd.wire_K = h->wire_stiffness;
        fd.wire_D = h->wire_damping >= 0 ? h->wire_damping : 2.0 * sqrt(h->wire_stiffness * I);
        fd.threshold = h->clutch_threshold;
        fd.grasp_torque = h->torque;
        fd.torque_limit = lim;
        fd.sched_t = st; fd.sched_q = sq; fd.nsched = ns;
        fd.open_at = h->open_at;
        fid = cd_model_add_finger(m, &fd, err);
        if (fid < 0) return -1;
        hand->clutch[hand->nclutch++] = fid;
    }
    return 0;
}

/* the pairs: each finger's check points against the other fingers' links
 * (fingers that wrap past each other touch: they must not pass through),
 * the hand's against every target shape */
static int build_pairs(cd_model *m, const cd_hand_desc *h, cd_hand *hand, const int *target_sys, int ntarget, cd_error *err)
{
    int nf = hand->nfinger, n = h->nlink, f, g, i, j, k;
    for (f = 0; f < nf; f++)
        for (g = 0; g < nf; g++) {
            int bf = hand->finger_body[f][0], bg = hand->finger_body[g][0];
            double af[3], ag[3], cr[3], dp[3];
            if (g == f) continue;
            /* fingers that turn in parallel planes farther apart than two radii never meet */
            cd_m3_mulv(af, m->body_jnt_rot + 9 * bf, m->body_axis + 3 * bf);
            cd_m3_mulv(ag, m->body_jnt_rot + 9 * bg, m->body_axis + 3 * bg);
            cd_v3_cross(cr, af, ag);
            cd_v3_sub(dp, m->body_jnt_pos + 3 * bf, m->body_jnt_pos + 3 * bg);
            if (cd_v3_norm(cr) < 1e-9 && fabs(cd_v3_dot(dp, af)) > 2 * h->radius + 1e-12) continue;
            for (i = 0; i < n; i++)
                for (j = 0; j < n; j++) {
                    int shp = -1;
                    for (k = 0; k < m->nshape; k++)
                        if (m->shape_body[k] == hand->finger_body[g][j]) shp = k;
                    if (shp >= 0 && cd_model_add_pair(m, hand->sys, hand->finger_body[f][i], shp, hand->law, err) < 0) return -1;
                }
        }
    for (i = 0; i < ntarget; i++) {
        if (target_sys[i] < 0 || target_sys[i] >= m->nsys) { cd_error_set(err, CD_EINVAL, "hand: target system %d does not exist", target_sys[i]); return -1; }
        for (k = 0; k < m->nshape; k++)
            if (m->body_sys[m->shape_body[k]] == target_sys[i] && cd_model_add_pair(m, hand->sys, -1, k, hand->law, err) < 0) return -1;
    }
    return 0;
}

cd_status cd_build_hand_drive(cd_model *m, const cd_hand_desc *h, cd_hand *hand, const cd_contact_law *law,
                              const int *target_sys, int ntarget, cd_error *err)
{
    double ratio[CD_HAND_MAX_LINKS];
    const char *name;
    int j, n, given = 0;
    if (!m || !hand || !law || (ntarget > 0 && !target_sys) || ntarget < 0) {
        cd_error_set(err, CD_EINVAL, "hand drive: model, hand, law or targets are NULL");
        return CD_EINVAL;
    }
    if (desc_ok(h, err) < 0) return CD_EINVAL;
    if (hand->sys < 0 || hand->sys >= m->nsys || hand->nlink != h->nlink || hand->nfinger < 1) {
        cd_error_set(err, CD_EINVAL, "hand drive: the hand was not built from this description (cd_build_hand)");
        return CD_EINVAL;
    }
    if (!isfinite(h->torque) || !(h->close_time > 0) || !isfinite(h->close_time) || !(h->close_angle > 0) || !isfinite(h->close_angle) ||
        !(h->close_start >= 0) || !isfinite(h->close_start) || !(h->open_at >= 0) || !isfinite(h->open_at)) {
        cd_error_set(err, CD_EINVAL, "hand drive: torque must be finite, close_time and close_angle > 0, close_start and open_at >= 0");
        return CD_EINVAL;
    }
    if (h->open_at > 0 && (h->close_on_trigger || h->open_at <= h->close_start + h->close_time)) {
        cd_error_set(err, CD_EINVAL, "hand drive: open_at must come after the closing ends (%g s) and needs a timed closing",
                     h->close_start + h->close_time);
        return CD_EINVAL;
    }
    n = h->nlink;
    for (j = 0; j < n; j++) given |= h->ratio[j] != 0;
    for (j = 0; j < n; j++) ratio[j] = given ? h->ratio[j] : (double)((n - j) * (n - j)); /* quadratic, tip 1 */
    name = m->sys_name[hand->sys];
    hand->nact = hand->nclutch = 0;
    if (h->type == CD_HAND_SOFT || h->type == CD_HAND_TAKO) {
        if (build_motors(m, h, hand, name, ratio, err) < 0) return err ? err->status : CD_EINVAL;
    } else if (build_clutched(m, h, hand, name, ratio, err) < 0) {
        return err ? err->status : CD_EINVAL;
    }
    hand->law = cd_model_add_law(m, law, err);
    if (hand->law < 0) return err ? err->status : CD_EINVAL;
    if (build_pairs(m, h, hand, target_sys, ntarget, err) < 0) return err ? err->status : CD_EINVAL;
    return CD_OK;
}
