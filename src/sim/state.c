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

/* Every array of the state after t, in layout order: (kind, field, count);
 * kind i is an int array (stored exactly as doubles), d a double array. One
 * list serves the size, the save, the restore and the evaluation copy. */
#define STATE_ARRAYS(X)                  \
    X(d, y, m->ny)                       \
    X(i, slot_mode, m->nslot)            \
    X(d, slot_dir, 3 * m->nslot)         \
    X(d, sw_tswitch, m->nsw)             \
    X(i, sw_nswitch, m->nsw)             \
    X(i, sw_held, m->nsw)                \
    X(i, lim_mode, m->nlim)              \
    X(i, fric_mode, m->nfric)            \
    X(d, fric_dir, m->nfric)             \
    X(i, user_mode, m->nuser)            \
    X(i, act_piece, m->nu)               \
    X(i, finger_mode, m->nfinger)        \
    X(d, finger_brake, m->nfinger)       \
    X(d, finger_t0, m->nfinger)          \
    X(d, ctrl, m->nu)                    \
    X(d, qfrc_applied, m->nv)            \
    X(d, xfrc_applied, 6 * m->nbody)     \
    X(d, xfrc_body, 6 * m->nbody)

static size_t body_size(const cd_model *m)
{
#define COUNT(kind, field, n) +(size_t)(n)
    return (size_t)1 /* t */ STATE_ARRAYS(COUNT);
#undef COUNT
}

size_t cd_state_size(const cd_model *m)
{
    return HEADER + body_size(m) + (size_t)cd_integ_state_size(m);
}

static void put_i(double **p, const int *a, int n)
{
    int i;
    for (i = 0; i < n; i++) (*p)[i] = a[i];
    *p += n;
}
static void get_i(const double **p, int *a, int n)
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
#define PUT(kind, field, n) put_##kind(&p, d->field, n);
    STATE_ARRAYS(PUT)
#undef PUT
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
#define GET(kind, field, n) get_##kind(&p, d->field, n);
    STATE_ARRAYS(GET)
#undef GET
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
#define COPY(kind, field, n) memcpy(dst->field, src->field, (size_t)(n) * sizeof *dst->field);
    STATE_ARRAYS(COPY)
#undef COPY
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
