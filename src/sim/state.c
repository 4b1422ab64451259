/* The complete state of a cd_data (data.h): save, restore, copy.
 *
 * Layout (doubles): a header [magic, ny, nslot, nsw, nu, total size], then
 * t, y, every discrete part, the inputs, and the integrator's part
 * (cd_integ_state_*). Integers are stored exactly as doubles. */
#include "capdyn/sim.h"
#include "integ.h"

#include <string.h>

#define STATE_MAGIC 4.2e7 /* "capdyn state", version 1 */
#define HEADER 6

static size_t body_size(const cd_model *m)
{
    return (size_t)1 + (size_t)m->ny                             /* t, y */
           + (size_t)4 * m->nslot                                /* slot mode, slip direction */
           + (size_t)3 * m->nsw                                  /* switch times, counters, held */
           + (size_t)m->nlim + (size_t)2 * m->nfric + (size_t)m->nuser + (size_t)m->nu /* modes, rows */
           + (size_t)2 * m->nfinger                                                    /* clutches */
           + (size_t)m->nu + (size_t)m->nv + (size_t)12 * m->nbody;                     /* inputs */
}

size_t cd_state_size(const cd_model *m)
{
    return HEADER + body_size(m) + (size_t)cd_integ_state_size(m);
}

static void put_ints(double **p, const int *a, int n)
{
    int i;
    for (i = 0; i < n; i++) (*p)[i] = a[i];
    *p += n;
}
static void get_ints(const double **p, int *a, int n)
{
    int i;
    for (i = 0; i < n; i++) a[i] = (int)(*p)[i];
    *p += n;
}
static void put_d(double **p, const double *a, int n)
{
    memcpy(*p, a, (size_t)n * sizeof(double));
    *p += n;
}
static void get_d(const double **p, double *a, int n)
{
    memcpy(a, *p, (size_t)n * sizeof(double));
    *p += n;
}

void cd_state_get(const cd_model *m, cd_data *d, double *buf)
{
    double *p = buf + HEADER;
    buf[0] = STATE_MAGIC; buf[1] = m->ny; buf[2] = m->nslot; buf[3] = m->nsw; buf[4] = m->nu;
    buf[5] = (double)cd_state_size(m);
    *p++ = d->t;
    put_d(&p, d->y, m->ny);
    put_ints(&p, d->slot_mode, m->nslot);
    put_d(&p, d->slot_dir, 3 * m->nslot);
    put_d(&p, d->sw_tswitch, m->nsw);
    put_ints(&p, d->sw_nswitch, m->nsw);
    put_ints(&p, d->sw_held, m->nsw);
    put_ints(&p, d->lim_mode, m->nlim);
    put_ints(&p, d->fric_mode, m->nfric);
    put_d(&p, d->fric_dir, m->nfric);
    put_ints(&p, d->user_mode, m->nuser);
    put_ints(&p, d->act_piece, m->nu);
    put_ints(&p, d->finger_mode, m->nfinger);
    put_d(&p, d->finger_brake, m->nfinger);
    put_d(&p, d->ctrl, m->nu);
    put_d(&p, d->qfrc_applied, m->nv);
    put_d(&p, d->xfrc_applied, 6 * m->nbody);
    put_d(&p, d->xfrc_body, 6 * m->nbody);
    cd_integ_state_get(m, d, p);
}

cd_status cd_state_set(const cd_model *m, cd_data *d, const double *buf, cd_error *err)
{
    const double *p;
    if (!buf || buf[0] != STATE_MAGIC || buf[1] != m->ny || buf[2] != m->nslot || buf[3] != m->nsw ||
        buf[4] != m->nu || buf[5] != (double)cd_state_size(m)) {
        cd_error_set(err, CD_EINVAL, "cd_state_set: the buffer is not a state of this model (magic or sizes differ)");
        return CD_EINVAL;
    }
    p = buf + HEADER;
    d->t = *p++;
    get_d(&p, d->y, m->ny);
    get_ints(&p, d->slot_mode, m->nslot);
    get_d(&p, d->slot_dir, 3 * m->nslot);
    get_d(&p, d->sw_tswitch, m->nsw);
    get_ints(&p, d->sw_nswitch, m->nsw);
    get_ints(&p, d->sw_held, m->nsw);
    get_ints(&p, d->lim_mode, m->nlim);
    get_ints(&p, d->fric_mode, m->nfric);
    get_d(&p, d->fric_dir, m->nfric);
    get_ints(&p, d->user_mode, m->nuser);
    get_ints(&p, d->act_piece, m->nu);
    get_ints(&p, d->finger_mode, m->nfinger);
    get_d(&p, d->finger_brake, m->nfinger);
    get_d(&p, d->ctrl, m->nu);
    get_d(&p, d->qfrc_applied, m->nv);
    get_d(&p, d->xfrc_applied, 6 * m->nbody);
    get_d(&p, d->xfrc_body, 6 * m->nbody);
    cd_integ_state_set(m, d, p);
    /* the outputs of the restored state (the same evaluation the original had last) */
    if (cd_forward(m, d) != CD_OK) {
        cd_error_set(err, CD_ENUMERIC, "cd_state_set: the restored state cannot be evaluated at t = %.9g s", d->t);
        return CD_ENUMERIC;
    }
    return CD_OK;
}

/* dst takes src's t, y, modes, anchors, guard counters, schedule rows,
 * inputs and callbacks, not the integrator's part: what an evaluation of
 * dst needs to give src's outputs (the sampler's scratch data). No allocation. */
void cd_state_copy_eval(const cd_model *m, cd_data *dst, const cd_data *src)
{
    dst->t = src->t;
    memcpy(dst->y, src->y, (size_t)m->ny * sizeof(double));
    memcpy(dst->slot_mode, src->slot_mode, (size_t)m->nslot * sizeof(int));
    memcpy(dst->slot_dir, src->slot_dir, (size_t)3 * m->nslot * sizeof(double));
    memcpy(dst->sw_tswitch, src->sw_tswitch, (size_t)m->nsw * sizeof(double));
    memcpy(dst->sw_nswitch, src->sw_nswitch, (size_t)m->nsw * sizeof(int));
    memcpy(dst->sw_held, src->sw_held, (size_t)m->nsw * sizeof(int));
    memcpy(dst->lim_mode, src->lim_mode, (size_t)m->nlim * sizeof(int));
    memcpy(dst->fric_mode, src->fric_mode, (size_t)m->nfric * sizeof(int));
    memcpy(dst->fric_dir, src->fric_dir, (size_t)m->nfric * sizeof(double));
    memcpy(dst->user_mode, src->user_mode, (size_t)m->nuser * sizeof(int));
    memcpy(dst->act_piece, src->act_piece, (size_t)m->nu * sizeof(int));
    memcpy(dst->finger_mode, src->finger_mode, (size_t)m->nfinger * sizeof(int));
    memcpy(dst->finger_brake, src->finger_brake, (size_t)m->nfinger * sizeof(double));
    memcpy(dst->ctrl, src->ctrl, (size_t)m->nu * sizeof(double));
    memcpy(dst->qfrc_applied, src->qfrc_applied, (size_t)m->nv * sizeof(double));
    memcpy(dst->xfrc_applied, src->xfrc_applied, (size_t)6 * m->nbody * sizeof(double));
    memcpy(dst->xfrc_body, src->xfrc_body, (size_t)6 * m->nbody * sizeof(double));
    dst->control = src->control;
    dst->control_user = src->control_user;
    dst->user_switch = src->user_switch;
    dst->user_transition = src->user_transition;
    dst->switch_user = src->switch_user;
    dst->opt = src->opt;
}

cd_status cd_state_copy(const cd_model *m, cd_data *dst, cd_data *src, cd_error *err)
{
    /* one temporary buffer from dst's allocator (documented: this call allocates) */
    size_t n = cd_state_size(m);
    double *tmp = dst->allocator.alloc(n * sizeof(double), dst->allocator.ctx);
    cd_status st;
    if (!tmp) { cd_error_set(err, CD_ENOMEM, "cd_state_copy: out of memory"); return CD_ENOMEM; }
    cd_state_get(m, src, tmp);
    st = cd_state_set(m, dst, tmp, err);
    dst->allocator.free(tmp, dst->allocator.ctx);
    return st;
}
