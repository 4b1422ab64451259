/* capdyn export: whitespace-separated columns for gnuplot and other tools.
 *
 * Every output starts with ONE header line "# name name ..." naming the
 * columns (gnuplot skips it as a comment; `head -1` or gnuplot's
 * system("grep -m1 '^#' FILE") reads the names); further '#' lines describe
 * the data. Time series print one row per selected committed sample. The
 * geometry exports (outline, checkpoints) print one block per frame,
 * frames separated by two blank lines (gnuplot's `index`), and inside an
 * outline block one polyline per part, separated by one blank line (gnuplot
 * `with lines` breaks the line there). docs/cli.md lists the columns. */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "../math/cd_math.h"

#include <libqhull_r/qhull_ra.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static const char *export_help =
    "usage: capdyn export RESULTS.h5 WHAT [options]\n"
    "\n"
    "Writes columns of text to stdout: a header line '# name name ...' first,\n"
    "then one row per committed sample (or per event, slot, frame).\n"
    "\n"
    "WHAT:\n"
    "  time                 t\n"
    "  system NAME          t, base position x y z, quaternion qw qx qy qz,\n"
    "                       base velocity vx vy vz, angular velocity wx wy wz,\n"
    "                       then q.JOINT for each joint and qd.JOINT for each joint\n"
    "  contacts [--active]  t nopen nstick nslip fn_sum, then per slot K:\n"
    "                       fn.K ft.K mode.K (|f_t|; mode 0 open 1 stick 2 slip);\n"
    "                       --active keeps the slots that were ever in contact;\n"
    "                       forces at the samples (the run summary's 'peak fn\n"
    "                       over steps' sees every step: docs/cli.md)\n"
    "  slot N               t fn ftx fty ftz ft x xdot px py pz nx ny nz\n"
    "                       vtx vty vtz vt mode (all of one slot)\n"
    "  slots                the static slot table: slot checkpoint body_a body_b\n"
    "                       shape shape_type cpx cpy cpz radius\n"
    "  events               t kind kind_name slot mode_from mode_to x fn ft body_a body_b\n"
    "                       owner_kind owner (slot, joint, actuator, user, finger)\n"
    "  diagnostics [SYSTEM] t ke pe e de px py pz dp lx ly lz dl cx cy cz\n"
    "                       h nrhs nsteps nrejected nevents wall; totals over all\n"
    "                       systems, or one system's; l about the CoM; d* = change\n"
    "                       since the first sample (|.| for vectors)\n"
    "  outline              links as segments and shapes as outline polygons,\n"
    "                       projected on the view plane: u v part body\n"
    "                       (part 0 link, 1 shape, 2 base-to-joint segment)\n"
    "  checkpoints          u v r mode x y z t cp body (mode: 0 open, 1 stick,\n"
    "                       2 slip, the highest of the check point's slots)\n"
    "  edges                3-D wireframe: x y z part body (links, shape edges)\n"
    "  forces               contacts in contact per frame: x y z fx fy fz fn ft\n"
    "                       mode slot between body_a body_b t (force on the shape's\n"
    "                       body; between: 1 if the two bodies' systems differ)\n"
    "  gltf                 binary glTF 2.0 (GLB) of the run: one node per body\n"
    "                       with its shapes, check points and links as a mesh,\n"
    "                       the poses as an animation; capdyn export run.h5 gltf > run.glb\n"
    "\n"
    "options:\n"
    "  --every K            every K-th sample (time series default: all)\n"
    "  --frames N           N samples evenly spaced, first and last included\n"
    "  --at T[,T...]        the samples nearest to these times [s] ('end': the\n"
    "                       last committed sample)\n"
    "                       (outline/checkpoints default: the last sample)\n"
    "  --view xy|xz|yz      projection plane of outline/checkpoints (default xy)\n"
    "  --frame BODY         outline/checkpoints/edges/forces in the frame of BODY\n"
    "                       (its full name system/body, or a system name: its base)\n"
    "  --precision P        significant digits (default 10)\n"
    "  --active             (contacts) only slots ever in contact\n";

typedef struct {
    const char *path, *what, *arg;
    long every, frames;
    const char *at;
    int view_u, view_v, prec, active;
    const char *frame; /* --frame BODY: geometry in that body's frame */
    int frame_body;    /* its id, -1 world */
} exp_opts;

typedef struct {
    const cd_h5r *r;
    exp_opts *o;
    long *sel;   /* selected sample indices */
    long nsel;
    double *t;
    int nerr;             /* errors reported: only the first is printed (one error line) */
} exp_ctx;

static void num(double v, int prec)
{
    if (isnan(v)) fputs(" nan", stdout);
    else printf(" %.*g", prec, v);
}
static void num0(double v, int prec)
{
    if (isnan(v)) fputs("nan", stdout);
    else printf("%.*g", prec, v);
}
/* a name as one whitespace-free token */
static void token(const char *s)
{
    if (!*s) { fputs("-", stdout); return; }
    for (; *s; s++) putchar((*s == ' ' || *s == '\t' || *s == '\n') ? '_' : *s);
}
static double nrm3(const double *a) { return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

static double *series(exp_ctx *c, const char *path)
{
    cd_error err;
    double *v = cd_h5r_series(c->r, path, NULL, &err);
    if (!v && c->nerr++ == 0) cli_error("%s", err.msg); /* the first failure names the file's fault */
    return v;
}

/* ---- sample selection ------------------------------------------------------ */
static int select_samples(exp_ctx *c, int geometry)
{
    long n = c->r->n, i, k;
    exp_opts *o = c->o;
    c->sel = malloc((size_t)(n > 0 ? n : 1) * sizeof *c->sel + 64 * sizeof *c->sel);
    c->nsel = 0;
    if (!c->sel) return -1;
    if (n == 0) return 0;
    if (o->at) {
        const char *p = o->at;
        long cap = n + 64;
        while (*p) {
            char *end;
            double tt;
            long best = 0;
            if (strncmp(p, "end", 3) == 0) {
                /* "end": the last committed sample */
                end = (char *)p + 3;
                best = n - 1;
            } else {
                tt = strtod(p, &end);
                if (end == p || !isfinite(tt)) return -2;
                for (i = 1; i < n; i++)
                    if (fabs(c->t[i] - tt) < fabs(c->t[best] - tt)) best = i;
            }
            if (c->nsel >= cap) return -2;
            c->sel[c->nsel++] = best;
            p = end;
            if (*p == ',') p++;
            else if (*p) return -2;
        }
    } else if (o->frames > 0) {
        long N = o->frames < n ? o->frames : n;
        for (k = 0; k < N; k++) c->sel[c->nsel++] = N == 1 ? n - 1 : (long)floor((double)k * (double)(n - 1) / (double)(N - 1) + 0.5);
    } else if (o->every > 0) {
        for (i = 0; i < n; i += o->every) c->sel[c->nsel++] = i;
    } else if (geometry) {
        c->sel[c->nsel++] = n - 1;
    } else {
        for (i = 0; i < n; i++) c->sel[c->nsel++] = i;
    }
    return 0;
}

/* ---- time series exports ----------------------------------------------------- */
static int ex_time(exp_ctx *c)
{
    long j;
    puts("# t");
    for (j = 0; j < c->nsel; j++) {
        num0(c->t[c->sel[j]], c->o->prec);
        putchar('\n');
    }
    return CLI_OK;
}

static int ex_system(exp_ctx *c)
{
    const cd_h5r *r = c->r;
    int s = cd_h5r_system(r, c->o->arg), nj, k, p = c->o->prec;
    char path[512];
    double *pos, *quat, *vel, *av, *q = NULL, *qd = NULL;
    long j;
    if (s < 0) {
        cli_error("no system '%s' in %s (systems:%s%s%s%s)", c->o->arg, c->o->path, r->nsys > 0 ? " " : "",
                  r->nsys > 0 ? r->sys[0].name : "", r->nsys > 1 ? ", " : "", r->nsys > 1 ? r->sys[1].name : "");
        return CLI_FAIL;
    }
    nj = r->sys[s].njoint;
#define LOAD(var, name)                                                        \
    snprintf(path, sizeof path, "/systems/%s/" name, r->sys[s].group);         \
    var = series(c, path)
    LOAD(pos, "base_pos");
    LOAD(quat, "base_quat");
    LOAD(vel, "base_vel");
    LOAD(av, "base_angvel");
    if (nj > 0) {
        LOAD(q, "q");
        LOAD(qd, "qd");
    }
#undef LOAD
    if (!pos || !quat || !vel || !av || (nj > 0 && (!q || !qd))) {
        free(pos); free(quat); free(vel); free(av); free(q); free(qd);
        return CLI_FAIL;
    }
    fputs("# t x y z qw qx qy qz vx vy vz wx wy wz", stdout);
    for (k = 0; k < nj; k++) { fputs(" q.", stdout); token(r->body[r->sys[s].body_first + 1 + k].name); }
    for (k = 0; k < nj; k++) { fputs(" qd.", stdout); token(r->body[r->sys[s].body_first + 1 + k].name); }
    printf("\n# system %s (%s base); units m, rad, m/s, rad/s; quaternion body -> world\n", r->sys[s].name,
           r->sys[s].base_free ? "free-floating" : "fixed");
    for (j = 0; j < c->nsel; j++) {
        long i = c->sel[j];
        num0(c->t[i], p);
        for (k = 0; k < 3; k++) num(pos[3 * i + k], p);
        for (k = 0; k < 4; k++) num(quat[4 * i + k], p);
        for (k = 0; k < 3; k++) num(vel[3 * i + k], p);
        for (k = 0; k < 3; k++) num(av[3 * i + k], p);
        for (k = 0; k < nj; k++) num(q[(size_t)i * nj + k], p);
        for (k = 0; k < nj; k++) num(qd[(size_t)i * nj + k], p);
        putchar('\n');
    }
    free(pos); free(quat); free(vel); free(av); free(q); free(qd);
    return CLI_OK;
}

static void slot_comment(const cd_h5r *r, int k)
{
    const cd_h5r_slot *s = r->slot + k;
    printf("# slot %d: %s check point %d -> %s (%s)\n", k, s->body_a_name, s->checkpoint, s->body_b_name, s->shape_type);
}

static int ex_contacts(exp_ctx *c)
{
    const cd_h5r *r = c->r;
    int ns = r->nslot, k, p = c->o->prec, *use;
    double *fn, *ft, *mode;
    long j, i;
    if (ns == 0) {
        puts("# t nopen nstick nslip fn_sum");
        puts("# the model has no contact slots");
        for (j = 0; j < c->nsel; j++) {
            num0(c->t[c->sel[j]], p);
            puts(" 0 0 0 0");
        }
        return CLI_OK;
    }
    fn = series(c, "/contacts/fn");
    ft = series(c, "/contacts/ft");
    mode = series(c, "/contacts/mode");
    use = calloc((size_t)ns, sizeof *use);
    if (!fn || !ft || !mode || !use) {
        free(fn); free(ft); free(mode); free(use);
        return CLI_FAIL;
    }
    for (k = 0; k < ns; k++) {
        use[k] = !c->o->active;
        for (i = 0; !use[k] && i < r->n; i++)
            if (fn[(size_t)i * ns + k] != 0 || mode[(size_t)i * ns + k] != 0) use[k] = 1;
    }
    fputs("# t nopen nstick nslip fn_sum", stdout);
    for (k = 0; k < ns; k++)
        if (use[k]) printf(" fn.%d ft.%d mode.%d", k, k, k);
    putchar('\n');
    puts("# forces [N] at the samples, not between them (ft = |tangential force|); mode 0 open, 1 stick, 2 slip");
    for (k = 0; k < ns; k++)
        if (use[k]) slot_comment(r, k);
    for (j = 0; j < c->nsel; j++) {
        int cnt[3] = {0, 0, 0};
        double sum = 0;
        i = c->sel[j];
        for (k = 0; k < ns; k++) {
            int mo = (int)mode[(size_t)i * ns + k];
            if (mo >= 0 && mo <= 2) cnt[mo]++;
            sum += fn[(size_t)i * ns + k];
        }
        num0(c->t[i], p);
        printf(" %d %d %d", cnt[0], cnt[1], cnt[2]);
        num(sum, p);
        for (k = 0; k < ns; k++)
            if (use[k]) {
                num(fn[(size_t)i * ns + k], p);
                num(nrm3(ft + 3 * ((size_t)i * ns + k)), p);
                printf(" %d", (int)mode[(size_t)i * ns + k]);
            }
        putchar('\n');
    }
    free(fn); free(ft); free(mode); free(use);
    return CLI_OK;
}

static int ex_slot(exp_ctx *c)
{
    const cd_h5r *r = c->r;
    int ns = r->nslot, p = c->o->prec, a;
    long k, j;
    double *fn, *ft, *x, *xd, *pt, *nm, *vt, *mode;
    if (cli_count(c->o->arg, &k) || k >= ns) {
        cli_error("slot '%s' does not exist (the file has %d slot%s: 0 .. %d)", c->o->arg, ns, ns == 1 ? "" : "s", ns - 1);
        return CLI_FAIL;
    }
    fn = series(c, "/contacts/fn");
    ft = series(c, "/contacts/ft");
    x = series(c, "/contacts/penetration");
    xd = series(c, "/contacts/penetration_rate");
    pt = series(c, "/contacts/point");
    nm = series(c, "/contacts/normal");
    vt = series(c, "/contacts/slip_velocity");
    mode = series(c, "/contacts/mode");
    if (fn && ft && x && xd && pt && nm && vt && mode) {
        puts("# t fn ftx fty ftz ft x xdot px py pz nx ny nz vtx vty vtz vt mode");
        slot_comment(r, (int)k);
        puts("# N, m, m/s, at the samples; f_t on the check-point body; normal from the shape toward the check point");
        for (j = 0; j < c->nsel; j++) {
            size_t i = (size_t)c->sel[j], o = i * (size_t)ns + (size_t)k;
            num0(c->t[i], p);
            num(fn[o], p);
            for (a = 0; a < 3; a++) num(ft[3 * o + a], p);
            num(nrm3(ft + 3 * o), p);
            num(x[o], p);
            num(xd[o], p);
            for (a = 0; a < 3; a++) num(pt[3 * o + a], p);
            for (a = 0; a < 3; a++) num(nm[3 * o + a], p);
            for (a = 0; a < 3; a++) num(vt[3 * o + a], p);
            num(nrm3(vt + 3 * o), p);
            printf(" %d\n", (int)mode[o]);
        }
    }
    free(fn); free(ft); free(x); free(xd); free(pt); free(nm); free(vt); free(mode);
    return fn && ft && x && xd && pt && nm && vt && mode ? CLI_OK : CLI_FAIL;
}

static int ex_slots(exp_ctx *c)
{
    const cd_h5r *r = c->r;
    int k, p = c->o->prec;
    puts("# slot checkpoint body_a body_b shape shape_type cpx cpy cpz radius");
    puts("# check point position in the body frame [m]; body names system/body");
    for (k = 0; k < r->nslot; k++) {
        const cd_h5r_slot *s = r->slot + k;
        const cd_h5r_cp *cp = s->checkpoint >= 0 && s->checkpoint < r->ncp ? r->cp + s->checkpoint : NULL;
        printf("%d %d ", k, s->checkpoint);
        token(s->body_a_name);
        putchar(' ');
        token(s->body_b_name);
        printf(" %d ", s->shape);
        token(s->shape_type);
        num(cp ? cp->pos[0] : NAN, p);
        num(cp ? cp->pos[1] : NAN, p);
        num(cp ? cp->pos[2] : NAN, p);
        num(cp ? cp->radius : NAN, p);
        putchar('\n');
    }
    return CLI_OK;
}

static int ex_events(exp_ctx *c)
{
    const cd_h5r *r = c->r;
    cd_error err;
    long n, i;
    int p = c->o->prec;
    cd_event *ev = cd_h5r_events(r, &n, &err);
    if (!ev) {
        cli_error("%s", err.msg);
        return CLI_FAIL;
    }
    puts("# t kind kind_name slot mode_from mode_to x fn ft body_a body_b owner_kind owner");
    printf("# %ld events; kinds:", n);
    for (i = 0; i < CD_EV_NKINDS; i++) printf(" %ld %s", i, cd_event_kind_name((cd_event_kind)i));
    puts("; modes 0 open 1 stick 2 slip; x [m], fn and ft [N] just before the switch");
    if (r->ev_lost > 0) printf("# %lld events were lost from the event ring before they could be written\n", r->ev_lost);
    for (i = 0; i < n; i++) {
        const cd_event *e = ev + i;
        num0(e->t, p);
        printf(" %d %s %d %d %d", e->kind, cd_event_kind_name((cd_event_kind)e->kind), e->slot, e->mode_from, e->mode_to);
        num(e->x, p);
        num(e->fn, p);
        num(e->ft, p);
        putchar(' ');
        if (e->body_a >= 0 && e->body_a < r->nbody) token(r->body[e->body_a].full_name);
        else putchar('-');
        putchar(' ');
        if (e->body_b >= 0 && e->body_b < r->nbody) token(r->body[e->body_b].full_name);
        else putchar('-');
        printf(" %s %d\n", cd_owner_kind_name((cd_owner_kind)e->owner_kind), e->owner);
    }
    free(ev);
    return CLI_OK;
}

static int ex_diagnostics(exp_ctx *c)
{
    const cd_h5r *r = c->r;
    int ns = r->nsys, s0 = 0, s1 = ns, s, a, b, p = c->o->prec;
    double *ke = series(c, "/diagnostics/kinetic_energy"), *pe = series(c, "/diagnostics/potential_energy");
    double *P = series(c, "/diagnostics/momentum"), *Lo = series(c, "/diagnostics/angular_momentum_origin");
    double *com = series(c, "/diagnostics/com"), *h = series(c, "/diagnostics/step_size");
    double *nrhs = series(c, "/diagnostics/nrhs"), *nst = series(c, "/diagnostics/nsteps");
    double *nrej = series(c, "/diagnostics/nrejected"), *nev = series(c, "/diagnostics/nevents");
    double *wall = series(c, "/diagnostics/wall_time"), *Ms = calloc((size_t)(ns ? ns : 1), sizeof *Ms);
    double E0 = 0, P0[3] = {0, 0, 0}, L0[3] = {0, 0, 0}, M = 0;
    long j;
    int rc = CLI_OK;
    if (!ke || !pe || !P || !Lo || !com || !h || !nrhs || !nst || !nrej || !nev || !wall || !Ms) { rc = CLI_FAIL; goto out; }
    if (c->o->arg) {
        s0 = cd_h5r_system(r, c->o->arg);
        if (s0 < 0) {
            cli_error("no system '%s' in %s", c->o->arg, c->o->path);
            rc = CLI_FAIL;
            goto out;
        }
        s1 = s0 + 1;
    }
    for (s = s0; s < s1; s++) {
        for (b = r->sys[s].body_first; b < r->sys[s].body_first + r->sys[s].nbody && b < r->nbody; b++)
            Ms[s] += r->body[b].mass;
        M += Ms[s];
    }
    puts("# t ke pe e de px py pz dp lx ly lz dl cx cy cz h nrhs nsteps nrejected nevents wall");
    printf("# %s; J, kg m/s, kg m^2/s (l about the CoM), m, s; d* = change since the first sample\n",
           c->o->arg ? c->o->arg : "all systems");
    if (r->n == 0) goto out; /* no committed sample: no reference either */
    for (j = 0; j < c->nsel + 1; j++) {
        /* j == 0 computes the reference (first committed sample) silently */
        long i = j == 0 ? 0 : c->sel[j - 1];
        double T = 0, U = 0, Pt[3] = {0, 0, 0}, Lt[3] = {0, 0, 0}, C[3] = {0, 0, 0}, Lc[3], d3[3];
        for (s = s0; s < s1; s++) {
            size_t o = (size_t)i * (size_t)ns + (size_t)s;
            T += ke[o];
            U += pe[o];
            for (a = 0; a < 3; a++) {
                Pt[a] += P[3 * o + a];
                Lt[a] += Lo[3 * o + a];
                C[a] += M > 0 ? Ms[s] * com[3 * o + a] / M : 0.0;
            }
        }
        Lc[0] = Lt[0] - (C[1] * Pt[2] - C[2] * Pt[1]);
        Lc[1] = Lt[1] - (C[2] * Pt[0] - C[0] * Pt[2]);
        Lc[2] = Lt[2] - (C[0] * Pt[1] - C[1] * Pt[0]);
        if (j == 0) {
            E0 = T + U;
            memcpy(P0, Pt, sizeof P0);
            memcpy(L0, Lc, sizeof L0);
            continue;
        }
        num0(c->t[i], p);
        num(T, p);
        num(U, p);
        num(T + U, p);
        num(T + U - E0, p);
        for (a = 0; a < 3; a++) num(Pt[a], p);
        for (a = 0; a < 3; a++) d3[a] = Pt[a] - P0[a];
        num(nrm3(d3), p);
        for (a = 0; a < 3; a++) num(Lc[a], p);
        for (a = 0; a < 3; a++) d3[a] = Lc[a] - L0[a];
        num(nrm3(d3), p);
        for (a = 0; a < 3; a++) num(C[a], p);
        num(h[i], p);
        printf(" %.0f %.0f %.0f %.0f", nrhs[i], nst[i], nrej[i], nev[i]);
        num(wall[i], p);
        putchar('\n');
    }
out:
    free(ke); free(pe); free(P); free(Lo); free(com); free(h); free(nrhs); free(nst); free(nrej); free(nev);
    free(wall); free(Ms);
    return rc;
}

/* ---- geometry ------------------------------------------------------------------- */
typedef struct {
    double *X, *R;   /* (nbody x 3), (nbody x 9) of the current frame */
    double **bx, **bq;
    int frame;       /* --frame: poses relative to this body (-1: world) */
    double fX[3], fR[9]; /* that body's world pose at the current sample */
} pose_set;

static void pose_frame(const cd_h5r *r, pose_set *ps, long i)
{
    int s, j;
    for (s = 0; s < r->nsys; s++) {
        int nb = r->sys[s].nbody, b0 = r->sys[s].body_first;
        for (j = 0; j < nb; j++) {
            const double *x = ps->bx[s] + 3 * ((size_t)i * nb + j), *q = ps->bq[s] + 4 * ((size_t)i * nb + j);
            memcpy(ps->X + 3 * (b0 + j), x, 3 * sizeof(double));
            cd_quat_to_m3(ps->R + 9 * (b0 + j), q);
        }
    }
    cd_m3_identity(ps->fR);
    ps->fX[0] = ps->fX[1] = ps->fX[2] = 0;
    if (ps->frame >= 0 && ps->frame < r->nbody) {
        /* every pose relative to the frame body: X' = Rf^T (X - Xf), R' = Rf^T R */
        int b, k;
        memcpy(ps->fX, ps->X + 3 * ps->frame, sizeof ps->fX);
        memcpy(ps->fR, ps->R + 9 * ps->frame, sizeof ps->fR);
        for (b = 0; b < r->nbody; b++) {
            double d[3], Rt[9], col[3], out[3];
            cd_v3_sub(d, ps->X + 3 * b, ps->fX);
            cd_m3_tmulv(ps->X + 3 * b, ps->fR, d);
            memcpy(Rt, ps->R + 9 * b, sizeof Rt);
            for (k = 0; k < 3; k++) { /* column by column */
                col[0] = Rt[k]; col[1] = Rt[3 + k]; col[2] = Rt[6 + k];
                cd_m3_tmulv(out, ps->fR, col);
                ps->R[9 * b + k] = out[0]; ps->R[9 * b + 3 + k] = out[1]; ps->R[9 * b + 6 + k] = out[2];
            }
        }
    }
}
/* a world point / vector into the --frame body's frame (identity without it) */
/* the largest side of the box around every body's origin at that pose, at
 * least 0.1 m: the size of the drawn shape outlines and planes */
static double pose_extent(const cd_h5r *r, const pose_set *ps)
{
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL}, extent = 0;
    int b, k;
    for (b = 0; b < r->nbody; b++)
        for (k = 0; k < 3; k++) {
            if (ps->X[3 * b + k] < lo[k]) lo[k] = ps->X[3 * b + k];
            if (ps->X[3 * b + k] > hi[k]) hi[k] = ps->X[3 * b + k];
        }
    for (k = 0; k < 3; k++)
        if (r->nbody > 0 && hi[k] - lo[k] > extent) extent = hi[k] - lo[k];
    return extent < 0.1 ? 0.1 : extent;
}

static void frame_point(const pose_set *ps, const double w[3], double p[3])
{
    double d[3];
    cd_v3_sub(d, w, ps->fX);
    cd_m3_tmulv(p, ps->fR, d);
}
static void frame_vec(const pose_set *ps, const double w[3], double v[3]) { cd_m3_tmulv(v, ps->fR, w); }

static void to_world(const pose_set *ps, int b, const double p[3], double w[3])
{
    cd_m3_mulv(w, ps->R + 9 * b, p);
    cd_v3_add(w, w, ps->X + 3 * b);
}

static int cmp2(const void *a, const void *b)
{
    const double *p = (const double *)a, *q = (const double *)b;
    if (p[0] != q[0]) return p[0] < q[0] ? -1 : 1;
    if (p[1] != q[1]) return p[1] < q[1] ? -1 : 1;
    return 0;
}
static double cross2(const double *o, const double *a, const double *b)
{ return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]); }

/* Andrew's monotone chain: hull of n 2-D points (in place sorted); writes the
 * hull (counter-clockwise) into h (room for 2n points), returns its size. */
static int hull2(double *pts, int n, double *h)
{
    int k = 0, i, t;
    if (n < 3) {
        memcpy(h, pts, (size_t)n * 2 * sizeof(double));
        return n;
    }
    qsort(pts, (size_t)n, 2 * sizeof(double), cmp2);
    for (i = 0; i < n; i++) {
        while (k >= 2 && cross2(h + 2 * (k - 2), h + 2 * (k - 1), pts + 2 * i) <= 0) k--;
        h[2 * k] = pts[2 * i];
        h[2 * k + 1] = pts[2 * i + 1];
        k++;
    }
    for (i = n - 2, t = k + 1; i >= 0; i--) {
        while (k >= t && cross2(h + 2 * (k - 2), h + 2 * (k - 1), pts + 2 * i) <= 0) k--;
        h[2 * k] = pts[2 * i];
        h[2 * k + 1] = pts[2 * i + 1];
        k++;
    }
    return k - 1;
}

#define NCIRC 48

static void put_uv(exp_ctx *c, double u, double v, int part, int body)
{
    num0(u, c->o->prec);
    num(v, c->o->prec);
    printf(" %d %d\n", part, body);
}

static void put_seg(exp_ctx *c, const double *a, const double *b, int part, int body)
{
    put_uv(c, a[c->o->view_u], a[c->o->view_v], part, body);
    put_uv(c, b[c->o->view_u], b[c->o->view_v], part, body);
    putchar('\n');
}

/* a closed polygon through the hull of the projected points */
static void put_hull(exp_ctx *c, double *pts, int n, int body)
{
    double *h = malloc((size_t)(2 * n + 2) * 2 * sizeof(double));
    int m, i;
    if (!h) return;
    m = hull2(pts, n, h);
    for (i = 0; i <= m && m > 0; i++) put_uv(c, h[2 * (i % m)], h[2 * (i % m) + 1], 1, body);
    putchar('\n');
    free(h);
}

static void shape_outline(exp_ctx *c, const pose_set *ps, int k, double extent)
{
    const cd_h5r *r = c->r;
    const cd_h5r_shape *sh = r->shape + k;
    int u = c->o->view_u, v = c->o->view_v, i, n = 0;
    double *pts = malloc((size_t)(4 * NCIRC + 16 + (sh->vert_num > 0 ? sh->vert_num : 0)) * 2 * sizeof(double));
    double loc[3], w[3], ctr[3], Rw[9];
    if (!pts) return;
    /* shape frame -> world: X_b + R_b (pos + rot p) */
    cd_m3_mul(Rw, ps->R + 9 * sh->body, sh->rot);
    to_world(ps, sh->body, sh->pos, ctr);
#define ADD_LOCAL(px, py, pz)                                                  \
    do {                                                                       \
        loc[0] = (px); loc[1] = (py); loc[2] = (pz);                           \
        cd_m3_mulv(w, Rw, loc);                                                \
        pts[2 * n] = ctr[u] + w[u];                                            \
        pts[2 * n + 1] = ctr[v] + w[v];                                        \
        n++;                                                                   \
    } while (0)
    switch (sh->type) {
    case CD_SHAPE_SPHERE:
    case CD_SHAPE_CAPSULE: {
        /* the projection of a sphere is a circle: of each end sphere */
        int ends = sh->type == CD_SHAPE_SPHERE ? 1 : 2, e;
        for (e = 0; e < ends; e++) {
            double z = ends == 1 ? 0.0 : (e ? sh->size[1] : -sh->size[1]);
            loc[0] = 0; loc[1] = 0; loc[2] = z;
            cd_m3_mulv(w, Rw, loc);
            for (i = 0; i < NCIRC; i++) {
                double a = 2.0 * CD_PI * i / NCIRC;
                pts[2 * n] = ctr[u] + w[u] + sh->size[0] * cos(a);
                pts[2 * n + 1] = ctr[v] + w[v] + sh->size[0] * sin(a);
                n++;
            }
        }
        break;
    }
    case CD_SHAPE_CYLINDER:
        for (i = 0; i < NCIRC; i++) {
            double a = 2.0 * CD_PI * i / NCIRC;
            ADD_LOCAL(sh->size[0] * cos(a), sh->size[0] * sin(a), -sh->size[1]);
            ADD_LOCAL(sh->size[0] * cos(a), sh->size[0] * sin(a), sh->size[1]);
        }
        break;
    case CD_SHAPE_BOX:
        for (i = 0; i < 8; i++)
            ADD_LOCAL((i & 1 ? 1 : -1) * sh->size[0], (i & 2 ? 1 : -1) * sh->size[1], (i & 4 ? 1 : -1) * sh->size[2]);
        break;
    case CD_SHAPE_CONVEX:
        for (i = 0; i < sh->vert_num && sh->vert_adr + i < r->nvert; i++) {
            const double *vv = r->vert + 3 * (sh->vert_adr + i);
            ADD_LOCAL(vv[0], vv[1], vv[2]);
        }
        break;
    case CD_SHAPE_PLANE: {
        /* the trace of the boundary plane on the view, with ticks on the solid side */
        double nz[3] = {0, 0, 1}, nw[3], du, dv, len, tu, tv;
        cd_m3_mulv(nw, Rw, nz);
        du = nw[u];
        dv = nw[v];
        len = sqrt(du * du + dv * dv);
        if (len < 0.05) break; /* the plane is (nearly) the view plane itself */
        du /= len;
        dv /= len;
        tu = -dv;
        tv = du;
        put_uv(c, ctr[u] - extent * tu, ctr[v] - extent * tv, 1, sh->body);
        put_uv(c, ctr[u] + extent * tu, ctr[v] + extent * tv, 1, sh->body);
        putchar('\n');
        for (i = -10; i <= 10; i++) {
            double su = ctr[u] + 0.1 * i * extent * tu, sv = ctr[v] + 0.1 * i * extent * tv;
            put_uv(c, su, sv, 1, sh->body);
            put_uv(c, su - 0.04 * extent * (du + tu), sv - 0.04 * extent * (dv + tv), 1, sh->body);
            putchar('\n');
        }
        break;
    }
    default:
        break;
    }
#undef ADD_LOCAL
    if (n > 0) put_hull(c, pts, n, sh->body);
    free(pts);
}

static int load_poses(exp_ctx *c, pose_set *ps)
{
    const cd_h5r *r = c->r;
    int s;
    char path[512];
    ps->X = calloc((size_t)(r->nbody ? r->nbody : 1) * 3, sizeof(double));
    ps->R = calloc((size_t)(r->nbody ? r->nbody : 1) * 9, sizeof(double));
    ps->bx = calloc((size_t)(r->nsys ? r->nsys : 1), sizeof *ps->bx);
    ps->bq = calloc((size_t)(r->nsys ? r->nsys : 1), sizeof *ps->bq);
    ps->frame = c->o->frame_body;
    if (!ps->X || !ps->R || !ps->bx || !ps->bq) return -1;
    for (s = 0; s < r->nsys; s++) {
        snprintf(path, sizeof path, "/systems/%s/body_x", r->sys[s].group);
        ps->bx[s] = series(c, path);
        snprintf(path, sizeof path, "/systems/%s/body_quat", r->sys[s].group);
        ps->bq[s] = series(c, path);
        if (!ps->bx[s] || !ps->bq[s]) return -1;
    }
    return 0;
}

static void free_poses(const cd_h5r *r, pose_set *ps)
{
    int s;
    for (s = 0; s < r->nsys; s++) {
        if (ps->bx) free(ps->bx[s]);
        if (ps->bq) free(ps->bq[s]);
    }
    free(ps->bx);
    free(ps->bq);
    free(ps->X);
    free(ps->R);
}

static int ex_outline(exp_ctx *c)
{
    const cd_h5r *r = c->r;
    pose_set ps;
    long j;
    int b, k, rc = CLI_OK;
    memset(&ps, 0, sizeof ps);
    if (load_poses(c, &ps) < 0) {
        free_poses(r, &ps);
        return CLI_FAIL;
    }
    puts("# u v part body");
    printf("# view %c%c; part 0 link, 1 shape outline, 2 base-to-joint segment; one block per frame (gnuplot index)\n",
           "xyz"[c->o->view_u], "xyz"[c->o->view_v]);
    for (j = 0; j < c->nsel; j++) {
        long i = c->sel[j];
        double extent;
        pose_frame(r, &ps, i);
        extent = pose_extent(r, &ps);
        if (j > 0) fputs("\n\n", stdout);
        printf("# frame %ld sample %ld t %.9g\n", j, i, c->t[i]);
        for (b = 0; b < r->nbody; b++) {
            int ch, nchild = 0, q, has_shape = 0;
            for (q = 0; q < r->nshape; q++)
                if (r->shape[q].body == b) has_shape = 1;
            for (ch = b + 1; ch < r->nbody; ch++)
                if (r->body[ch].parent == b) {
                    /* a base drawn by its own shape needs no spokes to its joints */
                    if (r->body[b].parent >= 0 || !has_shape) put_seg(c, ps.X + 3 * b, ps.X + 3 * ch, r->body[b].parent < 0 ? 2 : 0, b);
                    nchild++;
                }
            if (nchild == 0 && r->body[b].parent >= 0) {
                /* a tip link: to its farthest check point, else capsule end, else twice the CoM */
                double tip[3] = {0, 0, 0}, best = 0, w[3];
                int q;
                for (q = 0; q < r->ncp; q++)
                    if (r->cp[q].body == b && nrm3(r->cp[q].pos) > best) {
                        best = nrm3(r->cp[q].pos);
                        memcpy(tip, r->cp[q].pos, sizeof tip);
                    }
                if (best == 0)
                    for (q = 0; q < r->nshape; q++)
                        if (r->shape[q].body == b && r->shape[q].type == CD_SHAPE_CAPSULE) {
                            double e[3] = {0, 0, r->shape[q].size[1]}, pe[3];
                            cd_m3_mulv(pe, r->shape[q].rot, e);
                            cd_v3_add(pe, pe, r->shape[q].pos);
                            if (nrm3(pe) > best) { best = nrm3(pe); memcpy(tip, pe, sizeof tip); }
                            e[2] = -e[2];
                            cd_m3_mulv(pe, r->shape[q].rot, e);
                            cd_v3_add(pe, pe, r->shape[q].pos);
                            if (nrm3(pe) > best) { best = nrm3(pe); memcpy(tip, pe, sizeof tip); }
                        }
                if (best == 0) cd_v3_scale(tip, r->body[b].com, 2.0);
                if (nrm3(tip) > 0) {
                    to_world(&ps, b, tip, w);
                    put_seg(c, ps.X + 3 * b, w, 0, b);
                }
            }
        }
        for (k = 0; k < r->nshape; k++) shape_outline(c, &ps, k, extent);
    }
    free_poses(r, &ps);
    return rc;
}

static int ex_checkpoints(exp_ctx *c)
{
    const cd_h5r *r = c->r;
    pose_set ps;
    double *mode = NULL;
    long j;
    int q, k, p = c->o->prec;
    memset(&ps, 0, sizeof ps);
    if (load_poses(c, &ps) < 0 || (r->nslot > 0 && !(mode = series(c, "/contacts/mode")))) {
        free_poses(r, &ps);
        free(mode);
        return CLI_FAIL;
    }
    puts("# u v r mode x y z t cp body");
    printf("# view %c%c; mode 0 open, 1 stick, 2 slip (highest over the check point's slots); one block per frame\n",
           "xyz"[c->o->view_u], "xyz"[c->o->view_v]);
    for (j = 0; j < c->nsel; j++) {
        long i = c->sel[j];
        pose_frame(r, &ps, i);
        if (j > 0) fputs("\n\n", stdout);
        printf("# frame %ld sample %ld t %.9g\n", j, i, c->t[i]);
        for (q = 0; q < r->ncp; q++) {
            double w[3];
            int mo = 0;
            to_world(&ps, r->cp[q].body, r->cp[q].pos, w);
            for (k = 0; k < r->nslot; k++)
                if (r->slot[k].checkpoint == q && mode[(size_t)i * r->nslot + k] > mo) mo = (int)mode[(size_t)i * r->nslot + k];
            num0(w[c->o->view_u], p);
            num(w[c->o->view_v], p);
            num(r->cp[q].radius, p);
            printf(" %d", mo);
            num(w[0], p);
            num(w[1], p);
            num(w[2], p);
            num(c->t[i], p);
            printf(" %d %d\n", q, r->cp[q].body);
        }
        if (r->ncp == 0) {
            fputs("nan nan 0 0 nan nan nan", stdout);
            num(c->t[i], p);
            puts(" -1 -1");
        }
    }
    free(mode);
    free_poses(r, &ps);
    return CLI_OK;
}

/* ---- glTF 2.0 binary (GLB) ------------------------------------------------------ *
 * One node per body (children of a root node that turns capdyn's z-up world
 * into glTF's y-up), its shapes, check points and link rods as one mesh in
 * the body frame (flat-shaded triangles), the poses of the selected samples
 * as one animation: a LINEAR translation and rotation sampler per body.
 * Written by hand: a 12-byte header, a JSON chunk, a BIN chunk
 * (docs/results-format.md, "glTF export"). */
typedef struct {
    unsigned char *p;
    size_t n, cap;
    int oom;
} gl_buf;

static void gb_bytes(gl_buf *b, const void *src, size_t n)
{
    if (b->oom) return;
    if (b->n + n > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        unsigned char *q;
        while (cap < b->n + n) cap *= 2;
        q = realloc(b->p, cap);
        if (!q) { b->oom = 1; return; }
        b->p = q;
        b->cap = cap;
    }
    memcpy(b->p + b->n, src, n);
    b->n += n;
}
/* a little-endian uint32 / float32, whatever the host's byte order */
static void gb_u32(gl_buf *b, unsigned long v)
{
    unsigned char c[4];
    c[0] = (unsigned char)(v & 0xff); c[1] = (unsigned char)((v >> 8) & 0xff);
    c[2] = (unsigned char)((v >> 16) & 0xff); c[3] = (unsigned char)((v >> 24) & 0xff);
    gb_bytes(b, c, 4);
}
static void gb_f32(gl_buf *b, float f)
{
    unsigned long u;
    unsigned int w;
    memcpy(&w, &f, 4); /* float is IEEE 754 binary32 on every platform capdyn builds on */
    u = w;
    gb_u32(b, u);
}

/* triangles (9 doubles each, body frame) of one primitive */
typedef struct {
    double *v;
    size_t n, cap;
    int oom;
} gl_tris;

typedef struct { double R[9], p[3]; } gl_xf; /* local -> body frame */

static void tri_add(gl_tris *m, const gl_xf *X, const double a[3], const double b[3], const double c[3])
{
    double w[9], e1[3], e2[3], n[3];
    int k;
    const double *pt[3];
    pt[0] = a; pt[1] = b; pt[2] = c;
    if (m->oom) return;
    for (k = 0; k < 3; k++) {
        cd_m3_mulv(w + 3 * k, X->R, pt[k]);
        cd_v3_add(w + 3 * k, w + 3 * k, X->p);
    }
    cd_v3_sub(e1, w + 3, w);
    cd_v3_sub(e2, w + 6, w);
    cd_v3_cross(n, e1, e2);
    /* degenerate (the pole of a sphere, a zero radius): no triangle; float32 area too */
    if (!(nrm3(n) > 1e-12 * (cd_v3_dot(e1, e1) + cd_v3_dot(e2, e2))) || !(nrm3(n) > 1e-14)) return;
    if (m->n + 1 > m->cap) {
        size_t cap = m->cap ? 2 * m->cap : 256;
        double *q = realloc(m->v, cap * 9 * sizeof *q);
        if (!q) { m->oom = 1; return; }
        m->v = q;
        m->cap = cap;
    }
    memcpy(m->v + 9 * m->n, w, sizeof w);
    m->n++;
}

/* a surface of revolution about local z: nring rings (radius rad[i], height
 * z[i], bottom to top), nlon points each; closed by fans where a ring's
 * radius is 0 (the quads there degenerate and are dropped) */
static void tri_rings(gl_tris *m, const gl_xf *X, int nring, const double *rad, const double *z, int nlon)
{
    int i, j;
    for (i = 0; i + 1 < nring; i++)
        for (j = 0; j < nlon; j++) {
            double a0 = 2.0 * CD_PI * j / nlon, a1 = 2.0 * CD_PI * (j + 1) / nlon;
            double p00[3], p01[3], p11[3], p10[3];
            p00[0] = rad[i] * cos(a0); p00[1] = rad[i] * sin(a0); p00[2] = z[i];
            p01[0] = rad[i] * cos(a1); p01[1] = rad[i] * sin(a1); p01[2] = z[i];
            p11[0] = rad[i + 1] * cos(a1); p11[1] = rad[i + 1] * sin(a1); p11[2] = z[i + 1];
            p10[0] = rad[i + 1] * cos(a0); p10[1] = rad[i + 1] * sin(a0); p10[2] = z[i + 1];
            tri_add(m, X, p00, p01, p11);
            tri_add(m, X, p00, p11, p10);
        }
}

#define GL_LON 24
#define GL_LAT 12

/* a sphere of radius r (capsule: half length h between the hemispheres) */
static void tri_capsule(gl_tris *m, const gl_xf *X, double r, double h, int nlat, int nlon)
{
    double rad[2 * GL_LAT + 2], z[2 * GL_LAT + 2];
    int i, n = 0;
    for (i = 0; i <= nlat; i++) {
        double th = CD_PI * (1.0 - (double)i / nlat); /* from the bottom pole */
        double zz = r * cos(th), rr = r * sin(th);
        if (h > 0 && 2 * i == nlat) { /* the equator twice: the cylinder between */
            rad[n] = rr; z[n++] = zz - h;
            rad[n] = rr; z[n++] = zz + h;
            continue;
        }
        rad[n] = i == 0 || i == nlat ? 0.0 : rr;
        z[n++] = zz + (2 * i < nlat ? -h : h);
    }
    tri_rings(m, X, n, rad, z, nlon);
}

static void tri_cylinder(gl_tris *m, const gl_xf *X, double r, double h, int nlon)
{
    double rad[4] = {0, r, r, 0}, z[4];
    z[0] = -h; z[1] = -h; z[2] = h; z[3] = h;
    tri_rings(m, X, 4, rad, z, nlon);
}

static void tri_box(gl_tris *m, const gl_xf *X, const double h[3])
{
    int a, s;
    for (a = 0; a < 3; a++)
        for (s = -1; s <= 1; s += 2) {
            int iu = (a + 1) % 3, iv = (a + 2) % 3, t;
            double c[4][3];
            if (s < 0) { t = iu; iu = iv; iv = t; } /* u x v = s e_a: outward */
            for (t = 0; t < 4; t++) {
                double su = (t == 1 || t == 2) ? 1 : -1, sv = t >= 2 ? 1 : -1;
                c[t][a] = s * h[a];
                c[t][iu] = su * h[iu];
                c[t][iv] = sv * h[iv];
            }
            tri_add(m, X, c[0], c[1], c[2]);
            tri_add(m, X, c[0], c[2], c[3]);
        }
}

/* the convex hull of a shape's vertices, triangulated by Qhull (Qt), outward */
static int tri_convex(gl_tris *m, const gl_xf *X, const double *v, int nv)
{
    qhT qh_qh;
    qhT *qh = &qh_qh;
    facetT *facet;
    int exitcode;
    int curlong, totlong;
    double *pts;
    FILE *ferr = fopen("/dev/null", "w");
    if (nv < 4 || !ferr) {
        if (ferr) fclose(ferr);
        return -1;
    }
    pts = malloc((size_t)nv * 3 * sizeof *pts);
    if (!pts) { fclose(ferr); return -1; }
    memcpy(pts, v, (size_t)nv * 3 * sizeof *pts);
    qh_zero(qh, ferr);
    exitcode = qh_new_qhull(qh, 3, nv, pts, False, (char *)"qhull Qt", NULL, ferr);
    if (exitcode == qh_ERRnone) {
        FORALLfacets {
            vertexT *vertex, **vertexp;
            double p[3][3], e1[3], e2[3], n[3];
            int k = 0;
            FOREACHvertex_(facet->vertices) {
                if (k < 3) memcpy(p[k], vertex->point, sizeof p[k]);
                k++;
            }
            if (k != 3) continue;
            cd_v3_sub(e1, p[1], p[0]);
            cd_v3_sub(e2, p[2], p[0]);
            cd_v3_cross(n, e1, e2);
            if (cd_v3_dot(n, facet->normal) >= 0) tri_add(m, X, p[0], p[1], p[2]);
            else tri_add(m, X, p[0], p[2], p[1]);
        }
    }
    qh_freeqhull(qh, !qh_ALL);
    qh_memfreeshort(qh, &curlong, &totlong);
    fclose(ferr);
    free(pts);
    return exitcode == qh_ERRnone ? 0 : -1;
}

/* a frame whose z is the unit vector d, at p */
static void xf_along(gl_xf *X, const double p[3], const double d[3])
{
    double a[3] = {1, 0, 0}, x[3], y[3];
    if (fabs(d[0]) > 0.9) { a[0] = 0; a[1] = 1; }
    cd_v3_cross(x, a, d);
    cd_v3_scale(x, x, 1.0 / nrm3(x));
    cd_v3_cross(y, d, x);
    X->R[0] = x[0]; X->R[1] = y[0]; X->R[2] = d[0];
    X->R[3] = x[1]; X->R[4] = y[1]; X->R[5] = d[1];
    X->R[6] = x[2]; X->R[7] = y[2]; X->R[8] = d[2];
    memcpy(X->p, p, 3 * sizeof(double));
}

/* a rod (thin cylinder) from a to b, body frame */
static void tri_rod(gl_tris *m, const double a[3], const double b[3], double r)
{
    double d[3], mid[3], L;
    gl_xf X;
    cd_v3_sub(d, b, a);
    L = nrm3(d);
    if (!(L > 1e-9)) return;
    cd_v3_scale(d, d, 1.0 / L);
    cd_v3_add(mid, a, b);
    cd_v3_scale(mid, mid, 0.5);
    xf_along(&X, mid, d);
    tri_cylinder(m, &X, r, 0.5 * L, 8);
}

enum { GL_MAT_LINK, GL_MAT_CP, GL_MAT_PLANE, GL_MAT_SYS0 };
#define GL_NPRIM 4 /* per body: links, check points, planes, shapes */

typedef struct {
    gl_buf bin, js;   /* js: the JSON arrays being built, as text */
    int nacc;         /* accessors (= bufferViews: one each) */
    FILE *acc, *views;
    int first_acc, first_view;
} gl_out;

/* a float32 accessor of n items of ncomp components (VEC3 ...), its own
 * bufferView; min/max are those of the float32 values written */
static int gl_accessor(gl_out *g, const float *f, size_t n, int ncomp, int target)
{
    static const char *types[] = {"", "SCALAR", "VEC2", "VEC3", "VEC4"};
    float lo[4], hi[4];
    size_t i, off;
    int k;
    while (g->bin.n % 4) gb_bytes(&g->bin, "", 1);
    off = g->bin.n;
    for (k = 0; k < ncomp; k++) { lo[k] = HUGE_VALF; hi[k] = -HUGE_VALF; }
    for (i = 0; i < n * (size_t)ncomp; i++) {
        k = (int)(i % (size_t)ncomp);
        if (f[i] < lo[k]) lo[k] = f[i];
        if (f[i] > hi[k]) hi[k] = f[i];
        gb_f32(&g->bin, f[i]);
    }
    fprintf(g->views, "%s{\"buffer\":0,\"byteOffset\":%lu,\"byteLength\":%lu", g->first_view ? "" : ",",
            (unsigned long)off, (unsigned long)(n * (size_t)ncomp * 4));
    if (target) fprintf(g->views, ",\"target\":%d", target);
    fputc('}', g->views);
    g->first_view = 0;
    fprintf(g->acc, "%s{\"bufferView\":%d,\"componentType\":5126,\"count\":%lu,\"type\":\"%s\",\"min\":[",
            g->first_acc ? "" : ",", g->nacc, (unsigned long)n, types[ncomp]);
    for (k = 0; k < ncomp; k++) fprintf(g->acc, "%s%.9g", k ? "," : "", (double)lo[k]);
    fputs("],\"max\":[", g->acc);
    for (k = 0; k < ncomp; k++) fprintf(g->acc, "%s%.9g", k ? "," : "", (double)hi[k]);
    fputs("]}", g->acc);
    g->first_acc = 0;
    return g->nacc++;
}

/* JSON string of a name (escapes quotes, backslashes and control characters) */
static void json_str(FILE *f, const char *s)
{
    fputc('"', f);
    for (; *s; s++) {
        unsigned char ch = (unsigned char)*s;
        if (ch == '"' || ch == '\\') fprintf(f, "\\%c", ch);
        else if (ch < 0x20) fprintf(f, "\\u%04x", ch);
        else fputc(ch, f);
    }
    fputc('"', f);
}

static int ex_gltf(exp_ctx *c)
{
    const cd_h5r *r = c->r;
    pose_set ps;
    gl_out g;
    gl_tris prim[GL_NPRIM];
    char *sacc = NULL, *sviews = NULL, *smesh = NULL, *snodes = NULL, *sanim = NULL, *json = NULL;
    size_t lacc = 0, lviews = 0, lmesh = 0, lnodes = 0, lanim = 0, ljson = 0;
    FILE *meshes = NULL, *nodes = NULL, *anim = NULL, *jf = NULL;
    long *keep = NULL, nkeep = 0, j;
    float *fb = NULL;
    double extent = 0.1, lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    int b, k, s, q, nmesh = 0, rc = CLI_FAIL, time_acc = -1, nsampler = 0;
    static const float colour[][3] = {{0.55f, 0.55f, 0.6f}, {0.95f, 0.45f, 0.1f}, {0.7f, 0.75f, 0.7f},
                                      {0.2f, 0.35f, 0.75f}, {0.8f, 0.65f, 0.2f}, {0.3f, 0.6f, 0.35f},
                                      {0.6f, 0.3f, 0.6f}, {0.3f, 0.6f, 0.65f}};
    memset(&ps, 0, sizeof ps);
    memset(&g, 0, sizeof g);
    memset(prim, 0, sizeof prim);
    g.first_acc = g.first_view = 1;
    if (isatty(fileno(stdout))) {
        cli_error("'export gltf' writes binary glTF (GLB): redirect it to a file, e.g. > run.glb");
        return CLI_FAIL;
    }
    if (load_poses(c, &ps) < 0) goto out;
    g.acc = open_memstream(&sacc, &lacc);
    g.views = open_memstream(&sviews, &lviews);
    meshes = open_memstream(&smesh, &lmesh);
    nodes = open_memstream(&snodes, &lnodes);
    anim = open_memstream(&sanim, &lanim);
    keep = malloc((size_t)(c->nsel > 0 ? c->nsel : 1) * sizeof *keep);
    fb = malloc((size_t)(c->nsel > 0 ? c->nsel : 1) * 4 * sizeof *fb);
    if (!g.acc || !g.views || !meshes || !nodes || !anim || !keep || !fb) { cli_error("out of memory"); goto out; }

    /* keyframes: selected samples with finite poses and float32 times that increase */
    for (j = 0; j < c->nsel; j++) {
        long i = c->sel[j];
        int finite = isfinite(c->t[i]);
        for (s = 0; s < r->nsys && finite; s++)
            for (k = 0; k < r->sys[s].nbody * 3 && finite; k++)
                finite = isfinite(ps.bx[s][(size_t)i * 3 * r->sys[s].nbody + k]);
        for (s = 0; s < r->nsys && finite; s++)
            for (k = 0; k < r->sys[s].nbody * 4 && finite; k++)
                finite = isfinite(ps.bq[s][(size_t)i * 4 * r->sys[s].nbody + k]);
        if (!finite) break; /* a run that failed numerically: its poses up to there */
        if (nkeep > 0 && !((float)c->t[i] > (float)c->t[keep[nkeep - 1]])) continue;
        keep[nkeep++] = i;
    }
    if (nkeep == 0) { cli_error("%s has no sample with finite body poses", c->o->path); goto out; }

    /* the plane's drawn size: the spread of the bodies at the first keyframe */
    pose_frame(r, &ps, keep[0]);
    for (b = 0; b < r->nbody; b++)
        for (k = 0; k < 3; k++) {
            if (ps.X[3 * b + k] < lo[k]) lo[k] = ps.X[3 * b + k];
            if (ps.X[3 * b + k] > hi[k]) hi[k] = ps.X[3 * b + k];
        }
    for (k = 0; k < 3; k++)
        if (r->nbody > 0 && hi[k] - lo[k] > extent) extent = hi[k] - lo[k];

    /* one mesh per body that has anything to draw */
    for (b = 0; b < r->nbody; b++) {
        gl_xf I;
        int p, nprim = 0, ch;
        double tip[3] = {0, 0, 0}, best = 0;
        memset(&I, 0, sizeof I);
        I.R[0] = I.R[4] = I.R[8] = 1;
        for (p = 0; p < GL_NPRIM; p++) prim[p].n = 0;
        for (q = 0; q < r->nshape; q++) {
            const cd_h5r_shape *sh = r->shape + q;
            gl_xf X;
            if (sh->body != b) continue;
            memcpy(X.R, sh->rot, sizeof X.R);
            memcpy(X.p, sh->pos, sizeof X.p);
            switch (sh->type) {
            case CD_SHAPE_SPHERE: tri_capsule(prim + 3, &X, sh->size[0], 0, GL_LAT, GL_LON); break;
            case CD_SHAPE_CAPSULE: tri_capsule(prim + 3, &X, sh->size[0], sh->size[1], GL_LAT, GL_LON); break;
            case CD_SHAPE_CYLINDER: tri_cylinder(prim + 3, &X, sh->size[0], sh->size[1], GL_LON); break;
            case CD_SHAPE_BOX: tri_box(prim + 3, &X, sh->size); break;
            case CD_SHAPE_CONVEX:
                if (sh->vert_num > 0 && sh->vert_adr >= 0 && sh->vert_adr + sh->vert_num <= r->nvert)
                    tri_convex(prim + 3, &X, r->vert + 3 * sh->vert_adr, sh->vert_num);
                break;
            case CD_SHAPE_PLANE: { /* a square of the scene's size, both faces */
                double e = extent, c0[3] = {-e, -e, 0}, c1[3] = {e, -e, 0}, c2[3] = {e, e, 0}, c3[3] = {-e, e, 0};
                tri_add(prim + 2, &X, c0, c1, c2); tri_add(prim + 2, &X, c0, c2, c3);
                tri_add(prim + 2, &X, c0, c2, c1); tri_add(prim + 2, &X, c0, c3, c2);
                break;
            }
            default: break;
            }
        }
        for (q = 0; q < r->ncp; q++) {
            gl_xf X;
            if (r->cp[q].body != b) continue;
            memset(&X, 0, sizeof X);
            X.R[0] = X.R[4] = X.R[8] = 1;
            memcpy(X.p, r->cp[q].pos, sizeof X.p);
            tri_capsule(prim + 1, &X, r->cp[q].radius > 1e-3 ? r->cp[q].radius : 1e-3, 0, 6, 8);
            if (nrm3(r->cp[q].pos) > best) { best = nrm3(r->cp[q].pos); memcpy(tip, r->cp[q].pos, sizeof tip); }
        }
        /* link rods: to each child's joint origin (at the first keyframe, in
         * this body's frame), and a tip link to its farthest check point */
        {
            int nchild = 0;
            for (ch = b + 1; ch < r->nbody; ch++)
                if (r->body[ch].parent == b) {
                    double d[3], loc[3], zero[3] = {0, 0, 0}, L;
                    cd_v3_sub(d, ps.X + 3 * ch, ps.X + 3 * b);
                    cd_m3_tmulv(loc, ps.R + 9 * b, d);
                    L = nrm3(loc);
                    if (r->body[b].parent >= 0 || prim[3].n == 0) /* a base drawn by its shape needs no spokes */
                        tri_rod(prim + 0, zero, loc, fmin(0.03, fmax(0.002, 0.04 * L)));
                    nchild++;
                }
            if (nchild == 0 && r->body[b].parent >= 0 && best > 0) {
                double zero[3] = {0, 0, 0};
                tri_rod(prim + 0, zero, tip, fmin(0.03, fmax(0.002, 0.04 * best)));
            }
        }
        for (p = 0; p < GL_NPRIM; p++)
            if (prim[p].oom) { cli_error("out of memory"); goto out; }
        fprintf(nodes, ",{\"name\":");
        json_str(nodes, r->body[b].full_name);
        fprintf(nodes, ",\"extras\":{\"body\":%d,\"system\":%d}", b, r->body[b].system);
        for (p = 0; p < GL_NPRIM; p++) nprim += prim[p].n > 0;
        if (nprim > 0) {
            int first = 1;
            fprintf(meshes, "%s{\"name\":", nmesh ? "," : "");
            json_str(meshes, r->body[b].full_name);
            fputs(",\"primitives\":[", meshes);
            for (p = 0; p < GL_NPRIM; p++) {
                size_t t, nv = 3 * prim[p].n;
                float *pos, *nor;
                int apos, anor, mat;
                if (prim[p].n == 0) continue;
                pos = malloc(nv * 3 * sizeof *pos);
                nor = malloc(nv * 3 * sizeof *nor);
                if (!pos || !nor) { free(pos); free(nor); cli_error("out of memory"); goto out; }
                for (t = 0; t < prim[p].n; t++) {
                    const double *w = prim[p].v + 9 * t;
                    double e1[3], e2[3], n[3];
                    cd_v3_sub(e1, w + 3, w);
                    cd_v3_sub(e2, w + 6, w);
                    cd_v3_cross(n, e1, e2);
                    cd_v3_scale(n, n, 1.0 / nrm3(n));
                    for (k = 0; k < 9; k++) {
                        pos[9 * t + k] = (float)w[k];
                        nor[9 * t + k] = (float)n[k % 3];
                    }
                }
                apos = gl_accessor(&g, pos, nv, 3, 34962);
                anor = gl_accessor(&g, nor, nv, 3, 34962);
                free(pos);
                free(nor);
                mat = p == 0 ? GL_MAT_LINK : p == 1 ? GL_MAT_CP : p == 2 ? GL_MAT_PLANE : GL_MAT_SYS0 + r->body[b].system % 5;
                fprintf(meshes, "%s{\"attributes\":{\"POSITION\":%d,\"NORMAL\":%d},\"material\":%d}", first ? "" : ",",
                        apos, anor, mat);
                first = 0;
            }
            fputs("]}", meshes);
            fprintf(nodes, ",\"mesh\":%d", nmesh++);
        }
        {
            const double *x = ps.X + 3 * b;
            const cd_h5r_sys *sy = r->sys + r->body[b].system;
            const double *qq = ps.bq[r->body[b].system] + 4 * ((size_t)keep[0] * sy->nbody + (b - sy->body_first));
            double nq = sqrt(qq[0] * qq[0] + qq[1] * qq[1] + qq[2] * qq[2] + qq[3] * qq[3]);
            fprintf(nodes, ",\"translation\":[%.9g,%.9g,%.9g],\"rotation\":[%.9g,%.9g,%.9g,%.9g]}",
                    (double)(float)x[0], (double)(float)x[1], (double)(float)x[2], (double)(float)(qq[1] / nq),
                    (double)(float)(qq[2] / nq), (double)(float)(qq[3] / nq), (double)(float)(qq[0] / nq));
        }
    }

    /* the animation: one time accessor, a translation and a rotation sampler per body */
    for (j = 0; j < nkeep; j++) fb[j] = (float)c->t[keep[j]];
    time_acc = gl_accessor(&g, fb, (size_t)nkeep, 1, 0);
    fputs("{\"name\":\"capdyn run\",\"samplers\":[", anim);
    for (b = 0; b < r->nbody; b++) {
        const cd_h5r_sys *sy = r->sys + r->body[b].system;
        int jb = b - sy->body_first, at, ar;
        for (j = 0; j < nkeep; j++) {
            const double *x = ps.bx[r->body[b].system] + 3 * ((size_t)keep[j] * sy->nbody + jb);
            for (k = 0; k < 3; k++) fb[3 * j + k] = (float)x[k];
        }
        at = gl_accessor(&g, fb, (size_t)nkeep, 3, 0);
        for (j = 0; j < nkeep; j++) {
            const double *qq = ps.bq[r->body[b].system] + 4 * ((size_t)keep[j] * sy->nbody + jb);
            double nq = sqrt(qq[0] * qq[0] + qq[1] * qq[1] + qq[2] * qq[2] + qq[3] * qq[3]);
            fb[4 * j + 0] = (float)(qq[1] / nq);
            fb[4 * j + 1] = (float)(qq[2] / nq);
            fb[4 * j + 2] = (float)(qq[3] / nq);
            fb[4 * j + 3] = (float)(qq[0] / nq);
        }
        ar = gl_accessor(&g, fb, (size_t)nkeep, 4, 0);
        fprintf(anim, "%s{\"input\":%d,\"output\":%d,\"interpolation\":\"LINEAR\"},"
                      "{\"input\":%d,\"output\":%d,\"interpolation\":\"LINEAR\"}",
                b ? "," : "", time_acc, at, time_acc, ar);
        nsampler += 2;
    }
    fputs("],\"channels\":[", anim);
    for (b = 0; b < r->nbody; b++)
        fprintf(anim, "%s{\"sampler\":%d,\"target\":{\"node\":%d,\"path\":\"translation\"}},"
                      "{\"sampler\":%d,\"target\":{\"node\":%d,\"path\":\"rotation\"}}",
                b ? "," : "", 2 * b, b + 1, 2 * b + 1, b + 1);
    fputs("]}", anim);
    if (g.bin.oom) { cli_error("out of memory"); goto out; }
    fclose(g.acc); g.acc = NULL;
    fclose(g.views); g.views = NULL;
    fclose(meshes); meshes = NULL;
    fclose(nodes); nodes = NULL;
    fclose(anim); anim = NULL;
    while (g.bin.n % 4) gb_bytes(&g.bin, "", 1);

    jf = open_memstream(&json, &ljson);
    if (!jf) { cli_error("out of memory"); goto out; }
    fprintf(jf, "{\"asset\":{\"version\":\"2.0\",\"generator\":\"capdyn %s export gltf\"", cd_version());
    {
        char *title = cd_h5r_attr_str(r, "/", "title");
        if (title) {
            fputs(",\"extras\":{\"title\":", jf);
            json_str(jf, title);
            fputc('}', jf);
            free(title);
        }
    }
    fputs("},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],", jf);
    /* node 0: capdyn's world (z up) turned into glTF's (y up): -90 deg about x */
    fputs("\"nodes\":[{\"name\":\"capdyn world (z up)\",\"rotation\":[-0.707106781,0,0,0.707106781]", jf);
    if (r->nbody > 0) {
        fputs(",\"children\":[", jf);
        for (b = 0; b < r->nbody; b++) fprintf(jf, "%s%d", b ? "," : "", b + 1);
        fputc(']', jf);
    }
    fprintf(jf, "}%s]", snodes ? snodes : "");
    if (nmesh > 0) fprintf(jf, ",\"meshes\":[%s]", smesh);
    fputs(",\"materials\":[", jf);
    {
        static const char *mname[] = {"link", "check point", "plane"};
        int mi;
        for (mi = 0; mi < GL_MAT_SYS0 + 5; mi++) {
            const float *col = colour[mi];
            fprintf(jf, "%s{\"name\":\"", mi ? "," : "");
            if (mi < GL_MAT_SYS0) fputs(mname[mi], jf);
            else fprintf(jf, "system %d", mi - GL_MAT_SYS0);
            fprintf(jf, "\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[%.3f,%.3f,%.3f,1],\"metallicFactor\":0,"
                        "\"roughnessFactor\":0.7}}", (double)col[0], (double)col[1], (double)col[2]);
        }
    }
    fputc(']', jf);
    fprintf(jf, ",\"accessors\":[%s],\"bufferViews\":[%s],\"buffers\":[{\"byteLength\":%lu}]", sacc, sviews,
            (unsigned long)g.bin.n);
    if (r->nbody > 0 && nsampler > 0) fprintf(jf, ",\"animations\":[%s]", sanim);
    fputc('}', jf);
    fclose(jf);
    jf = NULL;
    {
        gl_buf out;
        size_t jpad = (4 - ljson % 4) % 4, total = 12 + 8 + ljson + jpad + 8 + g.bin.n;
        memset(&out, 0, sizeof out);
        if (total > 0xffffffffUL) { cli_error("the glTF file would exceed 4 GiB: export fewer samples (--frames N)"); goto out; }
        gb_u32(&out, 0x46546C67UL); /* "glTF" */
        gb_u32(&out, 2);
        gb_u32(&out, (unsigned long)total);
        gb_u32(&out, (unsigned long)(ljson + jpad));
        gb_u32(&out, 0x4E4F534AUL); /* JSON */
        gb_bytes(&out, json, ljson);
        for (k = 0; k < (int)jpad; k++) gb_bytes(&out, " ", 1);
        gb_u32(&out, (unsigned long)g.bin.n);
        gb_u32(&out, 0x004E4942UL); /* BIN */
        gb_bytes(&out, g.bin.p, g.bin.n);
        if (out.oom) { free(out.p); cli_error("out of memory"); goto out; }
        if (fwrite(out.p, 1, out.n, stdout) != out.n) { free(out.p); cli_error("writing the output failed"); goto out; }
        free(out.p);
    }
    rc = CLI_OK;
out:
    if (g.acc) fclose(g.acc);
    if (g.views) fclose(g.views);
    if (meshes) fclose(meshes);
    if (nodes) fclose(nodes);
    if (anim) fclose(anim);
    if (jf) fclose(jf);
    free(sacc); free(sviews); free(smesh); free(snodes); free(sanim); free(json);
    for (k = 0; k < GL_NPRIM; k++) free(prim[k].v);
    free(g.bin.p);
    free(keep);
    free(fb);
    free_poses(r, &ps);
    return rc;
}

/* ---- 3-D wireframes and contact forces (for gnuplot splot) -------------------- */
static void e_pt(exp_ctx *c, const double ctr[3], const double Rw[9], double x, double y, double z, int part, int body)
{
    double loc[3], w[3];
    int p = c->o->prec;
    loc[0] = x; loc[1] = y; loc[2] = z;
    cd_m3_mulv(w, Rw, loc);
    num0(ctr[0] + w[0], p);
    num(ctr[1] + w[1], p);
    num(ctr[2] + w[2], p);
    printf(" %d %d\n", part, body);
}
/* a circle of radius r in the local plane z = z0 (axis 2), x = z0 (axis 0) or y = z0 (axis 1) */
static void e_circle(exp_ctx *c, const double ctr[3], const double Rw[9], double r, double z0, int axis, double a0,
                     double a1, int body)
{
    int i, n = NCIRC;
    for (i = 0; i <= n; i++) {
        double a = a0 + (a1 - a0) * i / n, u = r * cos(a), v = r * sin(a);
        if (axis == 2) e_pt(c, ctr, Rw, u, v, z0, 1, body);
        else if (axis == 0) e_pt(c, ctr, Rw, z0, u, v, 1, body);
        else e_pt(c, ctr, Rw, v, z0, u, 1, body);
    }
    putchar('\n');
}
static void e_line(exp_ctx *c, const double ctr[3], const double Rw[9], const double a[3], const double b[3], int part,
                   int body)
{
    e_pt(c, ctr, Rw, a[0], a[1], a[2], part, body);
    e_pt(c, ctr, Rw, b[0], b[1], b[2], part, body);
    putchar('\n');
}

static void shape_edges(exp_ctx *c, const pose_set *ps, int k, double extent)
{
    const cd_h5r *r = c->r;
    const cd_h5r_shape *sh = r->shape + k;
    double Rw[9], ctr[3];
    int i, b = sh->body;
    cd_m3_mul(Rw, ps->R + 9 * b, sh->rot);
    to_world(ps, b, sh->pos, ctr);
    switch (sh->type) {
    case CD_SHAPE_SPHERE:
        for (i = 0; i < 3; i++) e_circle(c, ctr, Rw, sh->size[0], 0, i, 0, 2 * CD_PI, b);
        break;
    case CD_SHAPE_CYLINDER:
    case CD_SHAPE_CAPSULE: {
        double rr = sh->size[0], h = sh->size[1];
        e_circle(c, ctr, Rw, rr, -h, 2, 0, 2 * CD_PI, b);
        e_circle(c, ctr, Rw, rr, h, 2, 0, 2 * CD_PI, b);
        for (i = 0; i < 4; i++) {
            double a = 0.5 * CD_PI * i, p0[3], p1[3];
            p0[0] = p1[0] = rr * cos(a); p0[1] = p1[1] = rr * sin(a); p0[2] = -h; p1[2] = h;
            e_line(c, ctr, Rw, p0, p1, 1, b);
        }
        if (sh->type == CD_SHAPE_CAPSULE) { /* the end caps: half circles in the xz and yz planes */
            int e;
            for (e = -1; e <= 1; e += 2) {
                int ax;
                for (ax = 0; ax < 2; ax++) {
                    int n;
                    for (n = 0; n <= NCIRC / 2; n++) {
                        double a = CD_PI * n / (NCIRC / 2), u = rr * cos(a), v = e * (h + rr * sin(a));
                        if (ax == 0) e_pt(c, ctr, Rw, u, 0, v, 1, b);
                        else e_pt(c, ctr, Rw, 0, u, v, 1, b);
                    }
                    putchar('\n');
                }
            }
        }
        break;
    }
    case CD_SHAPE_BOX: {
        const double *hh = sh->size;
        int e;
        for (e = 0; e < 12; e++) {
            int ax = e / 4, iu = (ax + 1) % 3, iv = (ax + 2) % 3;
            double p0[3], p1[3];
            p0[ax] = -hh[ax]; p1[ax] = hh[ax];
            p0[iu] = p1[iu] = (e & 1 ? 1 : -1) * hh[iu];
            p0[iv] = p1[iv] = (e & 2 ? 1 : -1) * hh[iv];
            e_line(c, ctr, Rw, p0, p1, 1, b);
        }
        break;
    }
    case CD_SHAPE_CONVEX: {
        gl_tris m;
        gl_xf I;
        size_t t;
        memset(&m, 0, sizeof m);
        memset(&I, 0, sizeof I);
        I.R[0] = I.R[4] = I.R[8] = 1;
        if (sh->vert_num > 0 && sh->vert_adr >= 0 && sh->vert_adr + sh->vert_num <= r->nvert)
            tri_convex(&m, &I, r->vert + 3 * sh->vert_adr, sh->vert_num);
        for (t = 0; t < m.n; t++) {
            const double *v = m.v + 9 * t;
            for (i = 0; i <= 3; i++) e_pt(c, ctr, Rw, v[3 * (i % 3)], v[3 * (i % 3) + 1], v[3 * (i % 3) + 2], 1, b);
            putchar('\n');
        }
        free(m.v);
        break;
    }
    case CD_SHAPE_PLANE: /* a grid of the scene's size on the boundary plane */
        for (i = -4; i <= 4; i++) {
            double p0[3], p1[3], s = extent * i / 4.0;
            p0[0] = s; p0[1] = -extent; p0[2] = 0; p1[0] = s; p1[1] = extent; p1[2] = 0;
            e_line(c, ctr, Rw, p0, p1, 1, b);
            p0[0] = -extent; p0[1] = s; p1[0] = extent; p1[1] = s;
            e_line(c, ctr, Rw, p0, p1, 1, b);
        }
        break;
    default:
        break;
    }
}

static int ex_edges(exp_ctx *c)
{
    const cd_h5r *r = c->r;
    pose_set ps;
    long j;
    int b, k;
    double I9[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, O3[3] = {0, 0, 0};
    memset(&ps, 0, sizeof ps);
    if (load_poses(c, &ps) < 0) {
        free_poses(r, &ps);
        return CLI_FAIL;
    }
    puts("# x y z part body");
    printf("# 3-D polylines in the %s frame [m]; part 0 link, 1 shape, 2 base-to-joint segment; one block per "
           "frame (gnuplot index), polylines separated by a blank line\n",
           c->o->frame_body >= 0 ? r->body[c->o->frame_body].full_name : "world");
    for (j = 0; j < c->nsel; j++) {
        long i = c->sel[j];
        double extent;
        pose_frame(r, &ps, i);
        extent = pose_extent(r, &ps);
        if (j > 0) fputs("\n\n", stdout);
        printf("# frame %ld sample %ld t %.9g\n", j, i, c->t[i]);
        for (b = 0; b < r->nbody; b++) {
            int ch, nchild = 0, q, has_shape = 0;
            double tip[3] = {0, 0, 0}, best = 0, w[3];
            for (q = 0; q < r->nshape; q++)
                if (r->shape[q].body == b) has_shape = 1;
            for (ch = b + 1; ch < r->nbody; ch++)
                if (r->body[ch].parent == b) {
                    if (r->body[b].parent >= 0 || !has_shape)
                        e_line(c, O3, I9, ps.X + 3 * b, ps.X + 3 * ch, r->body[b].parent < 0 ? 2 : 0, b);
                    nchild++;
                }
            if (nchild > 0 || r->body[b].parent < 0) continue;
            for (q = 0; q < r->ncp; q++)
                if (r->cp[q].body == b && nrm3(r->cp[q].pos) > best) {
                    best = nrm3(r->cp[q].pos);
                    memcpy(tip, r->cp[q].pos, sizeof tip);
                }
            if (best == 0) cd_v3_scale(tip, r->body[b].com, 2.0);
            if (nrm3(tip) > 0) {
                to_world(&ps, b, tip, w);
                e_line(c, O3, I9, ps.X + 3 * b, w, 0, b);
            }
        }
        for (k = 0; k < r->nshape; k++) shape_edges(c, &ps, k, extent);
    }
    free_poses(r, &ps);
    return CLI_OK;
}

/* the system of a body */
static int sys_of(const cd_h5r *r, int b) { return b >= 0 && b < r->nbody ? r->body[b].system : -1; }

static int ex_forces(exp_ctx *c)
{
    const cd_h5r *r = c->r;
    pose_set ps;
    double *fn = NULL, *ft = NULL, *pt = NULL, *nr = NULL, *mode = NULL;
    long j;
    int k, a, p = c->o->prec, rc = CLI_OK;
    memset(&ps, 0, sizeof ps);
    if (load_poses(c, &ps) < 0 ||
        (r->nslot > 0 && (!(fn = series(c, "/contacts/fn")) || !(ft = series(c, "/contacts/ft")) ||
                          !(pt = series(c, "/contacts/point")) || !(nr = series(c, "/contacts/normal")) ||
                          !(mode = series(c, "/contacts/mode"))))) {
        rc = CLI_FAIL;
        goto out;
    }
    puts("# x y z fx fy fz fn ft mode slot between body_a body_b t");
    printf("# contacts in contact (mode > 0) per frame, in the %s frame: contact point [m] and the force on the "
           "shape's body (body_b), -(fn normal + ft) [N]; between 1: body_a and body_b in different systems "
           "(e.g. finger on target), 0: the same system (e.g. finger on finger); body names system/body\n",
           c->o->frame_body >= 0 ? r->body[c->o->frame_body].full_name : "world");
    for (j = 0; j < c->nsel; j++) {
        long i = c->sel[j];
        int nout = 0;
        pose_frame(r, &ps, i);
        if (j > 0) fputs("\n\n", stdout);
        printf("# frame %ld sample %ld t %.9g\n", j, i, c->t[i]);
        for (k = 0; k < r->nslot; k++) {
            size_t o = (size_t)i * r->nslot + k;
            double f[3], x[3], fl[3];
            int m = (int)mode[o];
            if (m <= 0) continue;
            for (a = 0; a < 3; a++) f[a] = -(fn[o] * nr[3 * o + a] + ft[3 * o + a]);
            frame_point(&ps, pt + 3 * o, x);
            frame_vec(&ps, f, fl);
            num0(x[0], p); num(x[1], p); num(x[2], p);
            num(fl[0], p); num(fl[1], p); num(fl[2], p);
            num(fn[o], p);
            num(nrm3(ft + 3 * o), p);
            printf(" %d %d %d ", m, k, sys_of(r, r->slot[k].body_a) != sys_of(r, r->slot[k].body_b));
            token(r->slot[k].body_a_name);
            putchar(' ');
            token(r->slot[k].body_b_name);
            num(c->t[i], p);
            putchar('\n');
            nout++;
        }
        if (nout == 0) { /* gnuplot needs a row per block */
            fputs("nan nan nan nan nan nan 0 0 0 -1 0 - -", stdout);
            num(c->t[i], p);
            putchar('\n');
        }
    }
out:
    free(fn); free(ft); free(pt); free(nr); free(mode);
    free_poses(r, &ps);
    return rc;
}

int cmd_export(int argc, char **argv)
{
    exp_opts o;
    exp_ctx c;
    cd_error err;
    cd_h5r *r;
    const char *pos[3] = {NULL, NULL, NULL};
    int npos = 0, i, rc, geometry, needs_arg = 0, opt_arg = 0;
    memset(&o, 0, sizeof o);
    o.prec = 10;
    o.view_u = 0;
    o.view_v = 1;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (a[0] == '-' && a[1] && !(a[1] >= '0' && a[1] <= '9')) {
            const char *val = NULL;
            if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
                fputs(export_help, stdout);
                return CLI_OK;
            }
            if (!strcmp(a, "--active")) { o.active = 1; continue; }
            if (!strcmp(a, "--every") || !strcmp(a, "--frames") || !strcmp(a, "--at") || !strcmp(a, "--view") ||
                !strcmp(a, "--precision") || !strcmp(a, "--frame")) {
                if (i + 1 >= argc) return cli_usage("export", "%s needs a value", a);
                val = argv[++i];
            } else {
                return cli_usage("export", "unknown option '%s'", a);
            }
            if (!strcmp(a, "--every")) {
                if (cli_count(val, &o.every) || o.every < 1) return cli_usage("export", "--every expects a positive integer, got '%s'", val);
            } else if (!strcmp(a, "--frames")) {
                if (cli_count(val, &o.frames) || o.frames < 1) return cli_usage("export", "--frames expects a positive integer, got '%s'", val);
            } else if (!strcmp(a, "--at")) {
                o.at = val;
            } else if (!strcmp(a, "--frame")) {
                o.frame = val;
            } else if (!strcmp(a, "--view")) {
                if (!strcmp(val, "xy")) { o.view_u = 0; o.view_v = 1; }
                else if (!strcmp(val, "xz")) { o.view_u = 0; o.view_v = 2; }
                else if (!strcmp(val, "yz")) { o.view_u = 1; o.view_v = 2; }
                else return cli_usage("export", "--view expects xy, xz or yz, got '%s'", val);
            } else {
                long pr;
                if (cli_count(val, &pr) || pr < 1 || pr > 17) return cli_usage("export", "--precision expects 1 .. 17, got '%s'", val);
                o.prec = (int)pr;
            }
            continue;
        }
        if (npos >= 3) return cli_usage("export", "unexpected argument '%s'", a);
        pos[npos++] = a;
    }
    if (npos < 1) return cli_usage("export", "missing the results file");
    if (npos < 2) return cli_usage("export", "missing WHAT (time, system NAME, contacts, slot N, slots, events, diagnostics, outline, checkpoints, edges, forces, gltf)");
    o.path = pos[0];
    o.what = pos[1];
    o.arg = npos > 2 ? pos[2] : NULL;
    if (!strcmp(o.what, "system") || !strcmp(o.what, "slot")) needs_arg = 1;
    else if (!strcmp(o.what, "diagnostics")) opt_arg = 1;
    else if (strcmp(o.what, "time") && strcmp(o.what, "contacts") && strcmp(o.what, "slots") && strcmp(o.what, "events") &&
             strcmp(o.what, "outline") && strcmp(o.what, "checkpoints") && strcmp(o.what, "gltf") &&
             strcmp(o.what, "edges") && strcmp(o.what, "forces"))
        return cli_usage("export", "unknown WHAT '%s' (time, system NAME, contacts, slot N, slots, events, diagnostics, "
                                   "outline, checkpoints, edges, forces, gltf)", o.what);
    if (needs_arg && !o.arg) return cli_usage("export", "'%s' needs an argument (%s)", o.what, !strcmp(o.what, "system") ? "the system name" : "the slot number");
    if (!needs_arg && !opt_arg && o.arg) return cli_usage("export", "'%s' takes no argument, got '%s'", o.what, o.arg);
    if ((o.every > 0) + (o.frames > 0) + (o.at != NULL) > 1) return cli_usage("export", "use only one of --every, --frames, --at");

    r = cd_h5r_open(o.path, &err);
    if (!r) {
        cli_error("%s", err.msg);
        return CLI_FAIL;
    }
    memset(&c, 0, sizeof c);
    c.r = r;
    c.o = &o;
    c.t = cd_h5r_series(r, "/time", NULL, &err);
    if (!c.t) {
        cli_error("%s", err.msg);
        cd_h5r_close(r);
        return CLI_FAIL;
    }
    geometry = !strcmp(o.what, "outline") || !strcmp(o.what, "checkpoints") || !strcmp(o.what, "edges") ||
               !strcmp(o.what, "forces");
    o.frame_body = -1;
    if (o.frame) {
        int b;
        if (!geometry) {
            cd_h5r_close(r);
            free(c.t);
            return cli_usage("export", "--frame applies to outline, checkpoints, edges and forces, not to '%s'", o.what);
        }
        for (b = 0; b < r->nbody && o.frame_body < 0; b++)
            if (!strcmp(r->body[b].full_name, o.frame)) o.frame_body = b;
        if (o.frame_body < 0) {
            cli_error("--frame: no body '%s' in %s (bodies are named system/body, a base by its system's name)", o.frame,
                      o.path);
            cd_h5r_close(r);
            free(c.t);
            return CLI_FAIL;
        }
    }
    rc = select_samples(&c, geometry);
    if (rc == -2) {
        free(c.t);
        free(c.sel);
        cd_h5r_close(r);
        return cli_usage("export", "--at expects times separated by commas, got '%s'", o.at);
    }
    if (rc < 0) {
        cli_error("out of memory");
        rc = CLI_FAIL;
    } else if (!strcmp(o.what, "time")) rc = ex_time(&c);
    else if (!strcmp(o.what, "system")) rc = ex_system(&c);
    else if (!strcmp(o.what, "contacts")) rc = ex_contacts(&c);
    else if (!strcmp(o.what, "slot")) rc = ex_slot(&c);
    else if (!strcmp(o.what, "slots")) rc = ex_slots(&c);
    else if (!strcmp(o.what, "events")) rc = ex_events(&c);
    else if (!strcmp(o.what, "diagnostics")) rc = ex_diagnostics(&c);
    else if (!strcmp(o.what, "edges")) rc = r->n > 0 ? ex_edges(&c) : (cli_error("%s has no committed samples", o.path), CLI_FAIL);
    else if (!strcmp(o.what, "forces")) rc = r->n > 0 ? ex_forces(&c) : (cli_error("%s has no committed samples", o.path), CLI_FAIL);
    else if (!strcmp(o.what, "gltf")) rc = r->n > 0 ? ex_gltf(&c) : (cli_error("%s has no committed samples", o.path), CLI_FAIL);
    else if (!strcmp(o.what, "outline")) rc = r->n > 0 ? ex_outline(&c) : (cli_error("%s has no committed samples", o.path), CLI_FAIL);
    else rc = r->n > 0 ? ex_checkpoints(&c) : (cli_error("%s has no committed samples", o.path), CLI_FAIL);
    free(c.t);
    free(c.sel);
    cd_h5r_close(r);
    if (fflush(stdout) != 0 && rc == CLI_OK) {
        cli_error("writing the output failed");
        rc = CLI_FAIL;
    }
    return rc;
}
