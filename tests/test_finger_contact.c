/* [gripper] finger_contact (docs/scenario-format.md, docs/contact.md): the
 * law of a mechanism hand's finger-on-finger pairs, apart from the law of its
 * pairs against the targets. Facts: every pair whose check points are on a
 * finger and whose shape is another finger of the same hand takes the
 * finger_contact law (Hunt-Crossley, the given K, D, D_t); every pair against
 * the target keeps [contact]'s (linear) law; without the key both are
 * [contact]'s. Bad input: tests/bad_inputs/106-108. */
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <capdyn/io.h>
#include "loader_util.h"

static const char *HAND = "[simulation]\nduration = 0.1\n\n"
                          "[contact]\nK = 1e4\nD = 63.2\n\n"
                          "[[target]]\nname = \"object\"\nmass = 0.3\ninertia = [1e-4, 1e-4, 1e-4]\n"
                          "position = [0.0, 0.08, 0.0]\nshape = { type = \"sphere\", radius = 0.03 }\n\n"
                          "[gripper]\ntype = \"space\"\nlinks = [0.08, 0.07]\n%s\n";

/* counts the finger-on-finger pairs and the pairs against the target, and
 * checks the law of each against the wanted one */
static void count_pairs(const cd_model *m, int want_ff_hc, int *nff, int *ntg)
{
    *nff = *ntg = 0;
    for (int p = 0; p < m->npair; p++) {
        const cd_contact_law *l = &m->law[m->pair_law[p]];
        int shape_sys = m->body_sys[m->shape_body[m->pair_shape[p]]];
        if (shape_sys == m->pair_sys[p]) {
            (*nff)++;
            cr_assert(m->pair_body[p] >= 0, "a finger-on-finger pair names its finger link");
            if (want_ff_hc) {
                cr_expect_eq(l->damping, CD_DAMP_HUNT_CROSSLEY, "pair %d: finger on finger, Hunt-Crossley", p);
                cr_expect_eq(l->K, 2e4, "pair %d: K %g", p, l->K);
                cr_expect_eq(l->D, 1.474e5, "pair %d: D %g", p, l->D);
                cr_expect_eq(l->Dt, 89.4, "pair %d: D_t %g", p, l->Dt);
            } else {
                cr_expect_eq(l->damping, CD_DAMP_LINEAR, "pair %d: finger on finger, [contact]'s law", p);
                cr_expect_eq(l->D, 63.2, "pair %d: D %g", p, l->D);
            }
        } else {
            (*ntg)++;
            cr_expect_eq(l->damping, CD_DAMP_LINEAR, "pair %d: against the target, [contact]'s law", p);
            cr_expect_eq(l->K, 1e4, "pair %d: K %g", p, l->K);
            cr_expect_eq(l->D, 63.2, "pair %d: D %g", p, l->D);
        }
    }
}

static void load_and_count(const char *extra, int want_ff_hc)
{
    char dir[512], path[700];
    cd_error err;
    int nff, ntg;
    lu_tmpdir(dir, sizeof dir);
    lu_write(dir, "hand.toml", HAND, extra);
    snprintf(path, sizeof path, "%s/hand.toml", dir);
    cd_scenario *sc = cd_scenario_load(path, NULL, 0, &err);
    cr_assert_not_null(sc, "%s", err.msg);
    count_pairs(sc->model, want_ff_hc, &nff, &ntg);
    cr_log_info("%d finger-on-finger pairs, %d against the target", nff, ntg);
    cr_expect_gt(nff, 0, "the space hand's fingers can touch each other");
    cr_expect_gt(ntg, 0, "the hand touches the target");
    cd_scenario_free(sc);
    lu_rm_rf(dir);
}

Test(finger_contact, sets_the_law_of_the_finger_on_finger_pairs_only)
{
    load_and_count("finger_contact = { damping_law = \"hunt_crossley\", K = 2e4, D = 1.474e5, D_t = 89.4 }", 1);
}

Test(finger_contact, without_it_every_hand_pair_takes_the_contact_law)
{
    load_and_count("", 0);
}
