/* cd_state_set (src/sim/state.c; issue 24): every discrete field and every
 * value of a state buffer is checked before anything changes; a refused
 * state (bad field, non-finite value, or one that cannot be evaluated)
 * leaves the data exactly as it was, and the message names the field. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <capdyn/io.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "proc_util.h"

static cd_scenario *load(const char *name, const char *const *ovr, int novr)
{
    char p[512];
    cd_error e;
    cd_scenario *sc;
    scen(p, sizeof p, name);
    sc = cd_scenario_load(p, ovr, novr, &e);
    cr_assert_not_null(sc, "%s: %s", name, e.msg);
    return sc;
}

/* The position in a state buffer of element k of an int or double field:
 * found by changing that element in the data and comparing the saves. */
static long offset_of(const cd_model *m, cd_data *d, void *elem, int is_int)
{
    size_t n = cd_state_size(m), i;
    double *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b);
    long at = -1;
    int iv = 0;
    double dv = 0;
    cd_state_get(m, d, a);
    if (is_int) {
        iv = *(int *)elem;
        *(int *)elem = iv + 12345;
    } else {
        dv = *(double *)elem;
        *(double *)elem = dv == 12345.5 ? 54321.5 : 12345.5; /* also when dv is -inf */
    }
    cd_state_get(m, d, b);
    if (is_int) *(int *)elem = iv;
    else *(double *)elem = dv;
    for (i = 0; i < n; i++)
        if (memcmp(a + i, b + i, sizeof(double)) != 0) {
            cr_assert_eq(at, -1, "one element changed");
            at = (long)i;
        }
    cr_assert_geq(at, 0, "the element is in the state");
    free(a);
    free(b);
    return at;
}

/* Sets buf[at] to bad, asks cd_state_set, and checks: CD_EINVAL (or want),
 * the message names `name`, and the data's own save is unchanged bit for
 * bit (nothing changed). */
static void expect_refused(const cd_model *m, cd_data *d, const double *good, long at, double bad, cd_status want,
                           const char *name)
{
    size_t n = cd_state_size(m);
    double *buf = malloc(n * sizeof *buf), *before = malloc(n * sizeof *before), *after = malloc(n * sizeof *after);
    cd_error e;
    cd_status st;
    memcpy(buf, good, n * sizeof *buf);
    buf[at] = bad;
    cd_state_get(m, d, before);
    st = cd_state_set(m, d, buf, &e);
    cd_state_get(m, d, after);
    cr_expect_eq(st, want, "%s = %g: status %d (%s)", name, bad, st, e.msg);
    cr_expect(strstr(e.msg, name) != NULL, "the message names %s: %s", name, e.msg);
    cr_expect(strstr(e.msg, "nothing was changed") != NULL, "the message says nothing changed: %s", e.msg);
    cr_expect_eq(memcmp(before, after, n * sizeof *before), 0, "%s = %g: the data changed", name, bad);
    free(buf);
    free(before);
    free(after);
}

/* Every field present in the model: a bad value of its first element is
 * refused. Returns a bit mask of the fields tried. */
static unsigned try_fields(const cd_model *m, cd_data *d)
{
    size_t n = cd_state_size(m);
    double *good = malloc(n * sizeof *good), *other = malloc(n * sizeof *other);
    unsigned tried = 0;
    cd_error e;
    long at;
    /* a second, different state to restore into d: the refusals must keep
     * d's own state, not good's */
    cd_state_get(m, d, good);
    cr_assert_eq(cd_sim_advance(m, d, 0.002, NULL, NULL, &e), CD_OK, "%s", e.msg);
    cd_state_get(m, d, other);
    (void)other;
#define TRY_I(bit, field, cnt, bad)                                               \
    if ((cnt) > 0) {                                                              \
        at = offset_of(m, d, &d->field[0], 1);                                    \
        expect_refused(m, d, good, at, bad, CD_EINVAL, #field "[0]");             \
        tried |= 1u << (bit);                                                     \
    }
#define TRY_D(bit, field, cnt, bad)                                               \
    if ((cnt) > 0) {                                                              \
        at = offset_of(m, d, &d->field[0], 0);                                    \
        expect_refused(m, d, good, at, bad, CD_EINVAL, #field "[0]");             \
        tried |= 1u << (bit);                                                     \
    }
    TRY_D(0, y, m->ny, NAN)
    TRY_I(1, slot_mode, m->nslot, 3)
    TRY_D(2, slot_dir, m->nslot, INFINITY)
    TRY_D(3, sw_tswitch, m->nsw, NAN)
    TRY_I(4, sw_nswitch, m->nsw, -1)
    TRY_I(5, sw_held, m->nsw, 2)
    TRY_I(6, lim_mode, m->nlim, 3)
    TRY_I(7, fric_mode, m->nfric, 0)
    TRY_D(8, fric_dir, m->nfric, -INFINITY)
    TRY_I(9, user_mode, m->nuser, 0.5)
    TRY_I(10, act_piece, m->nu, 1e6)
    TRY_I(11, finger_mode, m->nfinger, 2)
    TRY_D(12, finger_brake, m->nfinger, NAN)
    TRY_D(13, finger_t0, m->nfinger, NAN)
    TRY_D(14, ctrl, m->nu, NAN)
    TRY_D(15, qfrc_applied, m->nv, NAN)
    TRY_D(16, xfrc_applied, m->nbody, NAN)
    TRY_D(17, xfrc_body, m->nbody, INFINITY)
#undef TRY_I
#undef TRY_D
    free(good);
    free(other);
    return tried;
}

Test(state, every_bad_field_is_refused_by_name_and_nothing_changes, .timeout = 120)
{
    /* Three models that together have every kind of field: the Space
     * Gripper at a handrail (slots, finger clutches, joint stops), a
     * controlled capture (user switches), the free-floating arm with table
     * schedules and Coulomb joint friction added by an override. For each
     * field present, its first element is set to a value outside its
     * domain (a mode 3, a NaN, a count -1, a flag 2, a schedule row 1e6,
     * a user mode 0.5): cd_state_set returns CD_EINVAL naming the field,
     * and a save of the data afterwards is bit-identical to one before. */
    static const char *const fric[] = {"system[0].link[0].friction = { torque = 0.5, stiffness = 1e4, damping = 10 }"};
    struct { const char *name; const char *const *ovr; int novr; } s[3] = {
        {"space_gripper_handrail.toml", NULL, 0}, {"capture_detumble.toml", NULL, 0}, {"free_floating_arm.toml", fric, 1}};
    unsigned all = 0;
    int i;
    for (i = 0; i < 3; i++) {
        cd_scenario *sc = load(s[i].name, s[i].ovr, s[i].novr);
        cd_error e;
        cd_data *d = cd_data_create(sc->model, 0, &e);
        cd_ctrl *c = NULL;
        cr_assert_not_null(d, "%s", e.msg);
        if (sc->control) {
            c = cd_ctrl_create(sc->model, sc->control, &e);
            cr_assert_not_null(c, "%s", e.msg);
            cd_ctrl_install(c, d);
        }
        all |= try_fields(sc->model, d);
        cd_ctrl_free(c);
        cd_data_free(d);
        cd_scenario_free(sc);
    }
    cr_expect_eq(all, (1u << 18) - 1, "every field kind tried (mask %#x)", all);
}

Test(state, a_nan_state_or_a_non_unit_quaternion_is_refused_and_y_keeps_its_values)
{
    /* The free-floating arm: a NaN in y (the case returned
     * CD_ENUMERIC and left the NaN in d->y), then a base quaternion scaled
     * by 1.01 (not a state cd_state_get makes). Both CD_EINVAL, y intact. */
    cd_scenario *sc = load("free_floating_arm.toml", NULL, 0);
    const cd_model *m = sc->model;
    cd_error e;
    cd_data *d = cd_data_create(m, 0, &e);
    size_t n = cd_state_size(m);
    double *buf = malloc(n * sizeof *buf), *y0 = malloc((size_t)m->ny * sizeof *y0);
    cd_sys_state x = cd_state_of(m, d, 0);
    long qa;
    int k;
    cr_assert_not_null(x.quat, "system 0 is free-floating");
    memcpy(y0, d->y, (size_t)m->ny * sizeof *y0);
    cd_state_get(m, d, buf);
    buf[offset_of(m, d, &d->y[m->ny - 1], 0)] = NAN;
    cr_expect_eq(cd_state_set(m, d, buf, &e), CD_EINVAL);
    cr_expect(strstr(e.msg, "is NaN") != NULL, "%s", e.msg);
    cr_expect_eq(memcmp(d->y, y0, (size_t)m->ny * sizeof *y0), 0, "y keeps its values");
    cd_state_get(m, d, buf);
    qa = offset_of(m, d, x.quat, 0);
    for (k = 0; k < 4; k++) buf[qa + k] *= 1.01;
    cr_expect_eq(cd_state_set(m, d, buf, &e), CD_EINVAL);
    cr_expect(strstr(e.msg, "quaternion") != NULL && strstr(e.msg, "norm 1.01") != NULL, "%s", e.msg);
    cr_expect_eq(memcmp(d->y, y0, (size_t)m->ny * sizeof *y0), 0, "y keeps its values");
    free(buf);
    free(y0);
    cd_data_free(d);
    cd_scenario_free(sc);
}

Test(state, a_state_that_cannot_be_evaluated_changes_nothing)
{
    /* Finite values whose evaluation overflows: a joint rate of 1e200 rad/s
     * (the velocity-product terms are ~1e400). CD_ENUMERIC naming the
     * evaluation, and the data's save is bit-identical to the one before;
     * then the good state is still restored with CD_OK. */
    cd_scenario *sc = load("free_floating_arm.toml", NULL, 0);
    const cd_model *m = sc->model;
    cd_error e;
    cd_data *d = cd_data_create(m, 0, &e);
    size_t n = cd_state_size(m);
    double *good = malloc(n * sizeof *good), *bad = malloc(n * sizeof *bad), *after = malloc(n * sizeof *after);
    cd_sys_state x = cd_state_of(m, d, 0);
    cr_assert_eq(cd_sim_advance(m, d, 0.01, NULL, NULL, &e), CD_OK, "%s", e.msg);
    cd_state_get(m, d, good);
    memcpy(bad, good, n * sizeof *bad);
    bad[offset_of(m, d, x.qd, 0)] = 1e200;
    cr_expect_eq(cd_state_set(m, d, bad, &e), CD_ENUMERIC, "%s", e.msg);
    cr_expect(strstr(e.msg, "cannot be evaluated") != NULL && strstr(e.msg, "nothing was changed") != NULL, "%s",
              e.msg);
    cd_state_get(m, d, after);
    cr_expect_eq(memcmp(good, after, n * sizeof *good), 0, "the data is as before the refused call");
    cr_expect_eq(cd_state_set(m, d, good, &e), CD_OK, "%s", e.msg);
    free(good);
    free(bad);
    free(after);
    cd_data_free(d);
    cd_scenario_free(sc);
}
