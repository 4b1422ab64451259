/* capdyn sweep: running the variants (docs/sweep.md, "How it runs").
 *
 * Variants run in worker processes (fork; HDF5 is not thread-safe and a
 * variant that crashes takes only its worker down), handed out one at a
 * time (dynamic distribution) through a pipe per worker; each worker loads
 * the scenario with the variant's overrides (cd_scenario_load) and runs the
 * loop of capdyn run (cli_run_loop) without a results file unless
 * --keep-runs. Results come back as fixed-size records and are stored by
 * variant index, so the summary does not depend on -j or on the order in
 * which variants finish. Under MPI (make MPI=1) rank 0 hands out the
 * variants to the other ranks the same way. The summary is checkpointed
 * every SW_CHECKPOINT seconds. */
#define _POSIX_C_SOURCE 200809L
#include "sweep.h"

#include <errno.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#ifdef CAPDYN_MPI
#include <mpi.h>
#endif

static volatile sig_atomic_t g_stop = 0;
static void on_stop(int sig) { g_stop = sig; }

/* ---- one variant ---------------------------------------------------------- */

/* The outcome of a finished run into r: counters, the largest step force,
 * the monitor's verdict and figures of merit; closes w (its failure, on an
 * otherwise good run, becomes the variant's). */
static void variant_outcome(const sw_ctx *cx, cd_scenario *sc, cd_data *d, cd_h5_writer *w, const cd_monitor *mon,
                            const cd_ctrl *ctl, const cd_ctrl_merit *merit, const run_ctx *ctx, cd_status st,
                            const cd_error *err, sw_result *r)
{
    int k;
    (void)cx;
    r->status = (int)st;
    if (st != CD_OK) snprintf(r->reason, sizeof r->reason, "%s", err->msg);
    r->t_final = d->t;
    r->nrhs = d->stats.nrhs;
    r->nsteps = d->stats.nsteps;
    r->nevents = d->ev_count;
    r->fn_step_max = 0;
    for (k = 0; k < sc->model->nslot; k++)
        if (ctx->fn_max[k] > r->fn_step_max) r->fn_step_max = ctx->fn_max[k];
    if (mon) {
        cd_h5_capture cap;
        cli_capture_of(mon, ctl, ctl ? merit : NULL, sc->model, d, &cap);
        r->verdict = (int)mon->verdict;
        r->t_capture = mon->t_capture;
        r->t_escape = mon->t_escape;
        r->t_cage = mon->t_cage;
        r->peak_fn = cap.peak_fn;
        r->peak_tau = cap.peak_tau;
        r->epsilon = cap.epsilon;
        memcpy(r->offset, cap.offset, sizeof r->offset);
        r->n_stick = cap.n_stick;
        r->n_slip = cap.n_slip;
        if (w) cd_h5_set_capture(w, &cap);
    }
    if (w) {
        cd_h5_step_peaks pk = {ctx->fn_max, ctx->fn_body, ctx->fn_onset, ctx->ft_max, ctx->t_body, ctx->t_onset};
        cd_h5_set_step_peaks(w, sc->model->nslot, &pk);
    }
    if (w) {
        cd_error cerr;
        char msg[SW_REASON + 64];
        if (st == CD_OK) snprintf(msg, sizeof msg, "finished at t = %.9g s", d->t);
        else snprintf(msg, sizeof msg, "%s", r->reason);
        if (cd_h5_close(w, sc->model, d, st, msg, &cerr) != CD_OK && r->status == CD_OK) {
            r->status = CD_EIO;
            snprintf(r->reason, sizeof r->reason, "%s", cerr.msg);
        }
    }
}

int sw_todo(const sw_ctx *cx, const sw_result *res, long i)
{
    const sw_opts *o = cx->o;
    return res[i].status == SW_NOT_RUN && (o->shard_n < 1 || i % o->shard_n == o->shard_k - 1);
}

void sw_run_variant(const sw_ctx *cx, long idx, sw_result *r)
{
    const sw_plan *p = cx->p;
    int have_mon = 0;
    char **ov = sw_overrides(cx->o->sets, cx->o->nsets, p, idx);
    cd_scenario *sc = NULL;
    cd_data *d = NULL;
    cd_h5_writer *w = NULL;
    cd_monitor mon;
    cd_error err;
    run_ctx ctx;
    cd_status st;
    cd_ctrl *ctl = NULL;
    cd_ctrl_merit merit;
    char wmsg[512], path[4096];
    double t0 = cli_wall();
    sw_result_blank(r, idx);
    memset(&ctx, 0, sizeof ctx);
    if (!ov) {
        r->status = CD_ENOMEM;
        snprintf(r->reason, sizeof r->reason, "out of memory");
        goto out;
    }
    sc = cd_scenario_load(cx->o->scenario, (const char **)ov, cx->o->nsets + p->nkey, &err);
    if (!sc) {
        r->status = SW_ELOAD;
        snprintf(r->reason, sizeof r->reason, "%s", err.msg);
        goto out;
    }
    if (!(sc->duration > 0) || !(sc->output_dt > 0) || !isfinite(sc->duration) ||
        !(sc->duration / sc->output_dt <= 1e9)) {
        r->status = SW_ELOAD;
        snprintf(r->reason, sizeof r->reason, "duration and output_dt must be positive, at most 1e9 samples");
        goto out;
    }
    d = cd_data_create(sc->model, sc->event_capacity, &err);
    if (!d) {
        r->status = err.status ? (int)err.status : CD_ENOMEM;
        snprintf(r->reason, sizeof r->reason, "%s", err.msg);
        goto out;
    }
    /* the scenario's built-in controller ([control], docs/capture.md), as capdyn run */
    if (sc->control) {
        ctl = cd_ctrl_create(sc->model, sc->control, &err);
        if (!ctl) {
            r->status = SW_ELOAD;
            snprintf(r->reason, sizeof r->reason, "%s", err.msg);
            goto out;
        }
        cd_ctrl_install(ctl, d);
    }
    if (cx->o->keep_dir) {
        snprintf(path, sizeof path, "%s/variant_%06ld.h5", cx->o->keep_dir, idx);
        w = cd_h5_create(path, sc->model, sc, &err);
        if (!w) {
            r->status = CD_EIO;
            snprintf(r->reason, sizeof r->reason, "%s", err.msg);
            goto out;
        }
    }
    ctx.fn_max = calloc((size_t)(sc->model->nslot ? sc->model->nslot : 1), sizeof(double));
    ctx.ft_max = calloc((size_t)(sc->model->nslot ? sc->model->nslot : 1), sizeof(double));
    /* the onset transients apart (cli.h), as capdyn run: a kept run's file
     * (--keep-runs) stores the peaks over steps that capdyn run prints */
    ctx.fn_onset = calloc((size_t)(sc->model->nslot ? sc->model->nslot : 1), sizeof(double));
    ctx.fn_body = calloc((size_t)(sc->model->nslot ? sc->model->nslot : 1), sizeof(double));
    ctx.t_onset = cli_nan_array(sc->model->nslot);
    ctx.t_body = cli_nan_array(sc->model->nslot);
    ctx.onset = malloc((size_t)(sc->model->nslot ? sc->model->nslot : 1));
    if (ctx.onset) memset(ctx.onset, 1, (size_t)(sc->model->nslot ? sc->model->nslot : 1));
    ctx.t_end = sc->duration;
    ctx.wall0 = t0;
    ctx.last_draw = -1e300;
    ctx.max_wall = sc->max_wall_time;
    ctx.max_rhs = sc->max_rhs_evals;
    ctx.until_verdict = cx->o->until_verdict;
    ctx.ctl = ctl;
    ctx.merit = ctl ? &merit : NULL;
    if (!ctx.fn_max || !ctx.ft_max || !ctx.fn_onset || !ctx.fn_body || !ctx.t_onset || !ctx.t_body || !ctx.onset) {
        r->status = CD_ENOMEM;
        snprintf(r->reason, sizeof r->reason, "out of memory");
        goto out;
    }
    have_mon = sc->capture_hand >= 0 && sc->capture_object >= 0;
    if (have_mon) {
        cd_monitor_opts mop = cd_scenario_monitor_opts(sc);
        if (cd_monitor_init(&mon, sc->model, d, &mop, &err) != CD_OK) {
            r->status = err.status;
            snprintf(r->reason, sizeof r->reason, "%s", err.msg);
            goto out;
        }
        cd_monitor_update(&mon, sc->model, d);
    }
    st = cli_run_loop(sc, d, w, have_mon ? &mon : NULL, &ctx, &err, wmsg, sizeof wmsg);
    variant_outcome(cx, sc, d, w, have_mon ? &mon : NULL, ctl, &merit, &ctx, st, &err, r);
    w = NULL;
out:
    if (w) cd_h5_close(w, sc->model, d, (cd_status)r->status, r->reason, NULL);
    free(ctx.fn_max);
    free(ctx.ft_max);
    free(ctx.fn_onset);
    free(ctx.fn_body);
    free(ctx.t_onset);
    free(ctx.t_body);
    free(ctx.onset);
    cd_data_free(d);
    cd_ctrl_free(ctl);
    cd_scenario_free(sc);
    sw_overrides_free(ov);
    r->wall = cli_wall() - t0;
}

/* ---- worker processes ----------------------------------------------------- */

static int write_full(int fd, const void *buf, size_t n)
{
    const char *p = buf;
    while (n > 0) {
        ssize_t w = write(fd, p, n);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) return -1;
        p += w;
        n -= (size_t)w;
    }
    return 0;
}
/* 1 read, 0 end of file, -1 error */
static int read_full(int fd, void *buf, size_t n)
{
    char *p = buf;
    size_t got = 0;
    while (got < n) {
        ssize_t r = read(fd, p + got, n - got);
        if (r < 0 && errno == EINTR) continue;
        if (r < 0) return -1;
        if (r == 0) return got == 0 ? 0 : -1;
        got += (size_t)r;
    }
    return 1;
}

typedef struct {
    pid_t pid;
    int task_fd, res_fd; /* parent's ends */
    long busy;           /* variant being run, -1 idle */
} sw_worker;

static void worker_loop(const sw_ctx *cx, int task_fd, int res_fd)
{
    long idx;
    sw_result r;
    /* the parent decides about SIGINT (the terminal sends it to the whole
     * group); SIGTERM from the parent ends the worker */
    signal(SIGINT, SIG_IGN);
    signal(SIGTERM, SIG_DFL);
    signal(SIGPIPE, SIG_DFL);
    while (read_full(task_fd, &idx, sizeof idx) == 1 && idx >= 0) {
        sw_run_variant(cx, idx, &r);
        if (write_full(res_fd, &r, sizeof r) != 0) break;
    }
    _exit(0);
}

static int spawn_worker(const sw_ctx *cx, sw_worker *wk, sw_worker *all, int nall)
{
    int tp[2], rp[2], i;
    if (pipe(tp) != 0) return -1;
    if (pipe(rp) != 0) {
        close(tp[0]);
        close(tp[1]);
        return -1;
    }
    fflush(NULL);
    wk->pid = fork();
    if (wk->pid < 0) {
        close(tp[0]);
        close(tp[1]);
        close(rp[0]);
        close(rp[1]);
        return -1;
    }
    if (wk->pid == 0) {
        for (i = 0; i < nall; i++) /* the other workers' pipes */
            if (&all[i] != wk && all[i].pid > 0) {
                close(all[i].task_fd);
                close(all[i].res_fd);
            }
        close(tp[1]);
        close(rp[0]);
        /* the summary's lock is the parent's: a worker that outlives a
         * killed parent must not keep it (--resume would be refused) */
        if (cx->out && cx->out->lock_fd >= 0) close(cx->out->lock_fd);
        worker_loop(cx, tp[0], rp[1]);
    }
    close(tp[0]);
    close(rp[1]);
    wk->task_fd = tp[1];
    wk->res_fd = rp[0];
    wk->busy = -1;
    return 0;
}

static void stop_worker(sw_worker *wk, int kill_it)
{
    int st;
    if (wk->pid <= 0) return;
    if (kill_it) kill(wk->pid, SIGTERM);
    close(wk->task_fd);
    close(wk->res_fd);
    while (waitpid(wk->pid, &st, 0) < 0 && errno == EINTR) {
    }
    wk->pid = -1;
}

/* Runs the variants not yet run (res[i].status == SW_NOT_RUN) on nj worker
 * processes; writes checkpoints. Returns 0, or the signal that stopped it. */
static int run_local(const sw_ctx *cx, const sw_meta *meta, sw_result *res, int nj, sw_progress *pg, long *ndone,
                     long *nfail, double wall0)
{
    const sw_plan *p = cx->p;
    sw_worker *wk = calloc((size_t)nj, sizeof *wk);
    struct pollfd *pf = calloc((size_t)nj, sizeof *pf);
    long next = 0, inflight = 0, i;
    double last_ckpt = cli_wall();
    int j, stopped = 0;
    char msg[1024];
    if (!wk || !pf) {
        free(wk);
        free(pf);
        cli_error("out of memory");
        return -1;
    }
    for (j = 0; j < nj; j++) { /* no process, no variant: stop_worker and the clean-up below skip it */
        wk[j].pid = -1;
        wk[j].busy = -1;
    }
    for (;;) {
        /* hand out work: one variant per idle worker */
        for (j = 0; j < nj && !g_stop; j++) {
            while (next < p->nvar && !sw_todo(cx, res, next)) next++;
            if (next >= p->nvar) break;
            if (wk[j].pid <= 0 && spawn_worker(cx, &wk[j], wk, nj) != 0) {
                cli_error("cannot start a worker process: %s", strerror(errno));
                g_stop = -1;
                break;
            }
            if (wk[j].busy >= 0) continue;
            if (write_full(wk[j].task_fd, &next, sizeof next) != 0) {
                stop_worker(&wk[j], 1); /* respawned above next time */
                continue;
            }
            wk[j].busy = next++;
            inflight++;
        }
        if (inflight == 0 || g_stop) break;
        for (j = 0; j < nj; j++) {
            pf[j].fd = wk[j].busy >= 0 ? wk[j].res_fd : -1;
            pf[j].events = POLLIN;
            pf[j].revents = 0;
        }
        if (poll(pf, (nfds_t)nj, 200) < 0 && errno != EINTR) {
            cli_error("poll: %s", strerror(errno));
            g_stop = -1;
            break;
        }
        for (j = 0; j < nj; j++) {
            sw_result r;
            int rr;
            if (wk[j].busy < 0 || !(pf[j].revents & (POLLIN | POLLHUP | POLLERR))) continue;
            rr = read_full(wk[j].res_fd, &r, sizeof r);
            if (rr == 1 && r.index == wk[j].busy) {
                res[r.index] = r;
            } else { /* the worker died running it */
                int st = 0;
                long idx = wk[j].busy;
                kill(wk[j].pid, SIGKILL);
                close(wk[j].task_fd);
                close(wk[j].res_fd);
                while (waitpid(wk[j].pid, &st, 0) < 0 && errno == EINTR) {
                }
                wk[j].pid = -1;
                sw_result_blank(&res[idx], idx);
                res[idx].status = SW_ECRASH;
                if (WIFSIGNALED(st))
                    snprintf(res[idx].reason, sizeof res[idx].reason, "the worker process died: %s (signal %d)",
                             strsignal(WTERMSIG(st)), WTERMSIG(st));
                else
                    snprintf(res[idx].reason, sizeof res[idx].reason, "the worker process ended without a result");
                res[idx].wall = NAN;
            }
            if (res[wk[j].busy].status != 0) (*nfail)++;
            wk[j].busy = -1;
            inflight--;
            (*ndone)++;
        }
        sw_draw(pg, *ndone, *nfail, 0);
        if (cli_wall() - last_ckpt >= SW_CHECKPOINT) {
            if (sw_summary_write(cx->out, meta, p, res, nj, cli_wall() - wall0, msg, sizeof msg) != 0)
                cli_error("%s", msg);
            last_ckpt = cli_wall();
        }
    }
    stopped = g_stop;
    for (j = 0; j < nj; j++) {
        if (wk[j].busy >= 0) { /* interrupted: not run */
            sw_result_blank(&res[wk[j].busy], wk[j].busy);
        }
        stop_worker(&wk[j], wk[j].busy >= 0 || stopped);
    }
    (void)i;
    free(wk);
    free(pf);
    return stopped;
}

#ifdef CAPDYN_MPI
/* ---- MPI (make MPI=1) ------------------------------------------------------ */

#define SW_TAG_TASK 1
#define SW_TAG_RESULT 2

/* Started by an MPI launcher (Open MPI's mpirun, PMI/PMIx: Slurm's srun)? */
int sw_under_mpi(void)
{
    return getenv("OMPI_COMM_WORLD_SIZE") || getenv("PMI_SIZE") || getenv("PMIX_RANK") || getenv("PMI_RANK");
}

void sw_mpi_worker(const sw_ctx *cx)
{
    long idx;
    sw_result r;
    /* rank 0 decides (a launcher or Slurm's time limit signals every rank):
     * it writes the summary, then aborts the job */
    signal(SIGINT, SIG_IGN);
    signal(SIGTERM, SIG_IGN);
    for (;;) {
        MPI_Recv(&idx, 1, MPI_LONG, 0, SW_TAG_TASK, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        if (idx < 0) break;
        sw_run_variant(cx, idx, &r);
        MPI_Send(&r, (int)sizeof r, MPI_BYTE, 0, SW_TAG_RESULT, MPI_COMM_WORLD);
    }
}

/* Rank 0: one variant at a time to each idle rank (dynamic distribution),
 * results stored by index; checkpoints as run_local. */
static int run_mpi(const sw_ctx *cx, const sw_meta *meta, sw_result *res, int size, sw_progress *pg, long *ndone,
                   long *nfail, double wall0)
{
    const sw_plan *p = cx->p;
    long next = 0, stop = -1, *busy = malloc(sizeof(long) * (size_t)size);
    int inflight = 0, r;
    double last_ckpt = cli_wall();
    char msg[1024];
    if (!busy) {
        cli_error("out of memory");
        MPI_Abort(MPI_COMM_WORLD, CLI_FAIL);
    }
    for (r = 1; r < size; r++) {
        while (next < p->nvar && !sw_todo(cx, res, next)) next++;
        busy[r] = next < p->nvar ? next++ : -1;
        if (busy[r] >= 0) inflight++;
        MPI_Send(busy[r] >= 0 ? &busy[r] : &stop, 1, MPI_LONG, r, SW_TAG_TASK, MPI_COMM_WORLD);
    }
    while (inflight > 0 && !g_stop) {
        int flag = 0;
        MPI_Status st;
        sw_result x;
        MPI_Iprobe(MPI_ANY_SOURCE, SW_TAG_RESULT, MPI_COMM_WORLD, &flag, &st);
        if (!flag) {
            struct timespec ts = {0, 5000000L};
            nanosleep(&ts, NULL);
        } else {
            r = st.MPI_SOURCE;
            MPI_Recv(&x, (int)sizeof x, MPI_BYTE, r, SW_TAG_RESULT, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
            if (x.index >= 0 && x.index < p->nvar) res[x.index] = x;
            if (x.status != 0) (*nfail)++;
            (*ndone)++;
            inflight--;
            while (next < p->nvar && !sw_todo(cx, res, next)) next++;
            busy[r] = next < p->nvar ? next++ : -1;
            if (busy[r] >= 0) inflight++;
            MPI_Send(busy[r] >= 0 ? &busy[r] : &stop, 1, MPI_LONG, r, SW_TAG_TASK, MPI_COMM_WORLD);
        }
        sw_draw(pg, *ndone, *nfail, 0);
        if (cli_wall() - last_ckpt >= SW_CHECKPOINT) {
            if (sw_summary_write(cx->out, meta, p, res, size, cli_wall() - wall0, msg, sizeof msg) != 0)
                cli_error("%s", msg);
            last_ckpt = cli_wall();
        }
    }
    if (g_stop) /* the variants still running are not run; MPI_Abort ends them after the summary */
        for (r = 1; r < size; r++)
            if (busy[r] >= 0) sw_result_blank(&res[busy[r]], busy[r]);
    free(busy);
    return g_stop;
}
#endif

int sw_run(const sw_ctx *cx, const sw_meta *meta, sw_result *res, int nj, int size, sw_progress *pg, long *ndone,
           long *nfail, double wall0)
{
    struct sigaction sa, old_int, old_term, old_pipe;
    int stopped;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old_int);
    sigaction(SIGTERM, &sa, &old_term);
    sa.sa_handler = SIG_IGN;
    sigaction(SIGPIPE, &sa, &old_pipe);
    g_stop = 0;
#ifdef CAPDYN_MPI
    if (size > 1) stopped = run_mpi(cx, meta, res, size, pg, ndone, nfail, wall0);
    else
#endif
        stopped = run_local(cx, meta, res, nj, pg, ndone, nfail, wall0);
    (void)size;
    sigaction(SIGINT, &old_int, NULL);
    sigaction(SIGTERM, &old_term, NULL);
    sigaction(SIGPIPE, &old_pipe, NULL);
    return stopped;
}
