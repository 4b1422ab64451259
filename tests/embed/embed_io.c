/* Embedding check for the installed io layer (tests/install_check.sh): a C
 * program that sees capdyn only through `pkg-config capdyn-io` loads a
 * scenario (written here, a free body tumbling about its major axis), runs
 * it and writes the HDF5 results; the body's kinetic energy must stay within
 * 1e-8 relative and every call must succeed. It also links the analysis
 * layer (Qhull through capdyn-io.pc): the planar antipodal pair with mu = 1/2
 * has epsilon mu / sqrt(2 + mu^2) = 1/3 (tests/test_grasp_quality.c). */
#define _POSIX_C_SOURCE 200809L /* mkdtemp */
#include <capdyn/capdyn.h>
#include <capdyn/io.h>
#include <capdyn/analysis.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static const char *scenario =
    "title = \"install check\"\n"
    "[simulation]\nduration = 1.0\nrtol = 1e-11\natol = 1e-13\noutput_dt = 0.1\n"
    "[[system]]\nname = \"body\"\nmass = 2.0\ninertia = [0.1, 0.2, 0.3]\n"
    "angular_velocity = [0.01, 0.0, 1.0]\n";

int main(void)
{
    char dir[] = "/tmp/capdyn_embed_ioXXXXXX", toml[256], h5[256];
    cd_error e;
    cd_scenario *sc;
    cd_data *d;
    cd_h5_writer *w;
    FILE *f;
    double ke0, ke1, t;
    int ok;
    cd_grasp_contact gc[2] = {{{0.1, 0, 0}, {-1, 0, 0}, 0.5, {0, 0, 0}}, {{-0.1, 0, 0}, {1, 0, 0}, 0.5, {0, 0, 0}}};
    cd_grasp_options go = cd_grasp_options_default();
    cd_grasp_quality gq;
    const double origin[3] = {0, 0, 0};
    if (!mkdtemp(dir)) { perror("mkdtemp"); return 1; }
    snprintf(toml, sizeof toml, "%s/s.toml", dir);
    snprintf(h5, sizeof h5, "%s/r.h5", dir);
    f = fopen(toml, "w");
    if (!f) { perror(toml); return 1; }
    fputs(scenario, f);
    fclose(f);
    sc = cd_scenario_load(toml, NULL, 0, &e);
    if (!sc) { fprintf(stderr, "%s\n", e.msg); return 1; }
    d = cd_data_create(sc->model, sc->event_capacity, &e);
    w = d ? cd_h5_create(h5, sc->model, sc, &e) : NULL;
    if (!w) { fprintf(stderr, "%s\n", e.msg); return 1; }
    cd_kinematics(sc->model, d);
    cd_momentum(sc->model, d, 0, &ke0, NULL, NULL, NULL, NULL);
    ok = cd_h5_append(w, sc->model, d, &e) == CD_OK;
    for (t = sc->output_dt; ok && t <= sc->duration + 1e-12; t += sc->output_dt)
        ok = cd_sim_advance(sc->model, d, t, NULL, NULL, &e) == CD_OK && cd_h5_append(w, sc->model, d, &e) == CD_OK;
    if (!ok) fprintf(stderr, "%s\n", e.msg);
    ok = cd_h5_close(w, sc->model, d, CD_OK, "done", &e) == CD_OK && ok;
    cd_kinematics(sc->model, d);
    cd_momentum(sc->model, d, 0, &ke1, NULL, NULL, NULL, NULL);
    ok = ok && fabs(ke1 - ke0) <= 1e-8 * ke0;
    go.mode = CD_GRASP_PLANAR;
    gq.epsilon = 0.0;
    ok = ok && cd_grasp_quality_eval(gc, 2, origin, &go, &gq, &e) == CD_OK && fabs(gq.epsilon - 1.0 / 3.0) <= 1e-9;
    printf("capdyn-io %s: scenario loaded, %.1f s run, results written, kinetic energy drift %.2e, grasp epsilon %.15f: %s\n",
           cd_version(), d->t, fabs(ke1 - ke0) / ke0, gq.epsilon, ok ? "ok" : "FAILED");
    remove(h5);
    remove(toml);
    remove(dir);
    cd_data_free(d);
    cd_scenario_free(sc);
    return ok ? 0 : 1;
}
