/* cd_data: creation (one block for every array, from the caller's allocator
 * or malloc), reset and the callbacks. The integrator's GSL objects are the
 * only other allocation (GSL allocates them itself). */
#include "capdyn/sim.h"
#include "../math/cd_math.h"
#include "integ.h"
#include "../dynamics/aba.h"
#include "../contact/contact.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void *std_alloc(size_t n, void *ctx) { (void)ctx; return malloc(n); }
static void std_free(void *p, void *ctx) { (void)ctx; free(p); }

void cd_data_free(cd_data *d)
{
    cd_allocator a;
    if (!d) return;
    cd_integ_free(d->integ);
    a = d->allocator;
    a.free(d->block, a.ctx);
}

/* d->work: 12 nbody + 4 maxdof doubles for RNE/CRBA, at least
 * CD_ABA_WORK_PER_BODY nbody for the articulated-body path (dynamics/aba.h) */
static int work_size(int nb, int maxdof)
{
    int crba = 12 * nb + 4 * maxdof, aba = CD_ABA_WORK_PER_BODY * nb;
    return crba > aba ? crba : aba;
}

/* Lays the arrays out in one block: with base == NULL only measures. Every
 * array starts on a 16-byte boundary; an empty array still gets one element
 * so that no pointer is NULL. */
static size_t carve(const cd_model *m, cd_data *d, char *base, int maxdof)
{
    size_t off = 0;
    int nb = m->nbody, ns = m->nslot;
#define CARVE(field, n)                                                              \
    do {                                                                             \
        size_t cnt_ = (size_t)(n) > 0 ? (size_t)(n) : 1;                              \
        off = (off + 15) & ~(size_t)15;                                              \
        if (base) d->field = (void *)(base + off);                                   \
        off += cnt_ * sizeof *d->field;                                              \
    } while (0)
    off = sizeof(cd_data);
    CARVE(y, m->ny); CARVE(ydot, m->ny); CARVE(ypresc, m->ny);
    CARVE(ctrl, m->nu); CARVE(qfrc_applied, m->nv); CARVE(xfrc_applied, 6 * nb); CARVE(xfrc_body, 6 * nb);
    CARVE(user_mode, m->nuser);
    CARVE(body_R, 9 * nb); CARVE(body_x, 3 * nb); CARVE(body_c, 3 * nb); CARVE(body_w, 3 * nb);
    CARVE(body_v, 3 * nb); CARVE(body_axisw, 3 * nb); CARVE(body_V, 6 * nb); CARVE(body_S, 6 * nb);
    CARVE(sys_ref, 3 * m->nsys);
    CARVE(udot, m->nv); CARVE(qfrc_actuator, m->nv); CARVE(qfrc_passive, m->nv); CARVE(qfrc_constraint, m->nv);
    CARVE(tau, m->nv); CARVE(act_force, m->nu); CARVE(act_velocity, m->nu);
    CARVE(body_fext, 6 * nb); CARVE(H, maxdof * maxdof); CARVE(work, work_size(nb, maxdof));
    CARVE(jwork, 12 * maxdof + 36);
    {
        size_t cnt = (size_t)(2 * nb) * sizeof(cd_rbi);
        off = (off + 15) & ~(size_t)15;
        if (base) d->body_rbi = base + off;
        off += cnt;
    }
    CARVE(slot_mode, ns); CARVE(slot_dir, 3 * ns); CARVE(slot_x, ns);
    CARVE(slot_xdot, ns); CARVE(slot_fn, ns); CARVE(slot_ft, 3 * ns); CARVE(slot_point, 3 * ns);
    CARVE(slot_normal, 3 * ns); CARVE(slot_vt, 3 * ns); CARVE(slot_va, 3 * ns); CARVE(slot_fnraw, ns);
    CARVE(slot_geomfail, ns); CARVE(slot_far, ns); CARVE(slot_free, 4 * ns); CARVE(group_near, 4 * m->ngroup);
    CARVE(shape_R, 9 * m->nshape); CARVE(shape_xw, 3 * m->nshape);
    CARVE(lim_mode, m->nlim); CARVE(lim_depth, m->nlim); CARVE(lim_force, m->nlim); CARVE(lim_raw, m->nlim);
    CARVE(fric_mode, m->nfric); CARVE(fric_dir, m->nfric); CARVE(fric_force, m->nfric);
    CARVE(finger_mode, m->nfinger); CARVE(finger_brake, m->nfinger); CARVE(finger_load, m->nfinger);
    CARVE(finger_theta, m->nfinger); CARVE(finger_t0, m->nfinger);
    CARVE(sw_tswitch, m->nsw); CARVE(sw_nswitch, m->nsw); CARVE(sw_held, m->nsw);
    CARVE(act_piece, m->nu);
    CARVE(state_undo, cd_state_body_size(m));
    CARVE(ev, d ? d->ev_cap : 0);
#undef CARVE
    off = (off + 15) & ~(size_t)15;
    if (base) d->integ = base + off;
    off += cd_integ_size(m);
    return off;
}

cd_data *cd_data_create_ex(const cd_model *m, int event_capacity, const cd_allocator *alloc, cd_error *err)
{
    cd_data probe, *d;
    cd_allocator a;
    int maxdof = 1, s;
    size_t size;
    char *block;
    if (!m || !m->finalized) {
        cd_error_set(err, CD_EINVAL, "model is NULL or not finalized");
        return NULL;
    }
    /* m->opt may have been edited after finalize; GSL would abort on some values */
    if (cd_options_check(&m->opt, err) != CD_OK) return NULL;
    if (m->ny == 0) {
        /* nothing can move and nothing can touch: GSL cannot integrate a 0-dimensional system */
        cd_error_set(err, CD_EINVAL, "model has no degree of freedom and no contact slot: nothing to simulate");
        return NULL;
    }
    if (event_capacity < 0 || event_capacity > 100000000) {
        cd_error_set(err, CD_EINVAL, "event capacity %d out of range [0, 1e8]", event_capacity);
        return NULL;
    }
    if (alloc && (!alloc->alloc || !alloc->free)) {
        cd_error_set(err, CD_EINVAL, "allocator needs both alloc and free");
        return NULL;
    }
    a.alloc = alloc ? alloc->alloc : std_alloc;
    a.free = alloc ? alloc->free : std_free;
    a.ctx = alloc ? alloc->ctx : NULL;
    for (s = 0; s < m->nsys; s++)
        if (m->sys_ndof[s] > maxdof) maxdof = m->sys_ndof[s];
    memset(&probe, 0, sizeof probe);
    probe.ev_cap = event_capacity > 0 ? event_capacity : 4096;
    size = carve(m, &probe, NULL, maxdof);
    block = a.alloc(size, a.ctx);
    if (!block) {
        size_t stiff = cd_integ_stiff_size(m);
        if (stiff > size / 2) /* what to change: the dense matrices grow with the square of the unknowns */
            cd_error_set(err, CD_ENOMEM,
                         "out of memory creating data (%zu bytes, of which %zu for the dense matrices of the implicit "
                         "steppers over %d unknowns; an explicit integrator such as \"rk8pd\" needs %zu)",
                         size, stiff, m->ny, size - stiff);
        else
            cd_error_set(err, CD_ENOMEM, "out of memory creating data (%zu bytes)", size);
        return NULL;
    }
    memset(block, 0, size);
    d = (cd_data *)(void *)block;
    d->ev_cap = probe.ev_cap;
    carve(m, d, block, maxdof);
    d->block = block;
    d->allocator = a;
    d->opt = m->opt;
    d->slot_tswitch = d->sw_tswitch;   /* the slots are the first switch units */
    d->slot_held = d->sw_held;
    if (!cd_integ_create(m, d, d->integ, err)) {
        cd_integ_free(d->integ);
        a.free(block, a.ctx);
        return NULL;
    }
    if (cd_data_reset(m, d, err) != CD_OK) {
        cd_data_free(d);
        return NULL;
    }
    return d;
}

cd_data *cd_data_create(const cd_model *m, int event_capacity, cd_error *err)
{
    return cd_data_create_ex(m, event_capacity, NULL, err);
}

void cd_data_set_control(cd_data *d, cd_control_fn fn, void *user)
{
    if (!d) return;
    d->control = fn;
    d->control_user = user;
}

void cd_data_set_user_switches(cd_data *d, cd_user_switch_fn g, cd_user_transition_fn tr, void *user)
{
    if (!d) return;
    d->user_switch = g;
    d->user_transition = tr;
    d->switch_user = user;
}

cd_status cd_data_reset(const cd_model *m, cd_data *d, cd_error *err)
{
    if (!m || !d) {
        cd_error_set(err, CD_EINVAL, "cd_data_reset: %s is NULL", !m ? "the model" : "the data");
        return CD_EINVAL;
    }
    int s, b, k;
    d->t = 0.0;
    memset(d->y, 0, (size_t)m->ny * sizeof(double));
    memset(d->ctrl, 0, (size_t)m->nu * sizeof(double));
    memset(d->qfrc_applied, 0, (size_t)m->nv * sizeof(double));
    memset(d->xfrc_applied, 0, 6 * (size_t)m->nbody * sizeof(double));
    memset(d->xfrc_body, 0, 6 * (size_t)m->nbody * sizeof(double));
    memset(d->user_mode, 0, (size_t)m->nuser * sizeof(int));
    for (s = 0; s < m->nsys; s++) {
        cd_sys_state x = cd_state_of(m, d, s);
        int b0 = m->sys_body_adr[s];
        if (x.pos) {
            cd_v3_copy(x.pos, m->sys_pos0 + 3 * s);
            memcpy(x.quat, m->sys_quat0 + 4 * s, 4 * sizeof(double));
            cd_v3_copy(x.vel, m->sys_vel0 + 3 * s);
            cd_v3_copy(x.angvel, m->sys_angvel0 + 3 * s);
        }
        for (b = b0 + 1; b < b0 + m->sys_nbody[s]; b++) {
            x.q[b - b0 - 1] = m->body_q0[b];
            x.qd[b - b0 - 1] = m->body_qd0[b];
        }
    }
    for (k = 0; k < m->nslot; k++) {
        d->slot_mode[k] = CD_MODE_OPEN;
        cd_v3_zero(d->slot_dir + 3 * k);
    }
    cd_contact_cache_clear(m, d); /* no free or near sphere yet */
    for (k = 0; k < m->nlim; k++) d->lim_mode[k] = CD_LIM_FREE;
    for (k = 0; k < m->nfric; k++) {
        d->fric_mode[k] = CD_MODE_STICK;
        d->fric_dir[k] = 0;
    }
    for (k = 0; k < m->nfinger; k++) {
        d->finger_mode[k] = CD_CLUTCH_ENGAGED;
        d->finger_brake[k] = 0;
        d->finger_t0[k] = 0;
    }
    for (k = 0; k < m->nsw; k++) {
        d->sw_tswitch[k] = -HUGE_VAL;
        d->sw_nswitch[k] = 0;
        d->sw_held[k] = 0;
    }
    memset(d->act_piece, 0, (size_t)m->nu * sizeof(int));
    d->ev_count = 0;
    memset(&d->stats, 0, sizeof d->stats);
    d->stats.h_min_seen = HUGE_VAL;
    d->stats.t_switch_last = -1.0;
    cd_integ_reset(m, d);
    /* contacts and stops already closed at t = 0 start closed (docs/contact.md),
     * optionally preloaded to static equilibrium */
    return cd_integ_initial_modes(m, d, err);
}
