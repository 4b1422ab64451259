/* The complete state of a cd_data (data.h): save, restore, copy.
 *
 * Layout (doubles): a header [magic, ny, nslot, nsw, nu, total size], then
 * t, y, every discrete part, the inputs, and the integrator's part
 * (cd_integ_state_*). Integers are stored exactly as doubles. */
#include "capdyn/sim.h"
#include "integ.h"
#include "../contact/contact.h"

#include <limits.h>
#include <stdio.h>
#include <math.h>
#include <string.h>

#define STATE_MAGIC 4.2e7 /* "capdyn state", version 1 */
#define HEADER 6

/* Every array of the state after t, in layout order: (kind, field, count,
 * lo, hi, what); kind i is an int array (stored exactly as doubles, each a
 * whole number in [lo, hi]; hi = -1: act_piece, at most the actuator's
 * schedule rows), d a double array (finite; sw_tswitch may also be -inf,
 * its value before any switch, finger_t0 +inf, a finger held open). One list serves the size, the check, the
 * save, the restore and the evaluation copy. */
#define STATE_ARRAYS(X)                                                                           \
    X(d, y, m->ny, 0, 0, "a state value")                                                         \
    X(i, slot_mode, m->nslot, CD_MODE_OPEN, CD_MODE_SLIP, "a slot mode (0 open, 1 stick, 2 slip)") \
    X(d, slot_dir, 3 * m->nslot, 0, 0, "a slip direction")                                        \
    X(d, sw_tswitch, m->nsw, 0, 0, "a switch time")                                               \
    X(i, sw_nswitch, m->nsw, 0, INT_MAX, "a switch count (>= 0)")                                 \
    X(i, sw_held, m->nsw, 0, 1, "a guard flag (0 or 1)")                                          \
    X(i, lim_mode, m->nlim, CD_LIM_FREE, CD_LIM_UPPER, "a stop mode (0 free, 1 lower, 2 upper)")  \
    X(i, fric_mode, m->nfric, CD_MODE_STICK, CD_MODE_SLIP, "a joint friction mode (1 stick, 2 slip)") \
    X(d, fric_dir, m->nfric, 0, 0, "a friction direction")                                        \
    X(i, user_mode, m->nuser, INT_MIN, INT_MAX, "a user switch mode (an int)")                    \
    X(i, act_piece, m->nu, 0, -1, "a schedule row of the actuator")                               \
    X(i, finger_mode, m->nfinger, CD_CLUTCH_ENGAGED, CD_CLUTCH_RELEASED, "a clutch mode (0 engaged, 1 released)") \
    X(d, finger_brake, m->nfinger, 0, 0, "a brake angle")                                         \
    X(d, finger_t0, m->nfinger, 0, 0, "a schedule origin")                                        \
    X(d, ctrl, m->nu, 0, 0, "an actuator input")                                                  \
    X(d, qfrc_applied, m->nv, 0, 0, "an applied generalized force")                               \
    X(d, xfrc_applied, 6 * m->nbody, 0, 0, "an applied wrench")                                   \
    X(d, xfrc_body, 6 * m->nbody, 0, 0, "an applied body-frame wrench")

/* a saved unit quaternion is unit to rounding (the integrator renormalises
 * after every step); this much off means the buffer was not made by
 * cd_state_get */
#define QUAT_TOL 1e-6

size_t cd_state_body_size(const cd_model *m)
{
#define COUNT(kind, field, n, lo, hi, what) +(size_t)(n)
    return (size_t)1 /* t */ STATE_ARRAYS(COUNT);
#undef COUNT
}

size_t cd_state_size(const cd_model *m)
{
    if (!m) return 0;
    return HEADER + cd_state_body_size(m) + (size_t)cd_integ_state_size(m);
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

static const char *nonfinite(double v) { return isnan(v) ? "NaN" : v > 0 ? "+inf" : "-inf"; }

/* The checks of one array (STATE_ARRAYS): 0, or -1 with why. */
static int check_d(const cd_model *m, const double **p, const char *field, int n, long lo, long hi, const char *what,
                   char *why, size_t len)
{
    int k;
    (void)m; (void)lo; (void)hi;
    for (k = 0; k < n; k++) {
        double v = (*p)[k];
        if (isfinite(v) || (v == -HUGE_VAL && !strcmp(field, "sw_tswitch")) ||
            (v == HUGE_VAL && !strcmp(field, "finger_t0")))
            continue;
        snprintf(why, len, "%s[%d] is %s (%s must be finite)", field, k, nonfinite(v), what);
        return -1;
    }
    *p += n;
    return 0;
}
static int check_i(const cd_model *m, const double **p, const char *field, int n, long lo, long hi, const char *what,
                   char *why, size_t len)
{
    int k;
    for (k = 0; k < n; k++) {
        double v = (*p)[k];
        long top = hi >= 0 ? hi : (long)m->act_tbl_n[k]; /* act_piece: rows 0 .. n of its schedule */
        if (isfinite(v) && v == floor(v) && v >= (double)lo && v <= (double)top) continue;
        if (hi >= 0)
            snprintf(why, len, "%s[%d] = %.17g is not %s", field, k, v, what);
        else
            snprintf(why, len, "%s[%d] = %.17g is not %s (0 .. %ld)", field, k, v, what, top);
        return -1;
    }
    *p += n;
    return 0;
}

/* Every value of buf (after the header) valid for model m: 0, or -1 with why. */
static int check_state(const cd_model *m, const double *buf, char *why, size_t len)
{
    const double *p = buf + HEADER, *y = buf + HEADER + 1;
    int s;
    if (!isfinite(*p)) {
        snprintf(why, len, "the time t is %s (must be finite)", nonfinite(*p));
        return -1;
    }
    p++;
#define CHECK(kind, field, n, lo, hi, what) \
    if (check_##kind(m, &p, #field, n, lo, hi, what, why, len) < 0) return -1;
    STATE_ARRAYS(CHECK)
#undef CHECK
    for (s = 0; s < m->nsys; s++) {
        /* system s's quaternion in the buffer's y (a view with its layout) */
        cd_data view;
        const double *qt;
        double nq;
        view.y = (double *)(size_t)y;
        qt = cd_state_of(m, &view, s).quat;
        if (!qt) continue; /* a fixed base */
        nq = sqrt(qt[0] * qt[0] + qt[1] * qt[1] + qt[2] * qt[2] + qt[3] * qt[3]);
        if (!(fabs(nq - 1.0) <= QUAT_TOL)) {
            snprintf(why, len, "system %d's base quaternion (y[%d..%d]) has norm %.17g (a unit quaternion, within %g, "
                     "is expected)", s, (int)(qt - y), (int)(qt - y) + 3, nq, QUAT_TOL);
            return -1;
        }
    }
    return cd_integ_state_check(m, p, why, len);
}

void cd_state_get(const cd_model *m, cd_data *d, double *buf)
{
    double *p;
    if (!m || !d || !buf) return;
    p = buf + HEADER;
    buf[0] = STATE_MAGIC; buf[1] = m->ny; buf[2] = m->nslot; buf[3] = m->nsw; buf[4] = m->nu;
    buf[5] = (double)cd_state_size(m);
    *p++ = d->t;
#define PUT(kind, field, n, lo, hi, what) put_##kind(&p, d->field, n);
    STATE_ARRAYS(PUT)
#undef PUT
    cd_integ_state_get(m, d, p);
}

/* t and the arrays (not the integrator's part) from p into d; returns the
 * position after them. */
static const double *set_body(const cd_model *m, cd_data *d, const double *p)
{
    d->t = *p++;
#define GET(kind, field, n, lo, hi, what) get_##kind(&p, d->field, n);
    STATE_ARRAYS(GET)
#undef GET
    return p;
}

cd_status cd_state_set(const cd_model *m, cd_data *d, const double *buf, cd_error *err)
{
    const double *p;
    char why[400];
    double *undo;
    if (!m || !d || !buf) {
        cd_error_set(err, CD_EINVAL, "cd_state_set: %s is NULL", !m ? "the model" : !d ? "the data" : "the buffer");
        return CD_EINVAL;
    }
    if (buf[0] != STATE_MAGIC || buf[1] != m->ny || buf[2] != m->nslot || buf[3] != m->nsw ||
        buf[4] != m->nu || buf[5] != (double)cd_state_size(m)) {
        cd_error_set(err, CD_EINVAL, "cd_state_set: the buffer is not a state of this model (magic or sizes differ)");
        return CD_EINVAL;
    }
    /* every field and value first: nothing changes unless all are valid */
    if (check_state(m, buf, why, sizeof why) < 0) {
        cd_error_set(err, CD_EINVAL, "cd_state_set: %s; nothing was changed", why);
        return CD_EINVAL;
    }
    /* the evaluation of the new state must succeed too: the old t and
     * arrays are kept in the data's undo area meanwhile (no allocation),
     * and the integrator's part is set only after it succeeded */
    undo = d->state_undo;
    {
        double *q = undo;
        *q++ = d->t;
#define PUT(kind, field, n, lo, hi, what) put_##kind(&q, d->field, n);
        STATE_ARRAYS(PUT)
#undef PUT
    }
    p = set_body(m, d, buf + HEADER);
    /* the broad phase's caches start afresh, as in a fresh data */
    cd_contact_cache_clear(m, d);
    if (cd_forward(m, d) != CD_OK) {
        double t = d->t;
        (void)set_body(m, d, undo);
        (void)cd_forward(m, d); /* the outputs of the kept state again */
        cd_error_set(err, CD_ENUMERIC, "cd_state_set: the state cannot be evaluated at t = %.9g s (non-finite "
                     "derivative or singular mass matrix); nothing was changed", t);
        return CD_ENUMERIC;
    }
    cd_integ_state_set(m, d, p);
    return CD_OK;
}

/* dst takes src's t, y, modes, anchors, guard counters, schedule rows,
 * inputs and callbacks, not the integrator's part: what an evaluation of
 * dst needs to give src's outputs (the sampler's scratch data). No allocation. */
void cd_state_copy_eval(const cd_model *m, cd_data *dst, const cd_data *src)
{
    dst->t = src->t;
#define COPY(kind, field, n, lo, hi, what) memcpy(dst->field, src->field, (size_t)(n) * sizeof *dst->field);
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
    size_t n;
    double *tmp;
    cd_status st;
    if (!m || !dst || !src) {
        cd_error_set(err, CD_EINVAL, "cd_state_copy: %s is NULL", !m ? "the model" : !dst ? "dst" : "src");
        return CD_EINVAL;
    }
    n = cd_state_size(m);
    tmp = dst->allocator.alloc(n * sizeof(double), dst->allocator.ctx);
    if (!tmp) { cd_error_set(err, CD_ENOMEM, "cd_state_copy: out of memory"); return CD_ENOMEM; }
    cd_state_get(m, src, tmp);
    st = cd_state_set(m, dst, tmp, err);
    dst->allocator.free(tmp, dst->allocator.ctx);
    return st;
}
