/* capdyn sweep: many variants of one scenario, each a normal run, on every
 * core (docs/sweep.md). This file is the command: its options and the
 * driver. The plan (grid or Latin hypercube over 1-4 --set keys) is made
 * in sweep_plan.c, the variants run in sweep_run.c, the summary is written
 * and read in sweep_h5.c (every SW_CHECKPOINT seconds, on SIGINT/SIGTERM
 * and at the end; --resume reads it back and runs only the variants not
 * yet run), and sweep_report.c prints. */
#define _POSIX_C_SOURCE 200809L
#include "sweep.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#ifdef CAPDYN_MPI
#include <mpi.h>
#endif

static const char *sweep_help =
    "usage: capdyn sweep SCENARIO.toml --vary KEY=SPEC [--vary KEY=SPEC ...] [options]\n"
    "       capdyn sweep SCENARIO.toml [--vary KEY=SPEC ...] --mc N --disperse KEY=DIST ... [options]\n"
    "       capdyn sweep --merge SHARD.h5 SHARD.h5 ... -o MERGED.h5\n"
    "       capdyn sweep --table SUMMARY.h5\n"
    "\n"
    "Runs one variant of the scenario per point of a grid (default) or of a Latin\n"
    "hypercube over 1 to 4 keys, on every core, and writes one HDF5 summary: the\n"
    "swept values, each variant's verdict and figures of merit, failure reasons,\n"
    "and wall times (docs/sweep.md).\n"
    "\n"
    "SPEC:  A:B:N         N values from A to B, both included (grid); the interval\n"
    "                     [A, B] under --lhs (N is then unused; A:B also works)\n"
    "       V1,V2,...     a list of TOML values (\"tako\",\"space\" needs the quotes\n"
    "                     escaped for the shell; bare words are strings)\n"
    "\n"
    "DIST:  normal(MEAN,SD[,LO,HI])  truncated to [LO, HI] if given\n"
    "       uniform(LO,HI)\n"
    "       cone(X,Y,Z,DEG)          a vector of that length, its direction uniform\n"
    "                                within DEG of (X,Y,Z)\n"
    "       rotation(W,X,Y,Z,DEG)    the quaternion turned by up to DEG about a\n"
    "                                uniform axis\n"
    "       inertia(A,B,C,REL_SD)    principal moments, each normal(I, REL_SD I),\n"
    "                                redrawn until positive and A+B>=C, B+C>=A, A+C>=B\n"
    "\n"
    "options:\n"
    "  -o, --output FILE   the summary (default: the scenario's base name with\n"
    "                      _sweep.h5); written under a temporary name, renamed\n"
    "  --set KEY=VALUE     an override of every variant (before the swept keys)\n"
    "  --lhs N             N variants of a Latin hypercube instead of the grid\n"
    "  --seed S            the hypercube's and the draws' seed (default 1)\n"
    "  --mc N              N Monte Carlo draws of the --disperse keys per grid cell\n"
    "                      (GSL mt19937; variant i's stream seeded from (S, i))\n"
    "  --disperse KEY=DIST a dispersed key (up to 8), a new value per variant\n"
    "  --shard K/N         run only the variants i with i mod N = K-1 (default:\n"
    "                      SLURM_ARRAY_TASK_ID/SLURM_ARRAY_TASK_COUNT when set)\n"
    "  --merge FILE...     join shard summaries of one sweep into -o FILE\n"
    "  --plan              print each variant's values (tab-separated) and exit\n"
    "                      without running anything\n"
    "  -j, --jobs N        worker processes (default: the online cores)\n"
    "  --resume            continue the sweep in FILE: run only what it lacks\n"
    "  --keep-runs DIR     also write each variant's results file DIR/variant_NNNNNN.h5\n"
    "  --until-verdict     end each variant at its verdict (captured or escaped)\n"
    "                      instead of at the scenario's duration\n"
    "  --length L          [m] the gripper's total finger length: positions and the\n"
    "                      region area are normalised by it\n"
    "  -q, --quiet         no progress bar and no summary line\n"
    "  --table FILE        print a summary as columns for gnuplot and exit\n"
    "  -h, --help          this text\n"
    "\n"
    "A variant that fails (numerical failure, work budget, an override its\n"
    "scenario refuses, a crash) is recorded with its reason and the sweep goes on.\n"
    "Ctrl-C (SIGINT) or SIGTERM stops the workers and writes the summary of what\n"
    "finished (exit 130); --resume completes it. Exit 0 when every variant ran\n"
    "(failed ones included), 1 on an error, 2 on a bad command line.\n";

/* ---- the command line ------------------------------------------------------ */

/* K/N, 1 <= K <= N; 0 or -1 */
static int parse_shard(const char *v, long *k, long *n)
{
    const char *sl = strchr(v, '/');
    char a[32];
    if (!sl || (size_t)(sl - v) >= sizeof a) return -1;
    memcpy(a, v, (size_t)(sl - v));
    a[sl - v] = 0;
    if (cli_count(a, k) || cli_count(sl + 1, n) || *n < 1 || *k < 1 || *k > *n) return -1;
    return 0;
}

static int parse(int argc, char **argv, sw_opts *o)
{
    int i, only = 0;
    memset(o, 0, sizeof *o);
    o->seed = 1;
    o->sets = calloc((size_t)argc + 1, sizeof *o->sets);
    if (!o->sets) {
        cli_error("out of memory");
        return CLI_FAIL;
    }
#define VAL(name) (i + 1 < argc ? argv[++i] : NULL)
    for (i = 1; i < argc; i++) {
        const char *a = argv[i], *v;
        if (!only && a[0] == '-' && a[1]) {
            if (!strcmp(a, "--")) { only = 1; continue; }
            if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
                fputs(sweep_help, stdout);
                return -1;
            }
            if (!strcmp(a, "--set")) {
                if (!(v = VAL(a)) || !strchr(v, '=') || v[0] == '=')
                    return cli_usage("sweep", "--set expects KEY=VALUE, got '%s'", v ? v : "");
                o->sets[o->nsets++] = v;
            } else if (!strcmp(a, "--mc")) {
                if (!(v = VAL(a)) || cli_count(v, &o->mc) || o->mc < 1 || o->mc > SW_MAX_VARIANTS)
                    return cli_usage("sweep", "--mc expects a number of draws from 1 to %ld, got '%s'", SW_MAX_VARIANTS,
                                     v ? v : "");
            } else if (!strcmp(a, "--disperse")) {
                if (!(v = VAL(a))) return cli_usage("sweep", "--disperse needs KEY=DIST");
                if (o->ndisp == SW_MAX_DISP) return cli_usage("sweep", "at most %d --disperse keys", SW_MAX_DISP);
                o->disp[o->ndisp++] = v;
            } else if (!strcmp(a, "--shard")) {
                if (!(v = VAL(a)) || parse_shard(v, &o->shard_k, &o->shard_n) != 0)
                    return cli_usage("sweep", "--shard expects K/N with 1 <= K <= N, got '%s'", v ? v : "");
            } else if (!strcmp(a, "--merge")) {
                o->merge = (const char **)&argv[i + 1];
                while (i + 1 < argc && argv[i + 1][0] != '-') {
                    i++;
                    o->nmerge++;
                }
                if (o->nmerge == 0) return cli_usage("sweep", "--merge needs the shard summaries");
            } else if (!strcmp(a, "--vary")) {
                if (!(v = VAL(a))) return cli_usage("sweep", "--vary needs KEY=SPEC");
                if (o->nvary == SW_MAX_VARY) return cli_usage("sweep", "at most %d --vary keys", SW_MAX_VARY);
                o->vary[o->nvary++] = v;
            } else if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
                if (!(v = VAL(a)) || !*v) return cli_usage("sweep", "%s needs a file name", a);
                o->output = v;
            } else if (!strcmp(a, "--keep-runs")) {
                if (!(v = VAL(a)) || !*v) return cli_usage("sweep", "--keep-runs needs a directory");
                o->keep_dir = v;
            } else if (!strcmp(a, "--table")) {
                if (!(v = VAL(a)) || !*v) return cli_usage("sweep", "--table needs a summary file");
                o->table = v;
            } else if (!strcmp(a, "--lhs")) {
                if (!(v = VAL(a)) || cli_count(v, &o->lhs) || o->lhs < 1 || o->lhs > SW_MAX_VARIANTS)
                    return cli_usage("sweep", "--lhs expects a number of variants from 1 to %ld, got '%s'",
                                     SW_MAX_VARIANTS, v ? v : "");
            } else if (!strcmp(a, "--seed")) {
                long s;
                if (!(v = VAL(a)) || cli_count(v, &s))
                    return cli_usage("sweep", "--seed expects a non-negative integer, got '%s'", v ? v : "");
                o->seed = (unsigned long long)s;
            } else if (!strcmp(a, "-j") || !strcmp(a, "--jobs")) {
                if (!(v = VAL(a)) || cli_count(v, &o->jobs) || o->jobs < 1 || o->jobs > SW_MAX_JOBS)
                    return cli_usage("sweep", "%s expects a number of processes from 1 to %d, got '%s'", a,
                                     SW_MAX_JOBS, v ? v : "");
                o->have_jobs = 1;
            } else if (!strcmp(a, "--length")) {
                if (!(v = VAL(a)) || cli_number(v, &o->length) || !(o->length > 0))
                    return cli_usage("sweep", "--length expects a positive length in metres, got '%s'", v ? v : "");
            } else if (!strcmp(a, "--until-verdict")) {
                o->until_verdict = 1;
            } else if (!strcmp(a, "--plan")) {
                o->plan = 1;
            } else if (!strcmp(a, "--resume")) {
                o->resume = 1;
            } else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
                o->quiet = 1;
            } else
                return cli_usage("sweep", "unknown option '%s'", a);
            continue;
        }
        if (o->scenario) return cli_usage("sweep", "unexpected argument '%s' (one scenario per sweep)", a);
        o->scenario = a;
    }
#undef VAL
    if (o->table) return 0;
    if (o->merge) {
        if (o->scenario) return cli_usage("sweep", "--merge takes summaries, not a scenario ('%s')", o->scenario);
        if (!o->output) return cli_usage("sweep", "--merge needs -o MERGED.h5");
        return 0;
    }
    if (!o->scenario) return cli_usage("sweep", "missing the scenario file");
    if (o->mc && !o->ndisp) return cli_usage("sweep", "--mc needs at least one --disperse KEY=DIST");
    if (o->ndisp && !o->mc) return cli_usage("sweep", "--disperse needs --mc N (draws per cell)");
    if (o->mc && o->lhs) return cli_usage("sweep", "--mc combines with a grid, not with --lhs");
    if (o->nvary == 0 && !o->mc)
        return cli_usage("sweep", "nothing to vary: give 1 to %d --vary KEY=SPEC or --mc N", SW_MAX_VARY);
    if (!o->shard_n) { /* a Slurm job array */
        const char *id = getenv("SLURM_ARRAY_TASK_ID"), *cnt = getenv("SLURM_ARRAY_TASK_COUNT");
        long k, n;
        if (id && cnt && *id && *cnt) {
            if (cli_count(id, &k) || cli_count(cnt, &n) || n < 1 || k >= n)
                return cli_usage("sweep",
                                 "SLURM_ARRAY_TASK_ID=%s, SLURM_ARRAY_TASK_COUNT=%s: expected 0 <= ID < COUNT "
                                 "(an array --array=0-(N-1))",
                                 id, cnt);
            o->shard_k = k + 1;
            o->shard_n = n;
        }
    }
    return 0;
}

/* The overrides of every variant, one per line (stored in the summary). */
static char *join_sets(const sw_opts *o)
{
    size_t n = 1;
    int i;
    char *s;
    for (i = 0; i < o->nsets; i++) n += strlen(o->sets[i]) + 1;
    s = malloc(n);
    if (!s) return NULL;
    s[0] = 0;
    for (i = 0; i < o->nsets; i++) {
        strcat(s, o->sets[i]);
        if (i + 1 < o->nsets) strcat(s, "\n");
    }
    return s;
}

/* parse() with stderr silenced on the ranks other than 0 (every rank parses
 * the same command line; only rank 0 says what is wrong with it) */
static int parse_quiet(int argc, char **argv, sw_opts *o, int rank)
{
    int saved = -1, nul, rc;
    if (rank > 0 && (nul = open("/dev/null", O_WRONLY)) >= 0) {
        fflush(stderr);
        saved = dup(STDERR_FILENO);
        dup2(nul, STDERR_FILENO);
        close(nul);
    }
    rc = parse(argc, argv, o);
    if (saved >= 0) {
        fflush(stderr);
        dup2(saved, STDERR_FILENO);
        close(saved);
    }
    return rc;
}

/* ---- the driver ------------------------------------------------------------ */

/* Everything a sweep holds between its steps (sweep_main). */
typedef struct {
    sw_opts o;
    sw_plan p;
    sw_meta meta;
    sw_ctx cx;
    sw_out out;
    sw_result *res;
    cd_scenario *sc;
    char *overrides;
    char outbuf[1024];
    long nrun0, nfail;
} sweep;

/* the default summary: the scenario's base name with _sweep.h5 */
static void default_output(sweep *s)
{
    const char *b = strrchr(s->o.scenario, '/');
    size_t n;
    b = b ? b + 1 : s->o.scenario;
    n = strlen(b);
    if (n > 5 && !strcmp(b + n - 5, ".toml")) n -= 5;
    snprintf(s->outbuf, sizeof s->outbuf, "%.*s_sweep.h5", (int)n, b);
    s->o.output = s->outbuf;
}

/* The base scenario (its text goes into the summary), the summary's place
 * (checked), then the first variant: a misspelt key stops here, not in
 * every variant. CLI_OK or CLI_FAIL (reported). */
static int load_inputs(sweep *s)
{
    cd_error err;
    char msg[2048], **ov;
    cd_scenario *s0 = NULL;
    const char *in[1];
    s->sc = cd_scenario_load(s->o.scenario, s->o.sets, s->o.nsets, &err);
    if (!s->sc) {
        cli_error("%s", err.msg);
        return CLI_FAIL;
    }
    /* the summary: never the scenario, a file another process writes or a
     * non-regular file (checked again, under a lock, at every write) */
    in[0] = s->o.scenario;
    if (sw_out_open(&s->out, s->o.output, in, 1, msg, sizeof msg) != 0) {
        cli_error("%s", msg);
        return CLI_FAIL;
    }
    ov = sw_overrides(s->o.sets, s->o.nsets, &s->p, 0);
    if (ov) s0 = cd_scenario_load(s->o.scenario, (const char **)ov, s->o.nsets + s->p.nkey, &err);
    else snprintf(err.msg, sizeof err.msg, "out of memory");
    sw_overrides_free(ov);
    if (!s0) {
        cli_error("%s (the first variant)", err.msg);
        return CLI_FAIL;
    }
    cd_scenario_free(s0);
    return CLI_OK;
}

/* The results so far (all not run, or what --resume reads), the --keep-runs
 * directory, and the first write of the summary: an unwritable -o fails
 * before any work. CLI_OK or CLI_FAIL (reported). */
static int prepare(sweep *s)
{
    long i;
    char msg[2048];
    s->overrides = join_sets(&s->o);
    s->res = malloc(sizeof *s->res * (size_t)s->p.nvar);
    if (!s->overrides || !s->res) {
        cli_error("out of memory");
        return CLI_FAIL;
    }
    s->meta.scenario = s->o.scenario;
    s->meta.scenario_text = s->sc->text ? s->sc->text : "";
    s->meta.overrides = s->overrides;
    s->meta.length = s->o.length;
    s->meta.until_verdict = s->o.until_verdict;
    for (i = 0; i < s->p.nvar; i++) sw_result_blank(&s->res[i], i);
    if (s->o.resume) {
        if (sw_summary_resume(s->o.output, &s->meta, &s->p, s->res) != 0) return CLI_FAIL;
        for (i = 0; i < s->p.nvar; i++)
            if (s->res[i].status != SW_NOT_RUN) {
                s->nrun0++;
                if (s->res[i].status != 0) s->nfail++;
            }
    }
    if (s->o.keep_dir && mkdir(s->o.keep_dir, 0777) != 0 && errno != EEXIST) {
        cli_error("--keep-runs: cannot create the directory '%s': %s", s->o.keep_dir, strerror(errno));
        return CLI_FAIL;
    }
    if (sw_summary_write(&s->out, &s->meta, &s->p, s->res, 0, 0, msg, sizeof msg) != 0) {
        cli_error("%s", msg);
        return CLI_FAIL;
    }
    return CLI_OK;
}

/* worker processes: -j, else the online cores; never more than the
 * variants left (MPI: one per rank) */
static int job_count(const sweep *s, int size)
{
    int nj;
    long left = s->p.nvar - s->nrun0;
    if (size > 1) return size;
    if (s->o.have_jobs) nj = (int)s->o.jobs;
    else {
        long nc = sysconf(_SC_NPROCESSORS_ONLN);
        nj = nc > 0 ? (int)(nc < SW_MAX_JOBS ? nc : SW_MAX_JOBS) : 1;
    }
    if (nj > left) nj = (int)(left > 0 ? left : 1);
    return nj;
}

/* Runs what is left, writes the final summary and reports; an exit status. */
static int run_and_report(sweep *s, int size, double wall0)
{
    sw_progress pg;
    long ndone = s->nrun0;
    int nj = job_count(s, size), stopped;
    double wall;
    char msg[2048];
    memset(&pg, 0, sizeof pg);
    pg.on = !s->o.quiet && isatty(STDERR_FILENO);
    pg.t0 = cli_wall();
    pg.total = s->p.nvar;
    pg.done0 = s->nrun0;
    sw_draw(&pg, ndone, s->nfail, 1);
    stopped = sw_run(&s->cx, &s->meta, s->res, nj, size, &pg, &ndone, &s->nfail, wall0);
    sw_clear(&pg);
    wall = cli_wall() - wall0;
    if (sw_summary_write(&s->out, &s->meta, &s->p, s->res, nj, wall, msg, sizeof msg) != 0) {
        cli_error("%s", msg);
        return CLI_FAIL;
    }
    if (!s->o.quiet) sw_report_end(&s->o, &s->p, s->res, ndone, s->nfail, s->nrun0, wall, nj);
    if (stopped > 0) {
        fprintf(stderr, "capdyn: sweep stopped by %s: %ld of %ld variants in '%s'; continue with --resume\n",
                stopped == SIGINT ? "SIGINT" : "SIGTERM", ndone, s->p.nvar, s->o.output);
        return CLI_INTERRUPT;
    }
    return stopped < 0 ? CLI_FAIL : CLI_OK;
}

static void sweep_free(sweep *s)
{
    free(s->res);
    free(s->overrides);
    sw_out_close(&s->out);
    cd_scenario_free(s->sc);
    sw_plan_free(&s->p);
    free(s->o.sets);
}

#ifdef CAPDYN_MPI
/* rank 0 tells the worker ranks whether to start (ok) */
static void mpi_go(int ok)
{
    MPI_Bcast(&ok, 1, MPI_INT, 0, MPI_COMM_WORLD);
}
#endif

static int sweep_main(int argc, char **argv, int rank, int size)
{
    sweep s;
    int rc;
    double wall0 = cli_wall();
    memset(&s, 0, sizeof s);
    s.out.lock_fd = -1;
    s.cx.o = &s.o;
    s.cx.p = &s.p;
    s.cx.out = &s.out;
    rc = parse_quiet(argc, argv, &s.o, rank);
    if (rc == 0 && s.o.table) rc = sw_summary_table(s.o.table);
    else if (rc == 0 && s.o.merge) rc = sw_merge(&s.o);
    else if (rc == 0) rc = sw_plan_make_mc(&s.p, s.o.vary, s.o.nvary, s.o.lhs, s.o.seed, s.o.disp, s.o.ndisp, s.o.mc);
    else if (rc < 0) rc = CLI_OK; /* --help */
    if (rc != 0 || s.o.table || s.o.merge) {
        free(s.o.sets);
        return rc;
    }
    if (s.o.plan) { /* the plan only: variant, then each key's value */
        long i;
        int k;
        printf("variant");
        for (k = 0; k < s.p.nkey; k++) printf("\t%s", s.p.key[k].key);
        printf("\n");
        for (i = 0; i < s.p.nvar; i++) {
            printf("%ld", i);
            for (k = 0; k < s.p.nkey; k++) printf("\t%s", s.p.val[i * s.p.nkey + k]);
            printf("\n");
        }
        fflush(stdout);
        sweep_free(&s);
        return CLI_OK;
    }
    if (!s.o.output) default_output(&s);
#ifdef CAPDYN_MPI
    if (rank > 0) { /* a worker rank: run what rank 0 hands out, once it has checked the sweep */
        int ok = 0;
        MPI_Bcast(&ok, 1, MPI_INT, 0, MPI_COMM_WORLD);
        if (ok) sw_mpi_worker(&s.cx);
        sweep_free(&s);
        return ok ? CLI_OK : CLI_FAIL;
    }
#endif
    /* SIGXFSZ (file size limit, ulimit -f) would kill the sweep in the middle
     * of a write and leave its temporary file: ignored, the write fails
     * with EFBIG and is reported (workers inherit this, as capdyn run) */
    signal(SIGXFSZ, SIG_IGN);
    rc = load_inputs(&s);
    if (rc == CLI_OK) rc = prepare(&s);
#ifdef CAPDYN_MPI
    if (size > 1) mpi_go(rc == CLI_OK); /* the worker ranks start, or are told there is nothing to do */
#endif
    if (rc == CLI_OK) rc = run_and_report(&s, size, wall0);
#ifdef CAPDYN_MPI
    /* stopped: the summary is written; end the ranks still running a variant */
    if (size > 1 && rc == CLI_INTERRUPT) {
        fflush(NULL);
        MPI_Abort(MPI_COMM_WORLD, CLI_INTERRUPT);
    }
#endif
    fflush(stdout);
    sweep_free(&s);
    return rc;
}

/* Under an MPI launcher (mpirun, srun) in a build with MPI (make MPI=1),
 * rank 0 hands out the variants and writes the summary, the other ranks run
 * them; elsewhere, worker processes on this machine (docs/sweep.md). */
int cmd_sweep(int argc, char **argv)
{
#ifdef CAPDYN_MPI
    if (sw_under_mpi()) {
        int rank = 0, size = 1, rc;
        MPI_Init(&argc, &argv);
        MPI_Comm_rank(MPI_COMM_WORLD, &rank);
        MPI_Comm_size(MPI_COMM_WORLD, &size);
        rc = sweep_main(argc, argv, rank, size);
        MPI_Finalize();
        return rc;
    }
#endif
    return sweep_main(argc, argv, 0, 1);
}

