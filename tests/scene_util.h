/* Scene builders shared by the contact tests (test_friction.c,
 * test_contact_impact.c): systems with an isotropic inertia, a point check
 * point, a plane; every failure is a Criterion assertion. */
#ifndef CD_TEST_SCENE_UTIL_H
#define CD_TEST_SCENE_UTIL_H
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <string.h>

/* A system with isotropic inertia; pos, vel, angvel may be NULL (zero). */
static inline int add_system(cd_model *m, const char *name, cd_base_type type, double mass, double inertia,
                             const double pos[3], const double vel[3], const double angvel[3])
{
    cd_error e;
    cd_system_desc s = cd_system_desc_default();
    int id;
    s.name = name;
    s.type = type;
    s.mass = mass;
    memset(s.inertia, 0, sizeof s.inertia);
    s.inertia[0] = s.inertia[4] = s.inertia[8] = inertia;
    if (pos) memcpy(s.pos, pos, sizeof s.pos);
    if (vel) memcpy(s.vel, vel, sizeof s.vel);
    if (angvel) memcpy(s.angvel, angvel, sizeof s.angvel);
    id = cd_model_add_system(m, &s, &e);
    cr_assert(id >= 0, "%s", e.msg);
    return id;
}

/* A check point of radius 0 at the body's frame origin. */
static inline int add_point(cd_model *m, int body)
{
    cd_error e;
    double z[3] = {0, 0, 0};
    int cp = cd_model_add_checkpoint(m, body, z, 0.0, &e);
    cr_assert(cp >= 0, "%s", e.msg);
    return cp;
}

/* The plane z = 0 (half-space z <= 0) of the body's frame. */
static inline int add_plane(cd_model *m, int body)
{
    cd_error e;
    int sh = cd_model_add_shape(m, body, CD_SHAPE_PLANE, NULL, NULL, NULL, NULL, 0, &e);
    cr_assert(sh >= 0, "%s", e.msg);
    return sh;
}

/* A ball (mass, uniform-sphere inertia 0.4 m r^2, check point of radius r
 * at its CoM) at height r + gap over a fixed ground plane, moving at -v0
 * toward it, in contact through law; integrated at rtol 1e-12, atol 1e-14
 * and h_max; the slot starts open. */
typedef struct { cd_model *m; cd_data *d; int ball; } ball_scene;

static inline ball_scene ball_on_plane(double mass, double r, double gap, double v0, const cd_contact_law *law,
                                       double h_max)
{
    ball_scene sc;
    cd_error e;
    double pos[3] = {0, 0, 0}, vel[3] = {0, 0, 0}, zero[3] = {0, 0, 0};
    int ground, plane, lid;
    sc.m = cd_model_create();
    cr_assert(sc.m);
    ground = add_system(sc.m, "ground", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    plane = add_plane(sc.m, sc.m->sys_body_adr[ground]);
    pos[2] = r + gap;
    vel[2] = -v0;
    sc.ball = add_system(sc.m, "ball", CD_BASE_FREE, mass, 0.4 * mass * r * r, pos, vel, NULL);
    cr_assert(cd_model_add_checkpoint(sc.m, sc.m->sys_body_adr[sc.ball], zero, r, &e) >= 0, "%s", e.msg);
    lid = cd_model_add_law(sc.m, law, &e);
    cr_assert(lid >= 0, "the model accepts the law: %s", e.msg);
    cr_assert(cd_model_add_pair(sc.m, sc.ball, -1, plane, lid, &e) >= 0, "%s", e.msg);
    cr_assert_eq(cd_model_finalize(sc.m, &e), CD_OK, "%s", e.msg);
    sc.m->opt.rtol = 1e-12;
    sc.m->opt.atol = 1e-14;
    sc.m->opt.h_max = h_max;
    sc.d = cd_data_create(sc.m, 0, &e);
    cr_assert(sc.d, "%s", e.msg);
    cr_assert_eq(sc.d->slot_mode[0], CD_MODE_OPEN);
    return sc;
}

static inline void ball_scene_free(ball_scene *sc)
{
    cd_data_free(sc->d);
    cd_model_free(sc->m);
}

#endif
