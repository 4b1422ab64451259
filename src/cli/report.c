/* The report of a results file (cli_report): the body of capdyn info, and
 * the summary printed at the end of capdyn run. Both read the results file
 * back (one code path); the run adds what only it knows (wall time, force
 * maxima over every step rather than at samples). One function per section
 * of the report, printed in this order: identity, status, events, systems,
 * contacts, capture verdict, integrator, energy and momentum.
 *
 * Conservation figures. Energy is kinetic + gravitational (contact springs
 * and actuator work are not in it, so it is conserved only without
 * contact and actuation). Momentum drift is reported absolutely and
 * relative to a bound that the momentum of the motion cannot exceed:
 * |P| <= sqrt(2 M T) and |L_com| <= sqrt(2 T J), J = sum_b m_b |c_b - C|^2
 * + tr(I_b) (Cauchy-Schwarz on T = 1/2 sum m v^2 + w.I w), maximised over
 * the samples, so that a run starting at rest still has a meaningful
 * relative figure. */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "../io/h5_schema.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define RAD_TO_DEG 57.29577951308232

static double norm3(const double *a) { return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

static void print_wrapped_kv(FILE *out, const char *key, const char *val)
{
    if (strlen(key) >= 12) fprintf(out, "%s  %s\n", key, val);
    else fprintf(out, "%-12s%s\n", key, val);
}

/* one line naming a slot: "left/link2 cp 3 -> target (cylinder)" */
static void slot_label(const cd_h5r *r, int k, char *buf, size_t len)
{
    const cd_h5r_slot *s = r->slot + k;
    snprintf(buf, len, "%s cp %d -> %s (%s)", s->body_a_name, s->checkpoint, s->body_b_name, s->shape_type);
}

/* ---- identity: title, file, scenario, overrides ---- */

static void report_identity(FILE *out, const cd_h5r *r, const char *path)
{
    char *title = cd_h5r_attr_str(r, "/", "title"), *ver = cd_h5r_attr_str(r, "/", "capdyn_version");
    char *created = cd_h5r_attr_str(r, "/", "created_utc"), *closed = cd_h5r_attr_str(r, "/", "closed_utc");
    char *spath = cd_h5r_attr_str(r, "/", "scenario_path"), *stext = cd_h5r_text(r, "scenario_text");
    char *ovr = cd_h5r_text(r, "overrides");
    char line[1024];

    print_wrapped_kv(out, "title", title ? title : "");
    snprintf(line, sizeof line, "%s (capdyn %s, created %s%s%s)", path, ver ? ver : "?", created ? created : "?",
             closed && *closed ? ", closed " : "", closed && *closed ? closed : "");
    print_wrapped_kv(out, "file", line);
    snprintf(line, sizeof line, "%s (%lu bytes of text stored)", spath && *spath ? spath : "(built by code)",
             (unsigned long)(stext ? strlen(stext) : 0));
    print_wrapped_kv(out, "scenario", line);
    if (ovr && *ovr) {
        char *c;
        for (c = ovr; *c; c++)
            if (*c == '\n') *c = ' ';
        print_wrapped_kv(out, "overrides", ovr);
    }
    free(title); free(ver); free(created); free(closed); free(spath); free(stext); free(ovr);
}

/* ---- status: run status, committed samples, wall time ---- */

static void report_status(FILE *out, const cd_h5r *r, const char *status, const cli_run_extra *x)
{
    char *message = cd_h5r_attr_str(r, "/", "run_message");
    cd_error err;
    double *t = cd_h5r_series(r, "/time", NULL, &err), *wall = cd_h5r_series(r, "/diagnostics/wall_time", NULL, &err);
    long n = r->n;
    char line[1024];

    if (status && strcmp(status, "running") == 0)
        snprintf(line, sizeof line, "unfinished: the writer did not close the file (killed, or writing failed: disk full?); committed data only");
    else
        snprintf(line, sizeof line, "%s%s%s", status ? status : "?", message && *message ? ": " : "",
                 message ? message : "");
    print_wrapped_kv(out, "status", line);
    if (n > 0 && t)
        snprintf(line, sizeof line, "%ld committed, t = %.9g .. %.9g s%s", n, t[0], t[n - 1],
                 r->nrows > n ? " (more rows on disk from an interrupted commit: ignored)" : "");
    else
        snprintf(line, sizeof line, "0 committed");
    print_wrapped_kv(out, "samples", line);
    if (x) snprintf(line, sizeof line, "%.3f s", x->wall);
    else if (wall && n > 0) snprintf(line, sizeof line, "%.3f s (at the last committed sample)", wall[n - 1]);
    else line[0] = 0;
    if (line[0]) print_wrapped_kv(out, "wall time", line);
    free(message);
    free(t);
    free(wall);
}

/* ---- events by kind ---- */

static void report_events(FILE *out, const cd_h5r *r)
{
    long count[CD_EV_NKINDS + 1], nev = 0, i;
    cd_error err;
    cd_event *ev = cd_h5r_events(r, &nev, &err);
    char line[1024];
    size_t off;
    int k;

    memset(count, 0, sizeof count);
    for (i = 0; ev && i < nev; i++) count[ev[i].kind >= 0 && ev[i].kind < CD_EV_NKINDS ? ev[i].kind : CD_EV_NKINDS]++;
    off = (size_t)snprintf(line, sizeof line, "%ld", nev);
    if (nev > 0) {
        const char *sep = " (";
        for (k = 0; k < CD_EV_NKINDS; k++)
            if (count[k] && off < sizeof line) {
                off += (size_t)snprintf(line + off, sizeof line - off, "%s%s %ld", sep, cd_event_kind_name((cd_event_kind)k), count[k]);
                sep = ", ";
            }
        if (off < sizeof line) off += (size_t)snprintf(line + off, sizeof line - off, ")");
    }
    if (r->ev_lost > 0 && off < sizeof line)
        snprintf(line + off, sizeof line - off, "; %lld more were lost from the event ring (raise simulation.event_capacity)", r->ev_lost);
    print_wrapped_kv(out, "events", line);
    free(ev);
}

/* ---- systems ---- */

static void report_systems(FILE *out, const cd_h5r *r)
{
    char line[1024];
    int s;
    for (s = 0; s < r->nsys; s++) {
        snprintf(line, sizeof line, "%s: %s base, %d joint%s, %d bod%s", r->sys[s].name,
                 r->sys[s].base_free ? "free-floating" : "fixed", r->sys[s].njoint, r->sys[s].njoint == 1 ? "" : "s",
                 r->sys[s].nbody, r->sys[s].nbody == 1 ? "y" : "ies");
        print_wrapped_kv(out, s == 0 ? "systems" : "", line);
    }
}

/* ---- contacts ---- */

/* The peak normal and tangential force of every slot at the samples (mfn,
 * mft: nslot, zeroed on entry); *kfn, *kft: the slots with the largest of
 * each. The forces over every step (a run's x) are kept apart: they have
 * their own names (docs/cli.md, "Peak forces"). Returns the number of slots
 * that were in contact at some time (at a sample, or at a step for a run). */
static int contact_maxima(const cd_h5r *r, const double *fn, const double *ft, const double *mode,
                          const cli_run_extra *x, double *mfn, double *mft, int *kfn, int *kft)
{
    long i, n = r->n;
    int k, nslot = r->nslot, nclosed = 0;
    for (k = 0; k < nslot; k++) {
        int closed_k = 0;
        for (i = 0; i < n; i++) {
            double a = norm3(ft + 3 * ((size_t)i * nslot + k));
            if (fn[(size_t)i * nslot + k] > mfn[k]) mfn[k] = fn[(size_t)i * nslot + k];
            if (a > mft[k]) mft[k] = a;
            if (mode[(size_t)i * nslot + k] != 0) closed_k = 1;
        }
        if (x && x->fn_max[k] > 0) closed_k = 1;
        if (closed_k || mfn[k] > 0) nclosed++;
        if (mfn[k] > mfn[*kfn]) *kfn = k;
        if (mft[k] > mft[*kft]) *kft = k;
    }
    return nclosed;
}

/* one row per slot that closed (at most 40), with its peak forces at the
 * samples, for a run also over the steps (onset transients apart), and its
 * mode at the last sample */
static void contact_table(FILE *out, const cd_h5r *r, const double *mode, const double *mfn, const double *mft,
                          const cli_run_extra *x, int nclosed)
{
    long i, n = r->n;
    int k, nslot = r->nslot, shown = 0, steps = x && x->fn_body && x->fn_onset;
    char line[1024];
    if (steps)
        fprintf(out, "  %5s  %-48s %11s %11s %11s %12s  %s\n", "slot", "check point -> shape", "fn smp [N]",
                "fn step [N]", "onset [N]", "|ft| smp [N]", "mode at end");
    else
        fprintf(out, "  %5s  %-48s %11s %12s  %s\n", "slot", "check point -> shape", "fn smp [N]", "|ft| smp [N]",
                "mode at end");
    for (k = 0; k < nslot; k++) {
        int closed_k = mfn[k] > 0 || (x && x->fn_max[k] > 0);
        for (i = 0; !closed_k && i < n; i++) closed_k = mode[(size_t)i * nslot + k] != 0;
        if (!closed_k) continue;
        if (shown++ >= 40) {
            fprintf(out, "  ... (%d more; capdyn export FILE contacts --active lists them all)\n", nclosed - 40);
            break;
        }
        slot_label(r, k, line, sizeof line);
        if (steps)
            fprintf(out, "  %5d  %-48s %11.4g %11.4g %11.4g %12.4g  %s\n", k, line, mfn[k], x->fn_body[k],
                    x->fn_onset[k], mft[k],
                    n > 0 ? cd_slot_mode_name((cd_slot_mode)(int)mode[(size_t)(n - 1) * nslot + k]) : "-");
        else
            fprintf(out, "  %5d  %-48s %11.4g %12.4g  %s\n", k, line, mfn[k], mft[k],
                    n > 0 ? cd_slot_mode_name((cd_slot_mode)(int)mode[(size_t)(n - 1) * nslot + k]) : "-");
    }
}

/* "slot K: LABEL) at t = T s" of slot k whose peak was at t[k] (t NULL or
 * NaN: no time) into buf */
static void slot_when(const cd_h5r *r, int k, const double *t, char *buf, size_t len)
{
    char lab[512];
    slot_label(r, k, lab, sizeof lab);
    if (t && isfinite(t[k])) snprintf(buf, len, "slot %d: %s) at t = %.9g s", k, lab, t[k]);
    else snprintf(buf, len, "slot %d: %s)", k, lab);
}

/* a run's peak forces over every step: the physical peak (onset transients
 * excluded), the onset transient apart, the tangential peak; each with its
 * slot and, for the normal force, its time */
static void report_step_peaks(FILE *out, const cd_h5r *r, const cli_run_extra *x, int nslot)
{
    char line[1024], where[700];
    int k, kb = 0, ko = 0, kt = 0;
    for (k = 0; k < nslot; k++) {
        if (x->fn_body[k] > x->fn_body[kb]) kb = k;
        if (x->fn_onset[k] > x->fn_onset[ko]) ko = k;
        if (x->ft_max[k] > x->ft_max[kt]) kt = k;
    }
    slot_when(r, kb, x->t_body, where, sizeof where);
    snprintf(line, sizeof line, "%.6g N (%s, onset transients excluded", x->fn_body[kb], where);
    print_wrapped_kv(out, "peak fn over steps", line);
    slot_when(r, ko, x->t_onset, where, sizeof where);
    if (x->fn_onset[ko] > 0)
        snprintf(line, sizeof line, "%.6g N (%s: the largest force while the damper term exceeded the "
                 "elastic term just after a contact closed", x->fn_onset[ko], where);
    else
        snprintf(line, sizeof line, "none (no contact closed with its damper term above its elastic term)");
    print_wrapped_kv(out, "onset transient", line);
    snprintf(line, sizeof line, "%.6g N (slot %d)", x->ft_max[kt], kt);
    print_wrapped_kv(out, "peak |ft| over steps", line);
}

/* The peaks over steps stored in the file (/contacts/fn_step_max ...,
 * h5_schema.h) into fx, pointing into buf (CD_H5_STEP_COUNT x nslot,
 * caller frees): 1 if all are there and the forces finite, else 0 with why
 * (for the line that says they are not stored). */
static int stored_step_peaks(const cd_h5r *r, cli_run_extra *fx, double **buf, char *why, size_t len)
{
    int nslot = r->nslot, k, i, missing = 0, nonfinite = 0, bad = -1;
    double *b = malloc(sizeof(double) * CD_H5_STEP_COUNT * (size_t)(nslot > 0 ? nslot : 1));
    *buf = b;
    memset(fx, 0, sizeof *fx);
    if (!b) {
        snprintf(why, len, "not read (out of memory)");
        return 0;
    }
    for (k = 0; k < CD_H5_STEP_COUNT; k++) {
        char path[64];
        double *v = b + (size_t)k * (size_t)nslot;
        snprintf(path, sizeof path, "/contacts/%s", cd_h5_step_peak_names[k]);
        int rc = cd_h5r_vec(r, path, v, nslot);
        if (rc == -1) missing = 1;
        else if (rc != 0) {
            if (bad < 0) bad = k;
        } else
            for (i = 0; i < nslot && k < CD_H5_STEP_T_BODY; i++) nonfinite |= !isfinite(v[i]); /* times may be NaN */
    }
    if (bad >= 0)
        snprintf(why, len, "not read (/contacts/%s is not a dataset of %d numbers that reads)",
                 cd_h5_step_peak_names[bad], nslot);
    else if (missing)
        snprintf(why, len, "not stored in this file (written by a capdyn from before the peaks over steps were "
                 "kept in results files; capdyn run prints them at its end)");
    else if (nonfinite)
        snprintf(why, len, "not stored in this file (its run did not close it: the peaks over steps are written "
                 "at the end of the run)");
    if (bad >= 0 || missing || nonfinite) return 0;
    fx->fn_max = b + (size_t)CD_H5_STEP_FN_MAX * (size_t)nslot;
    fx->fn_body = b + (size_t)CD_H5_STEP_FN_BODY * (size_t)nslot;
    fx->fn_onset = b + (size_t)CD_H5_STEP_FN_ONSET * (size_t)nslot;
    fx->ft_max = b + (size_t)CD_H5_STEP_FT_MAX * (size_t)nslot;
    fx->t_body = b + (size_t)CD_H5_STEP_T_BODY * (size_t)nslot;
    fx->t_onset = b + (size_t)CD_H5_STEP_T_ONSET * (size_t)nslot;
    return 1;
}

/* Check points already inside their shapes at the first sample (x > 0):
 * their contacts close at once with K x, and the run starts with that
 * transient. Usually a set-up error (a body placed overlapping another); an
 * equilibrium start or a grasp begun closed has it too, at its static
 * depth, so it is stated, not refused. */
static void report_initial_overlap(FILE *out, const cd_h5r *r)
{
    cd_error err;
    /* the first sample alone: its row of each series */
    double *x = r->n > 0 ? cd_h5r_series_head(r, "/contacts/penetration", 1, NULL, &err) : NULL;
    double *t = x ? cd_h5r_series_head(r, "/time", 1, NULL, &err) : NULL;
    int k, n = 0, kmax = -1;
    char lab[512], line[1024];
    if (!x) return;
    for (k = 0; k < r->nslot; k++)
        if (x[k] > 0) {
            n++;
            if (kmax < 0 || x[k] > x[kmax]) kmax = k;
        }
    if (n > 0) {
        slot_label(r, kmax, lab, sizeof lab);
        snprintf(line, sizeof line,
                 "%d check point%s inside %s shape%s at the first sample, t = %.6g s (deepest %.4g mm: slot %d, %s); "
                 "their contacts start closed and the run begins with their transient",
                 n, n == 1 ? "" : "s", n == 1 ? "its" : "their", n == 1 ? "" : "s", t ? t[0] : 0.0,
                 1e3 * x[kmax], kmax, lab);
        print_wrapped_kv(out, "initial overlap", line);
    }
    free(x);
    free(t);
}

/* The contacts: slots that closed with their peaks at the samples and, from
 * a run's x or else from the file, over every step (the same lines in
 * capdyn run and capdyn info). */
static void report_contacts(FILE *out, const cd_h5r *r, const cli_run_extra *x)
{
    int nslot = r->nslot, nclosed = 0, kfn = 0, kft = 0;
    double *fn = NULL, *ft = NULL, *mode = NULL, *mfn, *mft, *sbuf = NULL;
    cd_error err;
    char line[1024], why[256] = "";
    cli_run_extra fx;

    if (nslot > 0) {
        fn = cd_h5r_series(r, "/contacts/fn", NULL, &err);
        ft = cd_h5r_series(r, "/contacts/ft", NULL, &err);
        mode = cd_h5r_series(r, "/contacts/mode", NULL, &err);
    }
    if (!(nslot > 0 && fn && ft && mode)) {
        print_wrapped_kv(out, "contacts", "no contact slots");
        free(fn); free(ft); free(mode);
        return;
    }
    if (!(x && x->fn_body && x->fn_onset) && stored_step_peaks(r, &fx, &sbuf, why, sizeof why)) x = &fx;
    mfn = calloc((size_t)nslot, sizeof *mfn);
    mft = calloc((size_t)nslot, sizeof *mft);
    if (mfn && mft) nclosed = contact_maxima(r, fn, ft, mode, x, mfn, mft, &kfn, &kft);
    snprintf(line, sizeof line, "%d slot%s, %d in contact at some time%s", nslot, nslot == 1 ? "" : "s", nclosed,
             nclosed ? ":" : "");
    print_wrapped_kv(out, "contacts", line);
    if (nclosed && mfn && mft) {
        contact_table(out, r, mode, mfn, mft, x, nclosed);
        snprintf(line, sizeof line, "%.6g N (slot %d), onset transients included; peak |ft| at samples %.6g N (slot %d)",
                 mfn[kfn], kfn, mft[kft], kft);
        print_wrapped_kv(out, "peak fn at samples", line);
        if (x && x->fn_body && x->fn_onset) report_step_peaks(out, r, x, nslot);
        else if (why[0]) print_wrapped_kv(out, "peak fn over steps", why);
        report_initial_overlap(out, r);
    }
    free(mfn); free(mft); free(fn); free(ft); free(mode); free(sbuf);
}

/* ---- the capture verdict (scenarios with a gripper and an object) ---- */

/* the figures of merit of a [control] run (docs/capture.md), if the file has them */
static void report_capture_control(FILE *out, const cd_h5r *r)
{
    double dP[3], dL[3], amax = NAN, rate = NAN, ttr = NAN, trig = NAN, vr = NAN, wr = NAN, tarm = NAN;
    char line[1024];
    if (cd_h5r_attr_f64v(r, "/", "capture_dP", dP, 3) != 0 || cd_h5r_attr_f64v(r, "/", "capture_dL", dL, 3) != 0)
        return;
    cd_h5r_attr_f64(r, "/", "capture_base_angle_max", &amax);
    cd_h5r_attr_f64(r, "/", "capture_base_rate_end", &rate);
    cd_h5r_attr_f64(r, "/", "capture_t_trigger", &trig);
    cd_h5r_attr_f64(r, "/", "capture_t_rigidise", &ttr);
    cd_h5r_attr_f64(r, "/", "capture_v_rel_end", &vr);
    cd_h5r_attr_f64(r, "/", "capture_w_rel_end", &wr);
    cd_h5r_attr_f64(r, "/", "capture_tau_arm_max", &tarm); /* NaN in files before it existed */
    snprintf(line, sizeof line,
             "momentum to the chaser (%.4g, %.4g, %.4g) kg m/s, (%.4g, %.4g, %.4g) kg m^2/s; base "
             "attitude max %.4g deg, final rate %.4g deg/s; trigger at %.6g s, rigidised %.6g s later; "
             "target relative to the base at the end %.4g m/s, %.4g deg/s; peak arm joint torque %.4g N m",
             dP[0], dP[1], dP[2], dL[0], dL[1], dL[2], amax * RAD_TO_DEG, rate * RAD_TO_DEG, trig, ttr,
             vr, wr * RAD_TO_DEG, tarm);
    print_wrapped_kv(out, "", line);
}

/* the verdict of a finished run with its peak loads and the grasp at the end */
static void report_capture_grasp(FILE *out, const cd_h5r *r, const char *verdict)
{
    double t = NAN, pfn = NAN, ptau = NAN, off[3] = {NAN, NAN, NAN}, eps = NAN;
    long long nst = -1, nsl = -1;
    char line[1024];
    cd_h5r_attr_f64(r, "/", "capture_t", &t);
    cd_h5r_attr_f64(r, "/", "capture_peak_fn", &pfn);
    cd_h5r_attr_f64(r, "/", "capture_peak_tau", &ptau);
    cd_h5r_attr_f64v(r, "/", "capture_offset", off, 3);
    cd_h5r_attr_f64(r, "/", "capture_epsilon", &eps);
    cd_h5r_attr_i64(r, "/", "capture_n_stick", &nst);
    cd_h5r_attr_i64(r, "/", "capture_n_slip", &nsl);
    if (isfinite(t)) snprintf(line, sizeof line, "%s at t = %.6g s", verdict, t);
    else snprintf(line, sizeof line, "%s", verdict);
    print_wrapped_kv(out, "capture", line);
    snprintf(line, sizeof line,
             "peak fn on the object at samples %.6g N, peak hand joint torque at samples %.6g N m; at the end %lld contacts (%lld stick, "
             "%lld slip), object offset from the palm (%.4g, %.4g, %.4g) m, grasp quality epsilon %.4g%s",
             pfn, ptau, nst + nsl, nst, nsl, off[0], off[1], off[2], eps, eps > 0 ? "" : " (no force closure)");
    print_wrapped_kv(out, "", line);
}

static void report_capture(FILE *out, const cd_h5r *r)
{
    char *verdict = cd_h5r_attr_str(r, "/", "capture_verdict");
    if (!verdict) return; /* no monitor in this scenario */
    if (verdict[0]) {
        report_capture_grasp(out, r, verdict);
        report_capture_control(out, r);
    } else {
        print_wrapped_kv(out, "capture", "no verdict (the run did not finish)");
    }
    free(verdict);
}

/* ---- integrator ---- */

/* the closing statistics of a finished run (ns steps) into line; *nd, *ng:
 * the warning counts */
static void integrator_final(const cd_h5r *r, const char *stepper, const char *rs, const char *as, long long ns,
                             char *line, size_t len, long long *nd, long long *ng)
{
    long long nr = 0, nf = 0, nl = 0, nj = 0, nws = 0, nwe = 0;
    double hmin = 0, hmax = 0, tstiff = 0, tfin = 0;
    size_t used;
    cd_h5r_attr_i64(r, "/", "stats_nrejected", &nr);
    cd_h5r_attr_i64(r, "/", "stats_nrhs", &nf);
    cd_h5r_attr_i64(r, "/", "stats_nlocate_steps", &nl);
    cd_h5r_attr_i64(r, "/", "stats_nwarn_dwell", nd);
    cd_h5r_attr_i64(r, "/", "stats_nwarn_geom", ng);
    cd_h5r_attr_i64(r, "/", "stats_njac", &nj); /* absent from files before it existed: stays 0 */
    cd_h5r_attr_i64(r, "/", "stats_nswitch_stiff", &nws);
    cd_h5r_attr_i64(r, "/", "stats_nswitch_explicit", &nwe);
    cd_h5r_attr_f64(r, "/", "stats_t_stiff", &tstiff);
    cd_h5r_attr_f64(r, "/", "t_final", &tfin);
    cd_h5r_attr_f64(r, "/", "stats_h_min", &hmin);
    cd_h5r_attr_f64(r, "/", "stats_h_max", &hmax);
    snprintf(line, len,
             "%s, rtol %s, atol %s: %lld steps (%lld rejected), %lld rhs evaluations, %lld event-locating "
             "steps; step %.3g .. %.3g s",
             stepper ? stepper : "?", rs, as, ns, nr, nf, nl, hmin, hmax);
    if (nj > 0) {
        used = strlen(line);
        snprintf(line + used, len - used, "; %lld Jacobians (in the evaluations)", nj);
    }
    if (stepper && strcmp(stepper, "auto") == 0 && nws >= 0 && nwe >= 0) {
        /* with interpolated samples the last step may end past the run's end:
         * the time on msbdf within the run is at most the run (stats_t_stiff
         * keeps the stepper's own count) */
        double ts = tstiff > 0 ? tstiff : 0.0;
        if (tfin > 0 && ts > tfin) ts = tfin;
        used = strlen(line);
        snprintf(line + used, len - used,
                 "; auto: %lld switches to msbdf and %lld back to rk8pd, msbdf for %.3g of %.3g s", nws, nwe, ts,
                 tfin);
    }
}

/* the counters at the last committed sample of an unfinished run into line */
static void integrator_partial(const cd_h5r *r, const char *stepper, const char *rs, const char *as, char *line,
                               size_t len)
{
    cd_error err;
    long n = r->n;
    double *a = cd_h5r_series(r, "/diagnostics/nsteps", NULL, &err);
    double *bb = cd_h5r_series(r, "/diagnostics/nrejected", NULL, &err);
    double *c = cd_h5r_series(r, "/diagnostics/nrhs", NULL, &err);
    snprintf(line, len, "%s, rtol %s, atol %s: %.0f steps (%.0f rejected), %.0f rhs evaluations "
             "(at the last committed sample)", stepper ? stepper : "?", rs, as,
             a ? a[n - 1] : 0.0, bb ? bb[n - 1] : 0.0, c ? c[n - 1] : 0.0);
    free(a);
    free(bb);
    free(c);
}

static void report_integrator(FILE *out, const cd_h5r *r, const char *status)
{
    char *stepper = cd_h5r_attr_str(r, "/", "stepper");
    long long ns = 0, nd = 0, ng = 0;
    double rtol = 0, atol = 0;
    char rs[CLI_NUM], as[CLI_NUM], line[1024];
    /* the closing statistics exist from the start (placeholders): final
     * once the run wrote its status */
    int final = status && strcmp(status, "running") != 0 && cd_h5r_attr_i64(r, "/", "stats_nsteps", &ns) == 0 &&
                ns >= 0;
    cd_h5r_attr_f64(r, "/", "rtol", &rtol);
    cd_h5r_attr_f64(r, "/", "atol", &atol);
    cli_fmt_num(rs, rtol); /* as given in the scenario: every digit */
    cli_fmt_num(as, atol);
    if (final)
        integrator_final(r, stepper, rs, as, ns, line, sizeof line, &nd, &ng);
    else if (r->n > 0)
        integrator_partial(r, stepper, rs, as, line, sizeof line);
    else
        snprintf(line, sizeof line, "%s, rtol %s, atol %s", stepper ? stepper : "?", rs, as);
    print_wrapped_kv(out, "integrator", line);
    if (nd || ng) {
        snprintf(line, sizeof line, "%lld switches deferred by the dwell rule, %lld rejected geometry answers", nd, ng);
        print_wrapped_kv(out, "warnings", line);
    }
    free(stepper);
}

/* ---- energy and momentum ---- */

/* the diagnostics series the conservation figures are made of */
typedef struct {
    double *ke, *pe;      /* (n, nsys) kinetic, gravitational energy [J] */
    double *P, *Lo, *com; /* (n, nsys, 3) momentum, angular momentum about the origin, CoM */
    double **bc;          /* (nsys) body CoMs (n, nbody, 3) of each system; entries may be NULL */
} cons_series;

/* totals over every system at one sample */
typedef struct {
    double E, T;        /* energy, kinetic energy [J] */
    double P[3], Lc[3]; /* momentum, angular momentum about the total CoM */
    double J;           /* sum_b m_b |c_b - C|^2 + tr(I_b) [kg m^2] */
} cons_totals;

/* the drift figures accumulated over the samples */
typedef struct {
    double E0, dEmax, Emax_ke, P0[3], Lc0[3], dP, dL, sP, sL;
} cons_drift;

static void cons_read(const cd_h5r *r, cons_series *cs)
{
    cd_error err;
    char path[1024];
    int s;
    cs->ke = cd_h5r_series(r, "/diagnostics/kinetic_energy", NULL, &err);
    cs->pe = cd_h5r_series(r, "/diagnostics/potential_energy", NULL, &err);
    cs->P = cd_h5r_series(r, "/diagnostics/momentum", NULL, &err);
    cs->Lo = cd_h5r_series(r, "/diagnostics/angular_momentum_origin", NULL, &err);
    cs->com = cd_h5r_series(r, "/diagnostics/com", NULL, &err);
    cs->bc = calloc((size_t)(r->nsys ? r->nsys : 1), sizeof *cs->bc);
    for (s = 0; cs->bc && s < r->nsys; s++) {
        snprintf(path, sizeof path, "/systems/%s/body_c", r->sys[s].group);
        cs->bc[s] = cd_h5r_series(r, path, NULL, &err);
    }
}

static void cons_free(const cd_h5r *r, cons_series *cs)
{
    int s;
    free(cs->ke); free(cs->pe); free(cs->P); free(cs->Lo); free(cs->com);
    for (s = 0; cs->bc && s < r->nsys; s++) free(cs->bc[s]);
    free(cs->bc);
}

/* the totals at sample i (Ms: mass of each system, M: their sum) */
static void cons_totals_at(const cd_h5r *r, const cons_series *cs, const double *Ms, double M, long i,
                           cons_totals *o)
{
    double Lt[3] = {0, 0, 0}, C[3] = {0, 0, 0}, d3[3];
    int s, a, nsys = r->nsys;
    memset(o, 0, sizeof *o);
    for (s = 0; s < nsys; s++) {
        const double *Ps = cs->P + 3 * ((size_t)i * nsys + s), *Ls = cs->Lo + 3 * ((size_t)i * nsys + s),
                     *cm = cs->com + 3 * ((size_t)i * nsys + s);
        o->T += cs->ke[(size_t)i * nsys + s];
        o->E += cs->ke[(size_t)i * nsys + s] + cs->pe[(size_t)i * nsys + s];
        for (a = 0; a < 3; a++) {
            o->P[a] += Ps[a];
            Lt[a] += Ls[a];
            C[a] += Ms[s] * cm[a] / M;
        }
    }
    /* angular momentum about the total CoM: L_O - C x P */
    o->Lc[0] = Lt[0] - (C[1] * o->P[2] - C[2] * o->P[1]);
    o->Lc[1] = Lt[1] - (C[2] * o->P[0] - C[0] * o->P[2]);
    o->Lc[2] = Lt[2] - (C[0] * o->P[1] - C[1] * o->P[0]);
    for (s = 0; cs->bc && s < nsys; s++) {
        int nb = r->sys[s].nbody, j;
        if (!cs->bc[s]) continue;
        for (j = 0; j < nb; j++) {
            const cd_h5r_body *bd = r->body + r->sys[s].body_first + j;
            const double *c = cs->bc[s] + 3 * ((size_t)i * nb + j);
            d3[0] = c[0] - C[0];
            d3[1] = c[1] - C[1];
            d3[2] = c[2] - C[2];
            o->J += bd->mass * (d3[0] * d3[0] + d3[1] * d3[1] + d3[2] * d3[2]) + bd->inertia[0] + bd->inertia[4] +
                    bd->inertia[8];
        }
    }
}

/* adds one sample's totals (the first sets the reference) */
static void cons_drift_add(cons_drift *dr, const cons_totals *o, double M, int first)
{
    double d3[3];
    int a;
    if (first) {
        dr->E0 = o->E;
        memcpy(dr->P0, o->P, sizeof dr->P0);
        memcpy(dr->Lc0, o->Lc, sizeof dr->Lc0);
    }
    if (fabs(o->E - dr->E0) > dr->dEmax) dr->dEmax = fabs(o->E - dr->E0);
    if (o->T > dr->Emax_ke) dr->Emax_ke = o->T;
    for (a = 0; a < 3; a++) d3[a] = o->P[a] - dr->P0[a];
    if (norm3(d3) > dr->dP) dr->dP = norm3(d3);
    for (a = 0; a < 3; a++) d3[a] = o->Lc[a] - dr->Lc0[a];
    if (norm3(d3) > dr->dL) dr->dL = norm3(d3);
    if (sqrt(2.0 * M * o->T) > dr->sP) dr->sP = sqrt(2.0 * M * o->T);
    if (sqrt(2.0 * o->T * o->J) > dr->sL) dr->sL = sqrt(2.0 * o->T * o->J);
}

static void print_energy(FILE *out, const cons_drift *dr, double E_end)
{
    char line[1024];
    snprintf(line, sizeof line, "kinetic + gravitational: E(0) = %.9g J, E(end) = %.9g J, max |E - E(0)| = %.3g J",
             dr->E0, E_end, dr->dEmax);
    print_wrapped_kv(out, "energy", line);
    /* a relative figure needs a reference: a largest kinetic energy at most
     * 1e-9 of the energy figures (|E(0)|, |E(end)|, the drift; all zero for
     * a run at rest) is round-off, and the drift divided by it (1e12 and
     * more) says nothing: the absolute drift above is the figure */
    double scale = fmax(fmax(fabs(dr->E0), fabs(E_end)), dr->dEmax);
    if (dr->Emax_ke > 1e-9 * scale && dr->Emax_ke > 0)
        snprintf(line, sizeof line, "(%.3g relative to the largest kinetic energy; contact springs and actuator "
                 "work are not in E)", dr->dEmax / dr->Emax_ke);
    else
        snprintf(line, sizeof line, "(no relative figure: the largest kinetic energy, %.3g J, is near zero, at most "
                 "1e-9 of |E|; contact springs and actuator work are not in E)", dr->Emax_ke);
    print_wrapped_kv(out, "", line);
}

/* conserved: no gravity; any_fixed: a system has a fixed base; torque: 1 the
 * run's [control] applied base attitude torque (external: the reaction
 * wheels' momentum is not modelled), 0 none, -1 unknown (capdyn info of a
 * [control] run: the file does not record whether the attitude law was on) */
static void print_momentum(FILE *out, const cons_drift *dr, int conserved, int any_fixed, int torque)
{
    char line[1024];
    double v = dr->sP > 0 ? dr->dP / dr->sP : 0.0;
    snprintf(line, sizeof line, "linear: max |P - P(0)| = %.3g kg m/s (%.3g relative to sqrt(2 M T) = %.3g)", dr->dP, v,
             dr->sP);
    print_wrapped_kv(out, "momentum", line);
    v = dr->sL > 0 ? dr->dL / dr->sL : 0.0;
    snprintf(line, sizeof line,
             "angular about the CoM: max |L - L(0)| = %.3g kg m^2/s (%.3g relative to sqrt(2 T J) = %.3g)", dr->dL, v,
             dr->sL);
    print_wrapped_kv(out, "", line);
    if (conserved && !any_fixed && torque > 0)
        print_wrapped_kv(out, "", "(linear expected to be conserved: free-floating systems, no gravity; angular "
                                  "not expected to be conserved: attitude control applies torque to the base)");
    else if (conserved && !any_fixed && torque < 0)
        print_wrapped_kv(out, "", "(expected to be conserved: free-floating systems, no gravity; angular only if "
                                  "[control] attitude control was off: it applies torque to the base)");
    else if (conserved && !any_fixed)
        print_wrapped_kv(out, "", "(expected to be conserved: free-floating systems, no gravity)");
    else
        print_wrapped_kv(out, "", any_fixed ? "(not expected to be conserved: a system has a fixed base)"
                                            : "(not expected to be conserved: gravity)");
}

static void report_conservation(FILE *out, const cd_h5r *r, const cli_run_extra *x)
{
    cons_series cs;
    cons_totals o;
    cons_drift dr;
    double g[3] = {0, 0, 0}, M = 0, *Ms;
    long i, n = r->n;
    int s, b, nsys = r->nsys, conserved, any_fixed = 0;

    cons_read(r, &cs);
    if (!(n > 0 && cs.ke && cs.pe && cs.P && cs.Lo && cs.com)) {
        cons_free(r, &cs);
        return;
    }
    cd_h5r_attr_f64v(r, "/", "gravity", g, 3);
    conserved = !(g[0] != 0 || g[1] != 0 || g[2] != 0);
    Ms = calloc((size_t)(nsys ? nsys : 1), sizeof *Ms);
    for (s = 0; Ms && s < nsys; s++) {
        for (b = r->sys[s].body_first; b < r->sys[s].body_first + r->sys[s].nbody && b < r->nbody; b++)
            Ms[s] += r->body[b].mass;
        M += Ms[s];
        if (!r->sys[s].base_free) any_fixed = 1;
    }
    memset(&dr, 0, sizeof dr);
    memset(&o, 0, sizeof o);
    for (i = 0; Ms && i < n; i++) {
        cons_totals_at(r, &cs, Ms, M, i, &o);
        cons_drift_add(&dr, &o, M, i == 0);
    }
    if (Ms) print_energy(out, &dr, o.E); /* o: the last sample */
    {   /* external torque: the run knows; the file only that a [control] ran */
        double dP[3];
        int torque = x ? (x->attitude ? 1 : 0) : cd_h5r_attr_f64v(r, "/", "capture_dP", dP, 3) == 0 ? -1 : 0;
        print_momentum(out, &dr, conserved, any_fixed, torque);
    }
    free(Ms);
    cons_free(r, &cs);
}

void cli_report(FILE *out, const cd_h5r *r, const char *path, const cli_run_extra *x)
{
    char *status = cd_h5r_attr_str(r, "/", "run_status");
    report_identity(out, r, path);
    report_status(out, r, status, x);
    report_events(out, r);
    report_systems(out, r);
    report_contacts(out, r, x);
    report_capture(out, r);
    report_integrator(out, r, status);
    report_conservation(out, r, x);
    free(status);
}
