/* The capture scenarios beyond the handrail (issue 10, docs/capture.md,
 * "Capture features beyond the handrail"): a cylindrical docking fixture,
 * a target with solar-array wings, a target tumbling about its intermediate
 * axis. Each scenario is run as `capdyn run --until-verdict`-like: sample by
 * sample with the capture monitor, stopped at its verdict (the verdict and
 * its time are then those of the full run, docs/sweep.md). */
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <capdyn/io.h>
#include "capture_util.h"

#include <math.h>
#include <string.h>

#define DOCK "scenarios/capture_docking_fixture.toml"
#define PANELS "scenarios/capture_solar_panels.toml"
#define INTERMEDIATE "scenarios/capture_intermediate_axis.toml"
#define HANDRAIL "scenarios/capture_handrail_tumbling.toml"

typedef struct {
    cd_scenario *sc;
    cd_data *d;
    cd_ctrl *c;
    cd_monitor mon;
    double dP, dL, Pmax, Lmax; /* whole-system momentum drift and scale (world origin) */
    long n_contact_events;     /* contact onsets and stick-slip switches */
} scen_run;

/* |P - P0|, |L - L0| of chaser + target, and the largest momentum either carries */
static void momentum_update(scen_run *r, double P0[3], double L0[3])
{
    const cd_model *m = r->sc->model;
    double P[3] = {0, 0, 0}, L[3] = {0, 0, 0};
    int s, k;
    cd_kinematics(m, r->d);
    for (s = 0; s < m->nsys; s++) {
        double p[3], l[3];
        cd_momentum(m, r->d, s, NULL, p, NULL, l, NULL);
        for (k = 0; k < 3; k++) { P[k] += p[k]; L[k] += l[k]; }
        r->Pmax = fmax(r->Pmax, sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]));
        r->Lmax = fmax(r->Lmax, sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]));
    }
    if (r->d->t == 0) { memcpy(P0, P, 3 * sizeof *P); memcpy(L0, L, 3 * sizeof *L); }
    for (k = 0; k < 3; k++) { P[k] -= P0[k]; L[k] -= L0[k]; }
    r->dP = fmax(r->dP, sqrt(P[0] * P[0] + P[1] * P[1] + P[2] * P[2]));
    r->dL = fmax(r->dL, sqrt(L[0] * L[0] + L[1] * L[1] + L[2] * L[2]));
}

/* Loads the scenario with the overrides, installs its controller and the
 * monitor, and runs it at its output_dt until t_end or (until_verdict) its
 * verdict, keeping the momentum drift. Free with scen_close. */
static void scen_run_to(scen_run *r, const char *path, const char *const *ov, int nov, double t_end, int until_verdict)
{
    cd_error err;
    double P0[3], L0[3];
    long i;
    memset(r, 0, sizeof *r);
    capture_open(path, ov, nov, &r->sc, &r->d, &r->c, &r->mon);
    momentum_update(r, P0, L0);
    while (r->d->t < t_end - 1e-12) {
        double tn = fmin(r->d->t + r->sc->output_dt, t_end);
        cr_assert_eq(cd_sim_advance(r->sc->model, r->d, tn, NULL, NULL, &err), CD_OK, "%s: %s", path, err.msg);
        cd_monitor_update(&r->mon, r->sc->model, r->d);
        momentum_update(r, P0, L0);
        if (until_verdict && r->mon.verdict != CD_VERDICT_UNRESOLVED) break;
    }
    for (i = 0; i < (r->d->ev_count < r->d->ev_cap ? r->d->ev_count : r->d->ev_cap); i++) {
        const cd_event *ev = cd_data_event(r->d, i);
        if (ev->kind == CD_EV_ONSET || ev->kind == CD_EV_STICK_SLIP || ev->kind == CD_EV_SLIP_STICK) r->n_contact_events++;
    }
}

static void scen_close(scen_run *r)
{
    cd_ctrl_free(r->c);
    cd_data_free(r->d);
    cd_scenario_free(r->sc);
}

/* The cylindrical docking fixture is captured (measured at 9.79 s; the
 * scenario runs 12 s), after the grasp trigger, with the cylinder (the
 * monitor's feature) enclosed and held by sticking contacts. */
Test(capture_scenarios, docking_fixture_is_captured, .timeout = 300)
{
    scen_run r;
    scen_run_to(&r, DOCK, NULL, 0, 12.0, 1);
    cr_expect_eq(r.mon.verdict, CD_VERDICT_CAPTURED, "verdict %s at t = %g (v_rel %g m/s, w_rel %g rad/s)",
                 cd_verdict_name(r.mon.verdict), r.d->t, r.mon.v_rel, r.mon.w_rel);
    cr_expect(r.mon.t_capture > cd_ctrl_t_trigger(r.c) && cd_ctrl_phase_of(r.c, r.d) == CD_CTRL_HOLD,
              "trigger at %g, capture at %g, phase %d", cd_ctrl_t_trigger(r.c), r.mon.t_capture, cd_ctrl_phase_of(r.c, r.d));
    cr_expect(r.mon.enclosed && r.mon.n_stick >= 2, "enclosed %d, %d sticking contacts", r.mon.enclosed, r.mon.n_stick);
    cr_log_info("docking fixture: captured at %.3g s (trigger %.4g s)", r.mon.t_capture, cd_ctrl_t_trigger(r.c));
    scen_close(&r);
}

/* Through the grasp of the cylinder (flat-ended cylinder shape, contact
 * onsets and stick-slip switches, the trigger) with the attitude control
 * (the only external torque) off, the whole system's linear and angular
 * momentum are conserved to 1e-9 of the largest momentum either body
 * carries. */
Test(capture_scenarios, docking_fixture_conserves_momentum, .timeout = 300)
{
    const char *ov[] = {"control.attitude.on=false"};
    scen_run r;
    scen_run_to(&r, DOCK, ov, 1, 3.4, 0);
    cr_expect(r.n_contact_events >= 10 && !isnan(cd_ctrl_t_trigger(r.c)), "contact events %ld, trigger at %g",
              r.n_contact_events, cd_ctrl_t_trigger(r.c));
    cr_expect(r.Pmax > 0.1 && r.Lmax > 1.0, "momenta exchanged: |P| %g, |L| %g", r.Pmax, r.Lmax);
    cr_expect(r.dP <= 1e-9 * r.Pmax, "linear momentum drift %g kg m/s, %g relative", r.dP, r.dP / r.Pmax);
    cr_expect(r.dL <= 1e-9 * r.Lmax, "angular momentum drift %g kg m^2/s, %g relative", r.dL, r.dL / r.Lmax);
    cr_log_info("docking momentum: |dP| %.3g (%.3g relative), |dL| %.3g (%.3g relative)", r.dP, r.dP / r.Pmax, r.dL,
                r.dL / r.Lmax);
    scen_close(&r);
}

/* The wings' mass and inertia in the scenario are the base target's plus
 * two thin boxes moved to the CoM (parallel-axis theorem), computed here
 * from the wing shapes of the loaded model (the box shapes of the target
 * outside its body): to 1e-5 relative (the file gives 6 digits). With the
 * wings, x is the target's intermediate axis, and the growth rate of a
 * perturbed 3 deg/s spin about it is the 0.0161 1/s docs/capture.md quotes. */
Test(capture_scenarios, solar_wing_inertia_is_the_sum_of_its_parts)
{
    cd_error err;
    cd_scenario *base = cd_scenario_load(HANDRAIL, NULL, 0, &err), *sc;
    const cd_model *mb, *m;
    int tb, t, sh, k, nw = 0;
    double mw, I[3], lam, w = 3.0 * M_PI / 180.0;
    cr_assert_not_null(base, "%s", err.msg);
    sc = cd_scenario_load(PANELS, NULL, 0, &err);
    cr_assert_not_null(sc, "%s", err.msg);
    mb = base->model;
    m = sc->model;
    tb = mb->sys_body_adr[cd_model_system_id(mb, "target")];
    t = m->sys_body_adr[cd_model_system_id(m, "target")];
    for (sh = 0; sh < m->nshape; sh++)
        if (m->shape_body[sh] == t && m->shape_type[sh] == CD_SHAPE_BOX && fabs(m->shape_pos[3 * sh + 1]) > 0.7) nw++;
    cr_assert_eq(nw, 2, "two wings, found %d", nw);
    mw = (m->body_mass[t] - mb->body_mass[tb]) / nw;
    cr_expect(fabs(mw - 20.0) < 1e-12, "wing mass %g kg", mw);
    for (k = 0; k < 3; k++) I[k] = mb->body_inertia[9 * tb + 4 * k];
    for (sh = 0; sh < m->nshape; sh++) {
        const double *h = m->shape_size + 3 * sh, *p = m->shape_pos + 3 * sh; /* half extents, centre */
        if (!(m->shape_body[sh] == t && m->shape_type[sh] == CD_SHAPE_BOX && fabs(p[1]) > 0.7)) continue;
        for (k = 0; k < 3; k++) {
            int a = (k + 1) % 3, b = (k + 2) % 3;
            I[k] += mw / 3.0 * (h[a] * h[a] + h[b] * h[b]) + mw * (p[a] * p[a] + p[b] * p[b]);
        }
    }
    for (k = 0; k < 3; k++)
        cr_expect(fabs(m->body_inertia[9 * t + 4 * k] - I[k]) <= 1e-5 * I[k], "I[%d] %.6f in the file, %.6f from the parts",
                  k, m->body_inertia[9 * t + 4 * k], I[k]);
    cr_expect(I[1] < I[0] && I[0] < I[2], "x intermediate: I = (%g, %g, %g)", I[0], I[1], I[2]);
    lam = w * sqrt((I[0] - I[1]) * (I[2] - I[0]) / (I[1] * I[2]));
    cr_expect(fabs(lam - 0.0161) < 5e-5, "growth rate %g 1/s", lam);
    cd_scenario_free(sc);
    cd_scenario_free(base);
}

/* The winged target tumbling about its minor axis y: its handrail's bar
 * slides along its own axis at 50 mm/s; the approach never brings the grasp
 * point within the trigger distance in 8 s (docs/capture.md says why), no
 * contact is ever made, and the run ends unresolved. */
Test(capture_scenarios, solar_panels_target_is_not_reached, .timeout = 300)
{
    scen_run r;
    scen_run_to(&r, PANELS, NULL, 0, 8.0, 1);
    cr_expect_eq(r.mon.verdict, CD_VERDICT_UNRESOLVED, "verdict %s at t = %g", cd_verdict_name(r.mon.verdict), r.d->t);
    cr_expect(isnan(cd_ctrl_t_trigger(r.c)) && r.mon.peak_fn == 0.0, "trigger at %g, peak contact force %g N",
              cd_ctrl_t_trigger(r.c), r.mon.peak_fn);
    scen_close(&r);
}

/* The winged target spinning about its intermediate axis x (3 deg/s, 0.1
 * deg/s about y and z) is captured (measured at 4.48 s) well before the
 * perturbation has grown (e-folding time 62 s): the capture sees a nearly
 * steady spin. */
Test(capture_scenarios, intermediate_axis_target_is_captured, .timeout = 300)
{
    scen_run r;
    scen_run_to(&r, INTERMEDIATE, NULL, 0, 8.0, 1);
    cr_expect_eq(r.mon.verdict, CD_VERDICT_CAPTURED, "verdict %s at t = %g (v_rel %g m/s, w_rel %g rad/s)",
                 cd_verdict_name(r.mon.verdict), r.d->t, r.mon.v_rel, r.mon.w_rel);
    cr_expect(r.mon.t_capture > cd_ctrl_t_trigger(r.c), "trigger at %g, capture at %g", cd_ctrl_t_trigger(r.c),
              r.mon.t_capture);
    cr_log_info("intermediate axis: captured at %.3g s (trigger %.4g s)", r.mon.t_capture, cd_ctrl_t_trigger(r.c));
    scen_close(&r);
}
