/* rk8pd: capdyn's explicit Prince-Dormand 8(7) stepper.
 *
 * The method: RK8(7)13M of P. J. Prince and J. R. Dormand, "High order
 * embedded Runge-Kutta formulae", J. Comput. Appl. Math. 7 (1981) 67-75:
 * 13 stages, the 8th-order solution is propagated, the 7th-order one gives
 * the error estimate yerr = h sum (b7_i - b8_i) k_i, order() = 8 for GSL's
 * standard control. The same tableau as GSL's gsl_odeiv2_step_rk8pd, which
 * capdyn used until now; the stage sums are formed term by term in the
 * order of the tableau's columns, so a step gives GSL's result bit for bit
 * (tested: tests/test_rk8.c).
 *
 * Why capdyn's own: the work of a step that is not an evaluation (13 stage
 * sums, the error estimate, copies) is proportional to the number of
 * unknowns, and in the capture scenes 1296 of their 1350 unknowns are the
 * stick anchors of contact slots that are open: GSL's stepper spent 15 % of
 * a capture run on them. An open slot's anchor has derivative exactly 0
 * (contact.c writes 0 for it at every evaluation, and a mode changes only
 * at an event, between steps), so every stage leaves it where it is and its
 * error estimate is 0: this stepper skips those unknowns. It advances the
 * runs of unknowns that can move (the bodies' and joints' positions and
 * velocities, the anchors of the closed slots, the joint-friction anchors),
 * copies the others once per step into the stage argument, and writes 0
 * into their error estimate. Nothing is allocated in a step. */
#include "rk8.h"

#include <gsl/gsl_errno.h>
#include <stdlib.h>
#include <string.h>

#define NST 13

/* nodes c_i, and the coefficient matrix a_ij (rows 1..12; zeros listed) */
static const double RK8_C[NST] = {0.0, 1.0 / 18.0, 1.0 / 12.0, 1.0 / 8.0, 5.0 / 16.0, 3.0 / 8.0, 59.0 / 400.0,
                                  93.0 / 200.0, 5490023248.0 / 9719169821.0, 13.0 / 20.0,
                                  1201146811.0 / 1299019798.0, 1.0, 1.0};
static const double RK8_A[NST][NST - 1] = {
    {0},
    {1.0 / 18.0},
    {1.0 / 48.0, 1.0 / 16.0},
    {1.0 / 32.0, 0.0, 3.0 / 32.0},
    {5.0 / 16.0, 0.0, -75.0 / 64.0, 75.0 / 64.0},
    {3.0 / 80.0, 0.0, 0.0, 3.0 / 16.0, 3.0 / 20.0},
    {29443841.0 / 614563906.0, 0.0, 0.0, 77736538.0 / 692538347.0, -28693883.0 / 1125000000.0,
     23124283.0 / 1800000000.0},
    {16016141.0 / 946692911.0, 0.0, 0.0, 61564180.0 / 158732637.0, 22789713.0 / 633445777.0,
     545815736.0 / 2771057229.0, -180193667.0 / 1043307555.0},
    {39632708.0 / 573591083.0, 0.0, 0.0, -433636366.0 / 683701615.0, -421739975.0 / 2616292301.0,
     100302831.0 / 723423059.0, 790204164.0 / 839813087.0, 800635310.0 / 3783071287.0},
    {246121993.0 / 1340847787.0, 0.0, 0.0, -37695042795.0 / 15268766246.0, -309121744.0 / 1061227803.0,
     -12992083.0 / 490766935.0, 6005943493.0 / 2108947869.0, 393006217.0 / 1396673457.0,
     123872331.0 / 1001029789.0},
    {-1028468189.0 / 846180014.0, 0.0, 0.0, 8478235783.0 / 508512852.0, 1311729495.0 / 1432422823.0,
     -10304129995.0 / 1701304382.0, -48777925059.0 / 3047939560.0, 15336726248.0 / 1032824649.0,
     -45442868181.0 / 3398467696.0, 3065993473.0 / 597172653.0},
    {185892177.0 / 718116043.0, 0.0, 0.0, -3185094517.0 / 667107341.0, -477755414.0 / 1098053517.0,
     -703635378.0 / 230739211.0, 5731566787.0 / 1027545527.0, 5232866602.0 / 850066563.0,
     -4093664535.0 / 808688257.0, 3962137247.0 / 1805957418.0, 65686358.0 / 487910083.0},
    {403863854.0 / 491063109.0, 0.0, 0.0, -5068492393.0 / 434740067.0, -411421997.0 / 543043805.0,
     652783627.0 / 914296604.0, 11173962825.0 / 925320556.0, -13158990841.0 / 6184727034.0,
     3936647629.0 / 1978049680.0, -160528059.0 / 685178525.0, 248638103.0 / 1413531060.0, 0.0}};
/* weights of the 8th-order solution and of the 7th-order one */
static const double RK8_B8[NST] = {14005451.0 / 335480064.0, 0.0, 0.0, 0.0, 0.0, -59238493.0 / 1068277825.0,
                                   181606767.0 / 758867731.0, 561292985.0 / 797845732.0,
                                   -1041891430.0 / 1371343529.0, 760417239.0 / 1151165299.0,
                                   118820643.0 / 751138087.0, -528747749.0 / 2220607170.0, 1.0 / 4.0};
static const double RK8_B7[NST] = {13451932.0 / 455176623.0, 0.0, 0.0, 0.0, 0.0, -808719846.0 / 976000145.0,
                                   1757004468.0 / 5645159321.0, 656045339.0 / 265891186.0,
                                   -3867574721.0 / 1518517206.0, 465885868.0 / 322736535.0,
                                   53011238.0 / 667516719.0, 2.0 / 45.0, 0.0};

typedef struct {
    size_t dim;
    double *k[NST], *y0, *ytmp;
    int *lo, *hi, nrun;       /* the runs of the next step (capacity dim + 2 each) */
    const cd_model *const *mp; /* where the bound model is, and the data (NULL: every unknown) */
    const cd_data *d;
} rk8_state;

static void rk8_free(void *vs)
{
    rk8_state *s = (rk8_state *)vs;
    if (!s) return;
    free(s->k[0]);
    free(s->lo);
    free(s);
}

static void *rk8_alloc(size_t dim)
{
    rk8_state *s = (rk8_state *)calloc(1, sizeof *s);
    size_t n = dim ? dim : 1, i;
    if (!s) GSL_ERROR_NULL("failed to allocate the rk8pd state", GSL_ENOMEM);
    s->dim = dim;
    s->k[0] = (double *)malloc((NST + 2) * n * sizeof(double));
    s->lo = (int *)malloc(2 * (n + 2) * sizeof(int));
    if (!s->k[0] || !s->lo) {
        rk8_free(s);
        GSL_ERROR_NULL("failed to allocate the rk8pd buffers", GSL_ENOMEM);
    }
    for (i = 1; i < NST; i++) s->k[i] = s->k[0] + i * n;
    s->y0 = s->k[0] + NST * n;
    s->ytmp = s->y0 + n;
    s->hi = s->lo + n + 2;
    return s;
}

static void add_run(int *lo, int *hi, int *nrun, int a, int b)
{
    if (b <= a) return;
    if (*nrun > 0 && hi[*nrun - 1] == a) { hi[*nrun - 1] = b; return; }
    lo[*nrun] = a;
    hi[*nrun] = b;
    (*nrun)++;
}

int cd_moving_runs(const cd_model *m, const cd_data *d, int ny, int *lo, int *hi)
{
    int k, nrun = 0;
    if (!m || !d || m->ny != ny) {
        add_run(lo, hi, &nrun, 0, ny);
        return nrun;
    }
    add_run(lo, hi, &nrun, 0, m->ny_slot_adr);
    for (k = 0; k < m->nslot; k++)
        if (d->slot_mode[k] != CD_MODE_OPEN) add_run(lo, hi, &nrun, m->ny_slot_adr + 3 * k, m->ny_slot_adr + 3 * k + 3);
    add_run(lo, hi, &nrun, m->ny_fric_adr, m->ny);
    return nrun;
}

/* the unknowns that can move at the current modes (header) */
static void runs(rk8_state *s)
{
    s->nrun = cd_moving_runs(s->mp ? *s->mp : NULL, s->d, (int)s->dim, s->lo, s->hi);
}

static int rk8_apply(void *vs, size_t dim, double t, double h, double y[], double yerr[], const double dydt_in[],
                     double dydt_out[], const gsl_odeiv2_system *sys)
{
    rk8_state *s = (rk8_state *)vs;
    double *const *k = s->k, *ytmp = s->ytmp, *y0 = s->y0;
    int r, i, j, l, st;
    if (dim != s->dim) return GSL_EINVAL;
    runs(s);
    for (r = 0; r < s->nrun; r++)
        for (i = s->lo[r]; i < s->hi[r]; i++) y0[i] = y[i];
    if (dydt_in) {
        for (r = 0; r < s->nrun; r++)
            for (i = s->lo[r]; i < s->hi[r]; i++) k[0][i] = dydt_in[i];
    } else if ((st = GSL_ODEIV_FN_EVAL(sys, t, y, k[0])) != GSL_SUCCESS) {
        return st;
    }
    /* the frozen unknowns keep y in every stage argument */
    memcpy(ytmp, y, dim * sizeof(double));
    for (j = 1; j < NST; j++) {
        const double *a = RK8_A[j];
        if (j == 1) {
            const double ah = a[0] * h;
            for (r = 0; r < s->nrun; r++)
                for (i = s->lo[r]; i < s->hi[r]; i++) ytmp[i] = y[i] + ah * k[0][i];
        } else {
            for (r = 0; r < s->nrun; r++)
                for (i = s->lo[r]; i < s->hi[r]; i++) {
                    double sum = a[0] * k[0][i];
                    for (l = 1; l < j; l++)
                        if (a[l] != 0.0) sum += a[l] * k[l][i];
                    ytmp[i] = y[i] + h * sum;
                }
        }
        if ((st = GSL_ODEIV_FN_EVAL(sys, t + RK8_C[j] * h, ytmp, k[j])) != GSL_SUCCESS) return st;
    }
    for (r = 0; r < s->nrun; r++)
        for (i = s->lo[r]; i < s->hi[r]; i++) {
            double sum = RK8_B8[0] * k[0][i];
            for (l = 5; l < NST; l++) sum += RK8_B8[l] * k[l][i];
            y[i] += h * sum;
        }
    if (dydt_out && (st = GSL_ODEIV_FN_EVAL(sys, t + h, y, dydt_out)) != GSL_SUCCESS) {
        for (r = 0; r < s->nrun; r++)
            for (i = s->lo[r]; i < s->hi[r]; i++) y[i] = y0[i];
        return st;
    }
    memset(yerr, 0, dim * sizeof(double));
    for (r = 0; r < s->nrun; r++)
        for (i = s->lo[r]; i < s->hi[r]; i++) {
            double s8 = RK8_B8[0] * k[0][i], s7 = RK8_B7[0] * k[0][i];
            for (l = 5; l < NST; l++) s8 += RK8_B8[l] * k[l][i];
            for (l = 5; l < NST - 1; l++) s7 += RK8_B7[l] * k[l][i];
            yerr[i] = h * (s7 - s8);
        }
    return GSL_SUCCESS;
}

static int rk8_set_driver(void *vs, const gsl_odeiv2_driver *d)
{
    (void)vs;
    (void)d;
    return GSL_SUCCESS;
}

/* nothing is carried from one step to the next */
static int rk8_reset(void *vs, size_t dim)
{
    (void)vs;
    (void)dim;
    return GSL_SUCCESS;
}

static unsigned int rk8_order(void *vs)
{
    (void)vs;
    return 8u;
}

static const gsl_odeiv2_step_type rk8_type = {"rk8pd", 1, 1, rk8_alloc, rk8_apply, rk8_set_driver,
                                              rk8_reset, rk8_order, rk8_free};
const gsl_odeiv2_step_type *cd_step_rk8pd = &rk8_type;

void cd_rk8_bind(gsl_odeiv2_step *s, const cd_model *const *mp, const cd_data *d)
{
    rk8_state *st = (rk8_state *)s->state;
    st->mp = mp;
    st->d = d;
}

int cd_rk8_runs(gsl_odeiv2_step *s, const int **lo, const int **hi)
{
    rk8_state *st = (rk8_state *)s->state;
    runs(st);
    *lo = st->lo;
    *hi = st->hi;
    return st->nrun;
}
