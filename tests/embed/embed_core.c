/* Embedding check for the installed core (tests/install_check.sh): a program
 * that sees capdyn only through `pkg-config capdyn`. A pendulum (1 kg at
 * 0.5 m, started at 60 deg) run for 2 s: its energy must stay within 1e-8
 * relative, and the two forward-dynamics paths (ABA, CRBA) must agree. */
#include <capdyn/capdyn.h>
#include <math.h>
#include <stdio.h>

static double energy(const cd_model *m, cd_data *d)
{
    double ke;
    cd_kinematics(m, d);
    cd_momentum(m, d, 0, &ke, NULL, NULL, NULL, NULL);
    return ke + cd_potential_energy(m, d, 0);
}

int main(void)
{
    cd_error e;
    cd_model *m = cd_model_create();
    cd_system_desc s = cd_system_desc_default();
    cd_link_desc l = cd_link_desc_default();
    cd_data *d;
    double e0, e1, a_aba, a_crba;
    int ok;
    s.type = CD_BASE_FIXED;
    cd_model_add_system(m, &s, &e);
    l.parent = 0;
    l.axis[0] = 1; l.axis[2] = 0;          /* swings in the y-z plane */
    l.com[1] = 0.5;
    l.inertia[0] = l.inertia[4] = l.inertia[8] = 1e-3;
    l.q0 = 1.0471975511965976;
    cd_model_add_link(m, 0, &l, &e);
    m->gravity[2] = -9.81;
    if (cd_model_finalize(m, &e) != CD_OK) { fprintf(stderr, "%s\n", e.msg); return 1; }
    m->opt.rtol = 1e-11;
    m->opt.atol = 1e-13;
    d = cd_data_create(m, 0, &e);
    if (!d) { fprintf(stderr, "%s\n", e.msg); return 1; }
    cd_kinematics(m, d);
    d->tau[0] = 0.0;
    cd_forward_dynamics_method(m, d, CD_FD_ABA);
    a_aba = d->udot[0];
    cd_forward_dynamics_method(m, d, CD_FD_CRBA);
    a_crba = d->udot[0];
    e0 = energy(m, d);
    if (cd_sim_advance(m, d, 2.0, NULL, NULL, &e) != CD_OK) { fprintf(stderr, "%s\n", e.msg); return 1; }
    e1 = energy(m, d);
    ok = fabs(e1 - e0) <= 1e-8 * fabs(e0) && fabs(a_aba - a_crba) <= 1e-12 * fabs(a_crba) && a_crba != 0.0;
    printf("capdyn %s: pendulum 2 s, energy drift %.2e relative, ABA vs CRBA qdd %.17g vs %.17g: %s\n", cd_version(),
           fabs(e1 - e0) / fabs(e0), a_aba, a_crba, ok ? "ok" : "FAILED");
    cd_data_free(d);
    cd_model_free(m);
    return ok ? 0 : 1;
}
