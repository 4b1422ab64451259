/* Contact slots built by cd_model_finalize (src/model/model.c, build_slots):
 * one slot per (check point, shape) wanted by some pair, in pair order then
 * check-point order, carrying the law of the first pair that wants it; later
 * pairs never duplicate a slot. The dedup is O(n log n) (issue 12: it was
 * quadratic); these tests pin the semantics exactly, and a large case that
 * the former code could not finish within the test's timeout. */
#include <criterion/criterion.h>

#include "capdyn/model.h"

#include <string.h>

static int add_law(cd_model *m, double K)
{
    cd_contact_law l = cd_contact_law_default();
    cd_error e;
    int id;
    l.K = K;
    id = cd_model_add_law(m, &l, &e);
    cr_assert(id >= 0, "%s", e.msg);
    return id;
}

/* system "a": free base with nb check points and a link "l" with nl check
 * points; target "t" with a sphere. Returns the sphere's shape id. */
static int scene(cd_model *m, int nb, int nl, int *link)
{
    cd_system_desc s = cd_system_desc_default();
    cd_link_desc ld = cd_link_desc_default();
    cd_error e;
    double p[3] = {0, 0, 0}, R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, sz[3] = {0.5, 0, 0};
    int a, t, k, sh;
    s.name = "a";
    a = cd_model_add_system(m, &s, &e);
    cr_assert(a >= 0, "%s", e.msg);
    ld.name = "l";
    ld.parent = m->sys_body_adr[a];
    *link = cd_model_add_link(m, a, &ld, &e);
    cr_assert(*link >= 0, "%s", e.msg);
    for (k = 0; k < nb; k++) {
        p[0] = 1e-3 * k;
        cr_assert(cd_model_add_checkpoint(m, m->sys_body_adr[a], p, 0.01, &e) >= 0, "%s", e.msg);
    }
    for (k = 0; k < nl; k++) {
        p[0] = 1e-3 * k;
        cr_assert(cd_model_add_checkpoint(m, *link, p, 0.01, &e) >= 0, "%s", e.msg);
    }
    s.name = "t";
    s.pos[0] = 5;
    t = cd_model_add_system(m, &s, &e);
    cr_assert(t >= 0, "%s", e.msg);
    p[0] = 0;
    sh = cd_model_add_shape(m, m->sys_body_adr[t], CD_SHAPE_SPHERE, p, R, sz, NULL, 0, &e);
    cr_assert(sh >= 0, "%s", e.msg);
    return sh;
}

Test(slots, identical_pairs_make_one_slot_per_check_point_with_the_first_law)
{
    cd_model *m = cd_model_create();
    cd_error e;
    int link, sh = scene(m, 3, 2, &link), i, laws[50];
    for (i = 0; i < 50; i++) laws[i] = add_law(m, 1000.0 + i);
    for (i = 0; i < 50; i++) cr_assert(cd_model_add_pair(m, 0, -1, sh, laws[i], &e) >= 0, "%s", e.msg);
    cr_assert_eq(cd_model_finalize(m, &e), CD_OK, "%s", e.msg);
    /* check points 0..4 (3 on the base, 2 on the link), once each, in order */
    cr_assert_eq(m->nslot, 5);
    for (i = 0; i < 5; i++) {
        cr_expect_eq(m->slot_cp[i], i);
        cr_expect_eq(m->slot_shape[i], sh);
        cr_expect_eq(m->slot_law[i], laws[0]);
    }
    cd_model_free(m);
}

Test(slots, body_pair_then_system_pair_keeps_the_body_pair_law_and_order)
{
    cd_model *m = cd_model_create();
    cd_error e;
    int link, sh = scene(m, 3, 2, &link), lb = add_law(m, 1e3), ls = add_law(m, 2e3), i;
    const int want_cp[5] = {3, 4, 0, 1, 2};
    cr_assert(cd_model_add_pair(m, 0, link, sh, lb, &e) >= 0, "%s", e.msg);
    cr_assert(cd_model_add_pair(m, 0, -1, sh, ls, &e) >= 0, "%s", e.msg);
    cr_assert(cd_model_add_pair(m, 0, link, sh, ls, &e) >= 0, "%s", e.msg); /* covered twice over */
    cr_assert_eq(cd_model_finalize(m, &e), CD_OK, "%s", e.msg);
    /* the link's two (pair 0, its law), then the base's three (pair 1) */
    cr_assert_eq(m->nslot, 5);
    for (i = 0; i < 5; i++) {
        cr_expect_eq(m->slot_cp[i], want_cp[i], "slot %d: cp %d", i, m->slot_cp[i]);
        cr_expect_eq(m->slot_law[i], i < 2 ? lb : ls, "slot %d", i);
    }
    cd_model_free(m);
}

Test(slots, many_check_points_and_many_identical_pairs_finish, .timeout = 30)
{
    /* 20 000 check points x 2 000 identical pairs: 4e7 (pair, check point)
     * combinations, each tested against up to 2e4 slots (about 4e11 tests)
     * in the former code; here the covered pairs are skipped and 20 000
     * slots are built (kept small for ASan, whose realloc copies: the
     * builder resizes its arrays on every add) */
    cd_model *m = cd_model_create();
    cd_error e;
    int link, sh = scene(m, 10000, 10000, &link), law = add_law(m, 1e3), i;
    for (i = 0; i < 2000; i++) cr_assert(cd_model_add_pair(m, 0, -1, sh, law, &e) >= 0, "%s", e.msg);
    cr_assert_eq(cd_model_finalize(m, &e), CD_OK, "%s", e.msg);
    cr_assert_eq(m->nslot, 20000);
    for (i = 0; i < m->nslot; i++)
        if (m->slot_cp[i] != i) cr_assert_fail("slot %d has check point %d", i, m->slot_cp[i]);
    cd_model_free(m);
}
