/* Internal: the world position of a point fixed on a body, inline for the
 * hot paths (cd_point_world, the contact evaluation's check points). */
#ifndef CD_KINEMATICS_H
#define CD_KINEMATICS_H
#include "capdyn/sim.h"
#include "../math/cd_math.h"

/* x_b + R_b pb, from d's evaluated kinematics */
static inline void cd_body_point(const cd_data *d, int b, const double pb[3], double pw[3])
{
    double t[3];
    cd_m3_mulv(t, d->body_R + 9 * b, pb);
    cd_v3_add(pw, d->body_x + 3 * b, t);
}

#endif
