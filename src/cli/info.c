/* capdyn info, and the summary printed at the end of capdyn run: both read
 * the results file back (one code path), the run adds what only it knows
 * (wall time, force maxima over every step rather than at samples).
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

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *info_help =
    "usage: capdyn info RESULTS.h5\n"
    "\n"
    "Summary of a results file: title, scenario, run status, committed samples\n"
    "and time span, events by kind, systems, contact slots that closed with\n"
    "their largest forces, integrator statistics, energy and momentum drift.\n"
    "Works on a file whose run was killed (it reads the committed samples only)\n"
    "and on a file that a run is still writing.\n";

static double norm3(const double *a) { return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

static void print_wrapped_kv(FILE *out, const char *key, const char *val)
{
    fprintf(out, "%-12s%s\n", key, val);
}

/* one line naming a slot: "left/link2 cp 3 -> target (cylinder)" */
static void slot_label(const cd_h5r *r, int k, char *buf, size_t len)
{
    const cd_h5r_slot *s = r->slot + k;
    snprintf(buf, len, "%s cp %d -> %s (%s)", s->body_a_name, s->checkpoint, s->body_b_name, s->shape_type);
}

void cli_report(FILE *out, const cd_h5r *r, const char *path, const cli_run_extra *x)
{
    char *title = cd_h5r_attr_str(r, "/", "title"), *ver = cd_h5r_attr_str(r, "/", "capdyn_version");
    char *created = cd_h5r_attr_str(r, "/", "created_utc"), *closed = cd_h5r_attr_str(r, "/", "closed_utc");
    char *spath = cd_h5r_attr_str(r, "/", "scenario_path"), *stext = cd_h5r_text(r, "scenario_text");
    char *ovr = cd_h5r_text(r, "overrides"), *status = cd_h5r_attr_str(r, "/", "run_status");
    char *message = cd_h5r_attr_str(r, "/", "run_message"), *stepper = cd_h5r_attr_str(r, "/", "stepper");
    double *t = NULL, *ke = NULL, *pe = NULL, *P = NULL, *Lo = NULL, *com = NULL, *fn = NULL, *ft = NULL,
           *mode = NULL, *wall = NULL, g[3] = {0, 0, 0}, v;
    double **bc = NULL;
    cd_event *ev = NULL;
    long nev = 0, i, n = r->n;
    int s, k, b, nsys = r->nsys, nslot = r->nslot;
    cd_error err;
    char line[1024];

    t = cd_h5r_series(r, "/time", NULL, &err);
    ke = cd_h5r_series(r, "/diagnostics/kinetic_energy", NULL, &err);
    pe = cd_h5r_series(r, "/diagnostics/potential_energy", NULL, &err);
    P = cd_h5r_series(r, "/diagnostics/momentum", NULL, &err);
    Lo = cd_h5r_series(r, "/diagnostics/angular_momentum_origin", NULL, &err);
    com = cd_h5r_series(r, "/diagnostics/com", NULL, &err);
    wall = cd_h5r_series(r, "/diagnostics/wall_time", NULL, &err);
    if (nslot > 0) {
        fn = cd_h5r_series(r, "/contacts/fn", NULL, &err);
        ft = cd_h5r_series(r, "/contacts/ft", NULL, &err);
        mode = cd_h5r_series(r, "/contacts/mode", NULL, &err);
    }
    bc = calloc((size_t)(nsys ? nsys : 1), sizeof *bc);
    for (s = 0; bc && s < nsys; s++) {
        snprintf(line, sizeof line, "/systems/%s/body_c", r->sys[s].group);
        bc[s] = cd_h5r_series(r, line, NULL, &err);
    }
    ev = cd_h5r_events(r, &nev, &err);
    cd_h5r_attr_f64v(r, "/", "gravity", g, 3);

    /* identity */
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
    /* status */
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

    /* events by kind */
    {
        long count[CD_EV_NKINDS + 1];
        size_t off;
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
    }

    /* systems */
    for (s = 0; s < nsys; s++) {
        snprintf(line, sizeof line, "%s: %s base, %d joint%s, %d bod%s", r->sys[s].name,
                 r->sys[s].base_free ? "free-floating" : "fixed", r->sys[s].njoint, r->sys[s].njoint == 1 ? "" : "s",
                 r->sys[s].nbody, r->sys[s].nbody == 1 ? "y" : "ies");
        print_wrapped_kv(out, s == 0 ? "systems" : "", line);
    }

    /* contacts */
    if (nslot > 0 && fn && ft && mode) {
        double *mfn = calloc((size_t)nslot, sizeof *mfn), *mft = calloc((size_t)nslot, sizeof *mft);
        int nclosed = 0, shown = 0, kfn = 0, kft = 0;
        for (k = 0; mfn && mft && k < nslot; k++) {
            int closed_k = 0;
            for (i = 0; i < n; i++) {
                double a = norm3(ft + 3 * ((size_t)i * nslot + k));
                if (fn[(size_t)i * nslot + k] > mfn[k]) mfn[k] = fn[(size_t)i * nslot + k];
                if (a > mft[k]) mft[k] = a;
                if (mode[(size_t)i * nslot + k] != 0) closed_k = 1;
            }
            if (x) {
                if (x->fn_max[k] > mfn[k]) mfn[k] = x->fn_max[k];
                if (x->ft_max[k] > mft[k]) mft[k] = x->ft_max[k];
                if (x->fn_max[k] > 0) closed_k = 1;
            }
            if (closed_k || mfn[k] > 0) nclosed++;
            if (mfn[k] > mfn[kfn]) kfn = k;
            if (mft[k] > mft[kft]) kft = k;
        }
        snprintf(line, sizeof line, "%d slot%s, %d in contact at some time%s", nslot, nslot == 1 ? "" : "s", nclosed,
                 nclosed ? ":" : "");
        print_wrapped_kv(out, "contacts", line);
        if (nclosed && mfn && mft) {
            fprintf(out, "  %5s  %-48s %11s %12s  %s\n", "slot", "check point -> shape", "max fn [N]", "max|ft| [N]",
                    "mode at end");
            for (k = 0; k < nslot; k++) {
                int closed_k = mfn[k] > 0;
                for (i = 0; !closed_k && i < n; i++) closed_k = mode[(size_t)i * nslot + k] != 0;
                if (!closed_k) continue;
                if (shown++ >= 40) {
                    fprintf(out, "  ... (%d more; capdyn export FILE contacts --active lists them all)\n", nclosed - 40);
                    break;
                }
                slot_label(r, k, line, sizeof line);
                fprintf(out, "  %5d  %-48s %11.4g %12.4g  %s\n", k, line, mfn[k], mft[k],
                        n > 0 ? cd_slot_mode_name((cd_slot_mode)(int)mode[(size_t)(n - 1) * nslot + k]) : "-");
            }
            snprintf(line, sizeof line, "normal %.6g N (slot %d), tangential %.6g N (slot %d), %s", mfn[kfn], kfn,
                     mft[kft], kft, x ? "over every integrator step" : "at the samples");
            print_wrapped_kv(out, "max force", line);
        }
        free(mfn);
        free(mft);
    } else {
        print_wrapped_kv(out, "contacts", "no contact slots");
    }

    /* the capture verdict (scenarios with a gripper and an object) */
    {
        char *verdict = cd_h5r_attr_str(r, "/", "capture_verdict");
        if (verdict) {
            if (verdict[0]) {
                double t = NAN, pfn = NAN, ptau = NAN, off[3] = {NAN, NAN, NAN}, eps = NAN;
                long long nst = -1, nsl = -1;
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
                         "peak contact force %.6g N, peak joint torque %.6g N m; at the end %lld contacts (%lld stick, "
                         "%lld slip), object offset from the palm (%.4g, %.4g, %.4g) m, grasp quality epsilon %.4g%s",
                         pfn, ptau, nst + nsl, nst, nsl, off[0], off[1], off[2], eps, eps > 0 ? "" : " (no force closure)");
                print_wrapped_kv(out, "", line);
                { /* a [control] run's figures of merit (docs/capture.md) */
                    double dP[3], dL[3], amax = NAN, rate = NAN, ttr = NAN, trig = NAN, vr = NAN, wr = NAN, tarm = NAN;
                    if (cd_h5r_attr_f64v(r, "/", "capture_dP", dP, 3) == 0 && cd_h5r_attr_f64v(r, "/", "capture_dL", dL, 3) == 0) {
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
                                 dP[0], dP[1], dP[2], dL[0], dL[1], dL[2], amax * 57.29577951308232, rate * 57.29577951308232, trig, ttr,
                                 vr, wr * 57.29577951308232, tarm);
                        print_wrapped_kv(out, "", line);
                    }
                }
            } else {
                print_wrapped_kv(out, "capture", "no verdict (the run did not finish)");
            }
            free(verdict);
        }
    }

    /* integrator */
    {
        long long ns = 0, nr = 0, nf = 0, nl = 0, nd = 0, ng = 0, nj = 0, nws = 0, nwe = 0;
        double rtol = 0, atol = 0, hmin = 0, hmax = 0, tstiff = 0, tfin = 0;
        char rs[CLI_NUM], as[CLI_NUM];
        /* the closing statistics exist from the start (placeholders): final
         * once the run wrote its status */
        int final = status && strcmp(status, "running") != 0 && cd_h5r_attr_i64(r, "/", "stats_nsteps", &ns) == 0 &&
                    ns >= 0;
        cd_h5r_attr_f64(r, "/", "rtol", &rtol);
        cd_h5r_attr_f64(r, "/", "atol", &atol);
        cli_fmt_num(rs, rtol); /* as given in the scenario: every digit */
        cli_fmt_num(as, atol);
        if (final) {
            cd_h5r_attr_i64(r, "/", "stats_nrejected", &nr);
            cd_h5r_attr_i64(r, "/", "stats_nrhs", &nf);
            cd_h5r_attr_i64(r, "/", "stats_nlocate_steps", &nl);
            cd_h5r_attr_i64(r, "/", "stats_nwarn_dwell", &nd);
            cd_h5r_attr_i64(r, "/", "stats_nwarn_geom", &ng);
            cd_h5r_attr_i64(r, "/", "stats_njac", &nj); /* absent from files before it existed: stays 0 */
            cd_h5r_attr_i64(r, "/", "stats_nswitch_stiff", &nws);
            cd_h5r_attr_i64(r, "/", "stats_nswitch_explicit", &nwe);
            cd_h5r_attr_f64(r, "/", "stats_t_stiff", &tstiff);
            cd_h5r_attr_f64(r, "/", "t_final", &tfin);
            cd_h5r_attr_f64(r, "/", "stats_h_min", &hmin);
            cd_h5r_attr_f64(r, "/", "stats_h_max", &hmax);
            snprintf(line, sizeof line,
                     "%s, rtol %s, atol %s: %lld steps (%lld rejected), %lld rhs evaluations, %lld event-locating "
                     "steps; step %.3g .. %.3g s",
                     stepper ? stepper : "?", rs, as, ns, nr, nf, nl, hmin, hmax);
            if (nj > 0) {
                size_t len = strlen(line);
                snprintf(line + len, sizeof line - len, "; %lld Jacobians (in the evaluations)", nj);
            }
            if (stepper && strcmp(stepper, "auto") == 0 && nws >= 0 && nwe >= 0) {
                size_t len = strlen(line);
                snprintf(line + len, sizeof line - len,
                         "; auto: %lld switches to ros34pw2 and %lld back to rk8pd, ros34pw2 for %.3g of %.3g s", nws, nwe,
                         tstiff > 0 ? tstiff : 0.0, tfin);
            }
        } else if (n > 0) {
            double *a = cd_h5r_series(r, "/diagnostics/nsteps", NULL, &err);
            double *bb = cd_h5r_series(r, "/diagnostics/nrejected", NULL, &err);
            double *c = cd_h5r_series(r, "/diagnostics/nrhs", NULL, &err);
            snprintf(line, sizeof line, "%s, rtol %s, atol %s: %.0f steps (%.0f rejected), %.0f rhs evaluations "
                     "(at the last committed sample)", stepper ? stepper : "?", rs, as,
                     a ? a[n - 1] : 0.0, bb ? bb[n - 1] : 0.0, c ? c[n - 1] : 0.0);
            free(a);
            free(bb);
            free(c);
        } else {
            snprintf(line, sizeof line, "%s, rtol %s, atol %s", stepper ? stepper : "?", rs, as);
        }
        print_wrapped_kv(out, "integrator", line);
        if (nd || ng) {
            snprintf(line, sizeof line, "%lld switches deferred by the dwell rule, %lld rejected geometry answers", nd, ng);
            print_wrapped_kv(out, "warnings", line);
        }
    }

    /* energy and momentum */
    if (n > 0 && ke && pe && P && Lo && com) {
        double E0 = 0, dEmax = 0, Emax_ke = 0, P0[3] = {0, 0, 0}, Lc0[3] = {0, 0, 0}, dP = 0, dL = 0, sP = 0, sL = 0;
        double M = 0, *Ms = calloc((size_t)(nsys ? nsys : 1), sizeof *Ms);
        int conserved = !(g[0] != 0 || g[1] != 0 || g[2] != 0), any_fixed = 0;
        for (s = 0; Ms && s < nsys; s++) {
            for (b = r->sys[s].body_first; b < r->sys[s].body_first + r->sys[s].nbody && b < r->nbody; b++)
                Ms[s] += r->body[b].mass;
            M += Ms[s];
            if (!r->sys[s].base_free) any_fixed = 1;
        }
        for (i = 0; Ms && i < n; i++) {
            double E = 0, T = 0, Pt[3] = {0, 0, 0}, Lt[3] = {0, 0, 0}, C[3] = {0, 0, 0}, Lc[3], J = 0, d3[3];
            int a;
            for (s = 0; s < nsys; s++) {
                const double *Ps = P + 3 * ((size_t)i * nsys + s), *Ls = Lo + 3 * ((size_t)i * nsys + s),
                             *cs = com + 3 * ((size_t)i * nsys + s);
                T += ke[(size_t)i * nsys + s];
                E += ke[(size_t)i * nsys + s] + pe[(size_t)i * nsys + s];
                for (a = 0; a < 3; a++) {
                    Pt[a] += Ps[a];
                    Lt[a] += Ls[a];
                    C[a] += Ms[s] * cs[a] / M;
                }
            }
            /* angular momentum about the total CoM: L_O - C x P */
            Lc[0] = Lt[0] - (C[1] * Pt[2] - C[2] * Pt[1]);
            Lc[1] = Lt[1] - (C[2] * Pt[0] - C[0] * Pt[2]);
            Lc[2] = Lt[2] - (C[0] * Pt[1] - C[1] * Pt[0]);
            for (s = 0; bc && s < nsys; s++) {
                int nb = r->sys[s].nbody, j;
                if (!bc[s]) continue;
                for (j = 0; j < nb; j++) {
                    const cd_h5r_body *bd = r->body + r->sys[s].body_first + j;
                    const double *c = bc[s] + 3 * ((size_t)i * nb + j);
                    d3[0] = c[0] - C[0];
                    d3[1] = c[1] - C[1];
                    d3[2] = c[2] - C[2];
                    J += bd->mass * (d3[0] * d3[0] + d3[1] * d3[1] + d3[2] * d3[2]) + bd->inertia[0] + bd->inertia[4] +
                         bd->inertia[8];
                }
            }
            if (i == 0) {
                E0 = E;
                memcpy(P0, Pt, sizeof P0);
                memcpy(Lc0, Lc, sizeof Lc0);
            }
            if (fabs(E - E0) > dEmax) dEmax = fabs(E - E0);
            if (T > Emax_ke) Emax_ke = T;
            for (a = 0; a < 3; a++) {
                d3[a] = Pt[a] - P0[a];
            }
            if (norm3(d3) > dP) dP = norm3(d3);
            for (a = 0; a < 3; a++) d3[a] = Lc[a] - Lc0[a];
            if (norm3(d3) > dL) dL = norm3(d3);
            if (sqrt(2.0 * M * T) > sP) sP = sqrt(2.0 * M * T);
            if (sqrt(2.0 * T * J) > sL) sL = sqrt(2.0 * T * J);
            if (i == n - 1) {
                snprintf(line, sizeof line, "kinetic + gravitational: E(0) = %.9g J, E(end) = %.9g J, max |E - E(0)| = %.3g J",
                         E0, E, dEmax);
                print_wrapped_kv(out, "energy", line);
                snprintf(line, sizeof line, "(%.3g relative to the largest kinetic energy; contact springs and actuator "
                         "work are not in E)", Emax_ke > 0 ? dEmax / Emax_ke : 0.0);
                print_wrapped_kv(out, "", line);
            }
        }
        v = sP > 0 ? dP / sP : 0.0;
        snprintf(line, sizeof line, "linear: max |P - P(0)| = %.3g kg m/s (%.3g relative to sqrt(2 M T) = %.3g)", dP, v,
                 sP);
        print_wrapped_kv(out, "momentum", line);
        v = sL > 0 ? dL / sL : 0.0;
        snprintf(line, sizeof line,
                 "angular about the CoM: max |L - L(0)| = %.3g kg m^2/s (%.3g relative to sqrt(2 T J) = %.3g)", dL, v, sL);
        print_wrapped_kv(out, "", line);
        if (conserved && !any_fixed)
            print_wrapped_kv(out, "", "(expected to be conserved: free-floating systems, no gravity)");
        else
            print_wrapped_kv(out, "", any_fixed ? "(not expected to be conserved: a system has a fixed base)"
                                                : "(not expected to be conserved: gravity)");
        free(Ms);
    }

    free(title); free(ver); free(created); free(closed); free(spath); free(stext); free(ovr); free(status);
    free(message); free(stepper);
    free(t); free(ke); free(pe); free(P); free(Lo); free(com); free(fn); free(ft); free(mode); free(wall);
    for (s = 0; bc && s < nsys; s++) free(bc[s]);
    free(bc);
    free(ev);
}

int cmd_info(int argc, char **argv)
{
    const char *path = NULL;
    cd_h5r *r;
    cd_error err;
    int i;
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) {
            fputs(info_help, stdout);
            return CLI_OK;
        }
        if (argv[i][0] == '-' && argv[i][1]) return cli_usage("info", "unknown option '%s'", argv[i]);
        if (path) return cli_usage("info", "unexpected argument '%s' (one results file)", argv[i]);
        path = argv[i];
    }
    if (!path) return cli_usage("info", "missing the results file");
    r = cd_h5r_open(path, &err);
    if (!r) {
        cli_error("%s", err.msg);
        return CLI_FAIL;
    }
    /* a file is called readable only if every dataset of it reads (issue 28) */
    if (cd_h5r_verify(r, path, &err) != 0) {
        cli_error("%s", err.msg);
        cd_h5r_close(r);
        return CLI_FAIL;
    }
    cli_report(stdout, r, path, NULL);
    cd_h5r_close(r);
    return CLI_OK;
}
