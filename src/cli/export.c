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

#include <math.h>
#include <stdlib.h>
#include <string.h>

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
    "\n"
    "options:\n"
    "  --every K            every K-th sample (time series default: all)\n"
    "  --frames N           N samples evenly spaced, first and last included\n"
    "  --at T[,T...]        the samples nearest to these times [s] ('end': the\n"
    "                       last committed sample)\n"
    "                       (outline/checkpoints default: the last sample)\n"
    "  --view xy|xz|yz      projection plane of outline/checkpoints (default xy)\n"
    "  --precision P        significant digits (default 10)\n"
    "  --active             (contacts) only slots ever in contact\n";

typedef struct {
    const char *path, *what, *arg;
    long every, frames;
    const char *at;
    int view_u, view_v, prec, active;
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
}

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
        double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL}, extent = 0;
        pose_frame(r, &ps, i);
        for (b = 0; b < r->nbody; b++)
            for (k = 0; k < 3; k++) {
                if (ps.X[3 * b + k] < lo[k]) lo[k] = ps.X[3 * b + k];
                if (ps.X[3 * b + k] > hi[k]) hi[k] = ps.X[3 * b + k];
            }
        for (k = 0; k < 3; k++)
            if (r->nbody > 0 && hi[k] - lo[k] > extent) extent = hi[k] - lo[k];
        if (extent < 0.1) extent = 0.1;
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
                !strcmp(a, "--precision")) {
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
    if (npos < 2) return cli_usage("export", "missing WHAT (time, system NAME, contacts, slot N, slots, events, diagnostics, outline, checkpoints)");
    o.path = pos[0];
    o.what = pos[1];
    o.arg = npos > 2 ? pos[2] : NULL;
    if (!strcmp(o.what, "system") || !strcmp(o.what, "slot")) needs_arg = 1;
    else if (!strcmp(o.what, "diagnostics")) opt_arg = 1;
    else if (strcmp(o.what, "time") && strcmp(o.what, "contacts") && strcmp(o.what, "slots") && strcmp(o.what, "events") &&
             strcmp(o.what, "outline") && strcmp(o.what, "checkpoints"))
        return cli_usage("export", "unknown WHAT '%s' (time, system NAME, contacts, slot N, slots, events, diagnostics, "
                                   "outline, checkpoints)", o.what);
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
    geometry = !strcmp(o.what, "outline") || !strcmp(o.what, "checkpoints");
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
