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

#endif
