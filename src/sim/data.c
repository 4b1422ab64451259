/* cd_data: creation (the only allocation besides the model), reset and the
 * event log. */
#include "capdyn/sim.h"
#include "../math/cd_math.h"
#include "integ.h"
#include "../dynamics/aba.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *ev_names[CD_EV_NKINDS] = {
    "onset", "separation", "stick_slip", "slip_stick", "slip_turn", "geometry_failure"};
static const char *mode_names[3] = {"open", "stick", "slip"};

const char *cd_event_kind_name(cd_event_kind k)
{ return (k >= 0 && k < CD_EV_NKINDS) ? ev_names[k] : "?"; }
const char *cd_slot_mode_name(cd_slot_mode mo)
{ return (mo >= 0 && mo <= CD_MODE_SLIP) ? mode_names[mo] : "?"; }

void cd_data_free(cd_data *d)
{
    if (!d) return;
    cd_integ_free(d->integ);
    free(d->y); free(d->ydot); free(d->body_R); free(d->body_x); free(d->body_c);
    free(d->body_w); free(d->body_v); free(d->body_axisw); free(d->body_V); free(d->body_S);
    free(d->sys_ref); free(d->udot); free(d->tau); free(d->body_fext); free(d->body_fuser);
    free(d->H); free(d->work); free(d->jwork); free(d->body_rbi);
    free(d->slot_mode); free(d->slot_dir); free(d->slot_va); free(d->slot_tswitch); free(d->slot_x);
    free(d->slot_xdot); free(d->slot_fn); free(d->slot_ft); free(d->slot_point);
    free(d->slot_normal); free(d->slot_vt); free(d->slot_fnraw); free(d->slot_geomfail); free(d->slot_held);
    free(d->ev);
    free(d);
}

/* d->work: 12 nbody + 4 maxdof doubles for RNE/CRBA, at least
 * CD_ABA_WORK_PER_BODY nbody for the articulated-body path (dynamics/aba.h) */
static int work_size(int nb, int maxdof)
{
    int crba = 12 * nb + 4 * maxdof, aba = CD_ABA_WORK_PER_BODY * nb;
    return crba > aba ? crba : aba;
}

cd_data *cd_data_create(const cd_model *m, int event_capacity, cd_error *err)
{
    cd_data *d;
    int maxdof = 1, s, nb, ns, ok = 1;
    if (!m || !m->finalized) {
        if (err) { err->status = CD_EINVAL; snprintf(err->msg, sizeof err->msg, "model is NULL or not finalized"); }
        return NULL;
    }
    /* m->opt may have been edited after finalize; GSL would abort on some values */
    if (cd_options_check(&m->opt, err) != CD_OK) return NULL;
    d = calloc(1, sizeof *d);
    if (!d) goto nomem;
    for (s = 0; s < m->nsys; s++)
        if (m->sys_ndof[s] > maxdof) maxdof = m->sys_ndof[s];
    nb = m->nbody;
    ns = m->nslot ? m->nslot : 1;
#define AL(p, n) ok &= ((d->p = calloc((size_t)(n), sizeof *d->p)) != NULL)
    AL(y, m->ny + 1); AL(ydot, m->ny + 1);
    AL(body_R, 9 * nb); AL(body_x, 3 * nb); AL(body_c, 3 * nb); AL(body_w, 3 * nb);
    AL(body_v, 3 * nb); AL(body_axisw, 3 * nb); AL(body_V, 6 * nb); AL(body_S, 6 * nb);
    AL(sys_ref, 3 * m->nsys); AL(udot, m->nv + 1); AL(tau, m->nv + 1);
    AL(body_fext, 6 * nb); AL(body_fuser, 6 * nb);
    AL(H, maxdof * maxdof); AL(work, work_size(nb, maxdof)); AL(jwork, 12 * maxdof + 36);
    AL(slot_mode, ns); AL(slot_dir, 3 * ns); AL(slot_va, 3 * ns); AL(slot_tswitch, ns); AL(slot_x, ns);
    AL(slot_xdot, ns); AL(slot_fn, ns); AL(slot_ft, 3 * ns); AL(slot_point, 3 * ns);
    AL(slot_normal, 3 * ns); AL(slot_vt, 3 * ns); AL(slot_fnraw, ns); AL(slot_geomfail, ns); AL(slot_held, ns);
#undef AL
    if (ok) ok = (d->body_rbi = calloc((size_t)(2 * nb), sizeof(cd_rbi))) != NULL;
    d->ev_cap = event_capacity > 0 ? event_capacity : 4096;
    if (ok) ok = (d->ev = calloc((size_t)d->ev_cap, sizeof *d->ev)) != NULL;
    if (!ok) goto nomem;
    d->integ = cd_integ_create(m, d, err);
    if (!d->integ) { cd_data_free(d); return NULL; }
    cd_data_reset(m, d);
    return d;
nomem:
    cd_data_free(d);
    if (err) { err->status = CD_ENOMEM; snprintf(err->msg, sizeof err->msg, "out of memory creating data"); }
    return NULL;
}

void cd_data_reset(const cd_model *m, cd_data *d)
{
    int s, b, k;
    d->t = 0.0;
    memset(d->y, 0, (size_t)m->ny * sizeof(double));
    memset(d->body_fuser, 0, 6 * (size_t)m->nbody * sizeof(double));
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
        d->slot_tswitch[k] = -HUGE_VAL;
        d->slot_held[k] = 0;
        cd_v3_zero(d->slot_dir + 3 * k);
    }
    d->ev_count = 0;
    memset(&d->stats, 0, sizeof d->stats);
    d->stats.h_min_seen = HUGE_VAL;
    cd_integ_reset(m, d);
    /* contacts already closed at t = 0 start sticking (see docs/contact.md) */
    cd_integ_initial_modes(m, d);
}

const cd_event *cd_data_event(const cd_data *d, long i)
{
    long held = d->ev_count < d->ev_cap ? d->ev_count : d->ev_cap;
    long first = d->ev_count - held;
    if (i < 0 || i >= held) return NULL;
    return &d->ev[(first + i) % d->ev_cap];
}
