/* Dense output (include/capdyn/sim.h, docs/dynamics.md "Dense output").
 *
 * Between two calls the sampler holds the start of the current step: its
 * time, state and derivative, and a scratch cd_data with the step's modes,
 * anchors and inputs (copied from the run's data at that start). A sample
 * at t in (t_a, t_b] is the cubic Hermite interpolant
 *   y(s) = h00 y_a + h10 h f_a + h01 y_b + h11 h f_b,  s = (t - t_a) / h,
 * with f_a the derivative the run's data held at t_a (after any event
 * there: the new modes' side) and f_b the scratch data's evaluation at
 * (t_b, y_b) with the step's modes (before any event at t_b: the step's own
 * side), so both end slopes belong to the smooth solution of the step.
 * A sample that falls exactly on the step's end is the run's own data there
 * (after an event at that instant: the new side, as a run stopped at that
 * time would show). */
#include "capdyn/sim.h"
#include "integ.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct cd_sampler {
    cd_data *scratch;
    double *ya, *fa, *yb, *fb; /* (ny) */
    double ta, t_first, dt;
    long k;                    /* index of the next sample */
    int ny, started;
};

cd_sampler *cd_sampler_create(const cd_model *m, cd_error *err)
{
    if (!m) {
        cd_error_set(err, CD_EINVAL, "cd_sampler_create: the model is NULL");
        return NULL;
    }
    cd_sampler *s = (cd_sampler *)calloc(1, sizeof *s);
    size_t n = (size_t)(m->ny ? m->ny : 1);
    if (!s) { cd_error_set(err, CD_ENOMEM, "sampler: out of memory"); return NULL; }
    s->scratch = cd_data_create(m, 256, err);
    s->ya = (double *)malloc(4 * n * sizeof(double));
    if (!s->scratch || !s->ya) {
        if (s->scratch && !s->ya) cd_error_set(err, CD_ENOMEM, "sampler: out of memory");
        cd_sampler_free(s);
        return NULL;
    }
    s->fa = s->ya + n;
    s->yb = s->fa + n;
    s->fb = s->yb + n;
    s->ny = m->ny;
    return s;
}

void cd_sampler_free(cd_sampler *s)
{
    if (!s) return;
    cd_data_free(s->scratch);
    free(s->ya);
    free(s);
}

/* The scratch's event log mirrors the run's: a sample taken on the scratch
 * carries the run's event count and its latest events, so a writer that
 * appends "the events logged since the last sample" sees one log whichever
 * data a sample comes from (a scratch log left at 0 read as a reset and
 * made the next sample at a step's end write every event again). Copies only
 * the events logged since the last call, the newest ev_cap of them. */
static void sync_events(cd_sampler *s, const cd_data *d)
{
    cd_data *x = s->scratch;
    long g, from = x->ev_count, oldest = d->ev_count > d->ev_cap ? d->ev_count - d->ev_cap : 0;
    if (d->ev_count < from) from = 0; /* the run was reset */
    if (from < oldest) from = oldest;
    if (d->ev_count - from > x->ev_cap) from = d->ev_count - x->ev_cap;
    for (g = from; g < d->ev_count; g++) x->ev[g % x->ev_cap] = d->ev[g % d->ev_cap];
    x->ev_count = d->ev_count;
}

static void take_start(cd_sampler *s, const cd_model *m, const cd_data *d)
{
    cd_state_copy_eval(m, s->scratch, d);
    sync_events(s, d);
    memcpy(s->ya, d->y, (size_t)s->ny * sizeof(double));
    memcpy(s->fa, d->ydot, (size_t)s->ny * sizeof(double));
    s->ta = d->t;
}

static double t_of(const cd_sampler *s, long k) { return s->t_first + (double)k * s->dt; }

cd_status cd_sampler_begin(cd_sampler *s, const cd_model *m, const cd_data *d, double t_first, double dt,
                           cd_error *err)
{
    if (!s || !m || !d) {
        cd_error_set(err, CD_EINVAL, "cd_sampler_begin: %s is NULL", !s ? "the sampler" : !m ? "the model" : "the data");
        return CD_EINVAL;
    }
    if (!(dt > 0) || !isfinite(dt) || !isfinite(t_first) || !isfinite(d->t)) {
        cd_error_set(err, CD_EINVAL, "sampler: expected a finite first time and dt > 0, got %g and %g", t_first, dt);
        return CD_EINVAL;
    }
    s->t_first = t_first;
    s->dt = dt;
    s->k = 0;
    while (t_of(s, s->k) <= d->t) s->k++;
    take_start(s, m, d);
    s->started = 1;
    return CD_OK;
}

double cd_sampler_next(const cd_sampler *s) { return s ? t_of(s, s->k) : NAN; }

int cd_sampler_update(cd_sampler *s, const cd_model *m, const cd_data *d, cd_sample_fn fn, void *user)
{
    if (!s || !m || !d) return -1;
    cd_data *x = s->scratch;
    double tb = d->t, h = tb - s->ta;
    int i, r = 0;
    if (!s->started) return -1;
    if (h > 0 && t_of(s, s->k) <= tb) {
        /* the step's end slope, with the step's modes */
        memcpy(s->yb, d->y, (size_t)s->ny * sizeof(double));
        memcpy(x->y, s->yb, (size_t)s->ny * sizeof(double));
        x->t = tb;
        if (cd_forward(m, x) != CD_OK) return -1;
        memcpy(s->fb, x->ydot, (size_t)s->ny * sizeof(double));
        while (t_of(s, s->k) <= tb) {
            double t = t_of(s, s->k), u = (t - s->ta) / h, u2 = u * u, u3 = u2 * u;
            if (t == tb) { /* at the step's end: the run's own state (after an event there, its new side) */
                s->k++;
                if (fn) r = fn(m, d, user);
                break;
            }
            double h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2, h11 = u3 - u2;
            for (i = 0; i < s->ny; i++)
                x->y[i] = h00 * s->ya[i] + h10 * h * s->fa[i] + h01 * s->yb[i] + h11 * h * s->fb[i];
            x->t = t;
            if (cd_forward(m, x) != CD_OK) return -1;
            /* the sample carries the run's statistics (steps, evaluations,
             * events so far, the last step): those at the end of the step
             * that contains it; the scratch's own counts mean nothing */
            x->stats = d->stats;
            s->k++;
            if (fn && (r = fn(m, x, user)) != 0) break;
        }
    }
    take_start(s, m, d);
    return r;
}
