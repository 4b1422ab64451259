/* The benchmark chain shared by bench_core.c and bench_speed.c: a base of
 * 100 kg (inertia 20 kg m^2), n links of 2 kg 0.3 m apart along x (CoM at
 * 0.15 m, inertia diag(0.01, 0.05, 0.05) kg m^2), axes alternating z and y;
 * q_i = 0.1 i rad, all joint rates 0.05 rad/s. bench_speed.c writes the same
 * chain as MJCF for MuJoCo. Exits on a builder error (benchmarks only). */
#ifndef CD_BENCH_CHAIN_H
#define CD_BENCH_CHAIN_H
#include <capdyn/capdyn.h>
#include <stdio.h>
#include <stdlib.h>

static cd_model *bench_chain(int n, int free_base)
{
    cd_model *m = cd_model_create();
    cd_error e;
    cd_system_desc s = cd_system_desc_default();
    cd_link_desc l = cd_link_desc_default();
    int i, prev = 0;
    s.type = free_base ? CD_BASE_FREE : CD_BASE_FIXED;
    s.mass = 100;
    s.inertia[0] = s.inertia[4] = s.inertia[8] = 20;
    cd_model_add_system(m, &s, &e);
    for (i = 0; i < n; i++) {
        l.parent = prev;
        l.pos[0] = 0.3;
        l.com[0] = 0.15;
        l.mass = 2;
        l.inertia[0] = 0.01; l.inertia[4] = l.inertia[8] = 0.05;
        l.axis[0] = 0; l.axis[1] = (i % 2); l.axis[2] = 1 - (i % 2);
        l.q0 = 0.1 * i;
        l.qd0 = 0.05;
        prev = cd_model_add_link(m, 0, &l, &e);
    }
    if (cd_model_finalize(m, &e) != CD_OK) {
        fprintf(stderr, "bench: chain of %d links: %s\n", n, e.msg);
        exit(1);
    }
    return m;
}
#endif
