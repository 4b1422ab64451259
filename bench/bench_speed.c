/* capdyn vs MuJoCo, side by side (issue 11; `make bench`, docs/performance.md).
 *
 *  1. Scenes, interleaved, R repetitions (default 5), each run in a fresh
 *     process (fork + exec) so that its peak resident memory is its own:
 *       grasp   scenarios/paper_fig5_envelope_grasp.toml (as written: rtol
 *               1e-8; make bench's first pass sets rtol 1e-6) and its
 *               twin bench/mjcf/fig5_grasp.xml: 2 s closing + 10 s hold
 *               (--hold S);
 *               accuracy: object offset over the hold and creep rate
 *       incline bench/incline.toml and bench/mjcf/incline.xml, 10 s;
 *               accuracy: drift along the slope between t = 1 s and 10 s
 *       capture bench/capture_twin.toml and bench/mjcf/capture.xml: a
 *               free-floating chaser (arm held by joint PD torques) and a
 *               tumbling target drifting into its gripper, which closes at
 *               0.5 s; 4 s; accuracy: the bar's offset from the palm at the
 *               end, its speed relative to the palm over the last 0.5 s,
 *               whether it is held, and the drift of the whole system's
 *               linear and angular momentum (no external force)
 *     Table: wall time per simulated second, real-time factor (RTF),
 *     capdyn RTF / MuJoCo RTF per repetition (min, median), steps, rhs
 *     evaluations (MuJoCo: one mj_forward per mj_step), peak RSS and heap.
 *  2. Forward dynamics of free-floating chains, 1 to 64 joints: capdyn
 *     cd_kinematics + cd_forward_dynamics_method (CRBA, ABA) vs MuJoCo
 *     mj_forward (no contacts), ns per call, min and median over 3 x R
 *     interleaved repetitions; the crossover CRBA -> ABA is read from the
 *     minima of this table.
 *
 * capdyn is driven only through its public headers (include/capdyn/ headers).
 * Usage: bench_speed [-r reps] [-o results.txt] [--hold S] [--fd-only] [--scenes-only]
 *                    [--scene grasp|incline|capture] (repeatable: only those scenes)
 * (run from the repository root). */
#include <capdyn/capdyn.h>
#include <capdyn/io.h>
#include "bench_chain.h"
#include <gsl/gsl_errno.h>
#include <mujoco/mujoco.h>

#include <malloc.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/time.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#define MAXREP 64

#include "bench_util.h"

static double now(void) { return clock_s(CLOCK_MONOTONIC); }

static double median_of(const double *v, int n)
{
    double t[MAXREP];
    memcpy(t, v, (size_t)n * sizeof *v);
    qsort(t, (size_t)n, sizeof *t, cmp_double);
    return n % 2 ? t[n / 2] : 0.5 * (t[n / 2 - 1] + t[n / 2]);
}
static double min_of(const double *v, int n)
{
    double r = v[0];
    int i;
    for (i = 1; i < n; i++)
        if (v[i] < r) r = v[i];
    return r;
}

static long heap_bytes(void)
{
    struct mallinfo2 mi = mallinfo2();
    return (long)(mi.uordblks + mi.hblkhd);
}

/* ---- scenes ------------------------------------------------------------- */
enum { ENG_CAPDYN = 0, ENG_MUJOCO = 1 };
enum { SC_GRASP = 0, SC_INCLINE = 1, SC_CAPTURE = 2, NSCENE = 3 };
static const char *scene_name[NSCENE] = {"grasp", "incline", "capture"};
static const char *scene_toml[NSCENE] = {"scenarios/paper_fig5_envelope_grasp.toml", "bench/incline.toml",
                                         "bench/capture_twin.toml"};
static const char *scene_xml[NSCENE] = {"bench/mjcf/fig5_grasp.xml", "bench/mjcf/incline.xml", "bench/mjcf/capture.xml"};
/* the system (capdyn) / body (MuJoCo) whose position the accuracy figure follows */
static const char *scene_body[NSCENE] = {"object", "block", "target"};
static const double T_CLOSE = 2.0, T_INCLINE = 10.0, T_SETTLE = 1.0;
static double T_HOLD = 10.0; /* --hold S */

/* capture scene: the fingers close at CAP_CLOSE; the run ends at CAP_END; the
 * relative speed is measured over [CAP_LAST, CAP_END]. Finger torques from
 * CAP_CLOSE (MuJoCo's ctrl; the twin check compares them with the TOML's
 * "steps" tables), the bar's centre in the target's frame and the palm face's
 * centre in the wrist_roll frame (bench/capture_twin.toml). */
static const double CAP_CLOSE = 0.5, CAP_LAST = 3.5, CAP_END = 4.0;
static const char *cap_finger[4] = {"left1", "left2", "right1", "right2"};
static const double cap_tau[4] = {0.4, 0.1, 0.4, 0.1};
static const char *cap_arm[6] = {"shoulder_yaw", "upper_arm", "forearm", "wrist_pitch", "wrist_yaw", "wrist_roll"};
static const double cap_bar[3] = {-0.95, 0.0, 0.0}, cap_palm[3] = {0.14, 0.0, 0.0};
/* held: the bar's centre between the finger bases (|y| < 0.05 m), within the
 * fingers' length of the palm face (x < 0.15 m) and the bar still across the
 * fingers' plane (|z| < its half length 0.15 m), palm frame */
static int cap_held(const double r[3]) { return fabs(r[1]) < 0.05 && r[0] < 0.15 && fabs(r[2]) < 0.15; }

/* scene times: [0] end of the first segment (grasp: closing; incline:
 * settling; capture: the fingers close), [1] start of the span of the rate,
 * [2] end */
static void scene_times(int scene, double t[3])
{
    if (scene == SC_CAPTURE) { t[0] = CAP_CLOSE; t[1] = CAP_LAST; t[2] = CAP_END; return; }
    t[0] = scene == SC_GRASP ? T_CLOSE : T_SETTLE;
    t[2] = scene == SC_GRASP ? T_CLOSE + T_HOLD : T_INCLINE;
    t[1] = 0.5 * (t[0] + t[2]);
}

/* what a child reports back through its pipe */
typedef struct {
    int ok;
    double wall;      /* [s] of the simulation calls only */
    double tsim;      /* simulated [s] */
    long steps, nrhs;
    long heap;        /* heap in use by the engine's model + data [B] */
    long hwm_kb;      /* peak resident memory of the run's process (VmHWM) [kB] */
    double acc;       /* grasp: object offset over the hold; incline: drift [m] */
    double rate;      /* the same over the second half of that span, per second [m/s] */
    double pos[3];    /* final object / block / target position [m] */
    /* capture scene */
    double rel[3];    /* the bar's centre relative to the palm face's centre at the end, palm frame [m] */
    double P0, L0;    /* |linear momentum|, |angular momentum about the common CoM| at t = 0 */
    double dP, dL;    /* their change from t = 0 to the end, |.|, largest of the segment ends */
    char msg[1100];
} run_result;

/* object/block position of a capdyn run: the free system's base */
static void capdyn_pos(const cd_model *m, const cd_data *d, int s, double p[3])
{
    cd_sys_state st = cd_state_of(m, d, s);
    memcpy(p, st.pos, 3 * sizeof(double));
}

static double dist3(const double a[3], const double b[3])
{
    double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

/* R^T (p - o), R a row-major rotation body -> world, o the body origin: world point p in the body frame;
 * from_frame: the reverse, body point p in the world */
static void to_frame(const double *R, const double o[3], const double p[3], double r[3])
{
    int i;
    for (i = 0; i < 3; i++)
        r[i] = R[i] * (p[0] - o[0]) + R[3 + i] * (p[1] - o[1]) + R[6 + i] * (p[2] - o[2]);
}
static void from_frame(const double *R, const double o[3], const double p[3], double w[3])
{
    int i;
    for (i = 0; i < 3; i++) w[i] = o[i] + R[3 * i] * p[0] + R[3 * i + 1] * p[1] + R[3 * i + 2] * p[2];
}
static double norm3(const double a[3]) { return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

/* capture scene, capdyn: the bar's centre relative to the palm face's
 * centre (palm frame) and the whole model's linear momentum and angular
 * momentum about the common CoM */
static void capdyn_capture_measure(const cd_model *m, cd_data *d, double rel[3], double P[3], double L[3])
{
    int palm = cd_model_body_id(m, "chaser/wrist_roll"), tgt = cd_model_body_id(m, "target"), s, k;
    double bar[3], pw[3], mc[3] = {0, 0, 0}, mt = 0;
    cd_kinematics(m, d);
    from_frame(d->body_R + 9 * tgt, d->body_x + 3 * tgt, cap_bar, bar);
    to_frame(d->body_R + 9 * palm, d->body_x + 3 * palm, bar, pw);
    for (k = 0; k < 3; k++) { rel[k] = pw[k] - cap_palm[k]; P[k] = L[k] = 0; }
    for (s = 0; s < m->nsys; s++) {
        double ps[3], lo[3], c[3], ms = 0;
        int b;
        cd_momentum(m, d, s, NULL, ps, NULL, lo, c);
        for (b = 0; b < m->nbody; b++)
            if (m->body_sys[b] == s) ms += m->body_mass[b];
        for (k = 0; k < 3; k++) { P[k] += ps[k]; L[k] += lo[k]; mc[k] += ms * c[k]; }
        mt += ms;
    }
    /* about the common CoM c: L_c = L_origin - c x P */
    for (k = 0; k < 3; k++) mc[k] /= mt;
    L[0] -= mc[1] * P[2] - mc[2] * P[1];
    L[1] -= mc[2] * P[0] - mc[0] * P[2];
    L[2] -= mc[0] * P[1] - mc[1] * P[0];
}

/* the same for MuJoCo (after mj_forward: world body 0's subtree is the whole
 * model; subtree_angmom is about the subtree's CoM) */
static void mujoco_capture_measure(const mjModel *m, mjData *d, double rel[3], double P[3], double L[3])
{
    int palm = mj_name2id(m, mjOBJ_BODY, "wrist_roll"), tgt = mj_name2id(m, mjOBJ_BODY, "target"), k;
    double bar[3], pw[3];
    mj_forward(m, d);
    mj_subtreeVel(m, d);
    from_frame(d->xmat + 9 * tgt, d->xpos + 3 * tgt, cap_bar, bar);
    to_frame(d->xmat + 9 * palm, d->xpos + 3 * palm, bar, pw);
    for (k = 0; k < 3; k++) {
        rel[k] = pw[k] - cap_palm[k];
        P[k] = m->body_subtreemass[0] * d->subtree_linvel[k];
        L[k] = d->subtree_angmom[k];
    }
}

/* the capture figures from the measurements at t = 0 and the segment ends */
static void capture_figures(run_result *r, double P[4][3], double L[4][3], double rel[4][3],
                            const double tseg[3])
{
    int k;
    r->P0 = norm3(P[0]);
    r->L0 = norm3(L[0]);
    r->dP = r->dL = 0;
    for (k = 1; k < 4; k++) {
        double dp[3] = {P[k][0] - P[0][0], P[k][1] - P[0][1], P[k][2] - P[0][2]};
        double dl[3] = {L[k][0] - L[0][0], L[k][1] - L[0][1], L[k][2] - L[0][2]};
        r->dP = fmax(r->dP, norm3(dp));
        r->dL = fmax(r->dL, norm3(dl));
    }
    memcpy(r->rel, rel[3], sizeof r->rel);
    r->acc = norm3(rel[3]);
    r->rate = dist3(rel[3], rel[2]) / (tseg[2] - tseg[1]);
}

/* Extra scenario overrides for both capdyn scenes from the environment:
 * CAPDYN_BENCH_SET='simulation.integrator="ros34pw2";simulation.h_max=0.05'
 * (';'-separated, at most 7), e.g. to bench another stepper. */
static int bench_overrides(const char **ovr, int n, char *buf, size_t len)
{
    const char *env = getenv("CAPDYN_BENCH_SET");
    char *p;
    if (!env || !*env) return n;
    snprintf(buf, len, "%s", env);
    for (p = strtok(buf, ";"); p && n < 8; p = strtok(NULL, ";"))
        if (*p) ovr[n++] = p;
    return n;
}

static void run_capdyn(int scene, run_result *r)
{
    const char *ovr[8];
    char ovbuf[1024];
    int nov = 0;
    cd_error e;
    long h0 = heap_bytes();
    cd_scenario *sc;
    cd_data *d;
    int s;
    double t0, tseg[3];
    cd_status st;
    scene_times(scene, tseg);
    nov = bench_overrides(ovr, nov, ovbuf, sizeof ovbuf);
    sc = cd_scenario_load(scene_toml[scene], ovr, nov, &e);
    if (!sc) { snprintf(r->msg, sizeof r->msg, "%s", e.msg); return; }
    d = cd_data_create(sc->model, sc->event_capacity, &e);
    if (!d) { snprintf(r->msg, sizeof r->msg, "%s", e.msg); cd_scenario_free(sc); return; }
    r->heap = heap_bytes() - h0;
    s = cd_model_system_id(sc->model, scene_body[scene]);
    {
        /* three segments: to tseg[0], to tseg[1], to the end; only the
         * cd_sim_advance calls are timed */
        double p[3][3], P[4][3], L[4][3], rel[4][3];
        int k;
        if (scene == SC_CAPTURE) capdyn_capture_measure(sc->model, d, rel[0], P[0], L[0]);
        r->wall = 0;
        st = CD_OK;
        for (k = 0; k < 3 && st == CD_OK; k++) {
            t0 = now();
            st = cd_sim_advance(sc->model, d, tseg[k], NULL, NULL, &e);
            r->wall += now() - t0;
            capdyn_pos(sc->model, d, s, p[k]);
            if (scene == SC_CAPTURE && st == CD_OK) capdyn_capture_measure(sc->model, d, rel[k + 1], P[k + 1], L[k + 1]);
        }
        if (st != CD_OK) {
            snprintf(r->msg, sizeof r->msg, "%s", e.msg);
        } else {
            r->ok = 1;
            r->tsim = tseg[2];
            r->steps = d->stats.nsteps;
            r->nrhs = d->stats.nrhs;
            memcpy(r->pos, p[2], sizeof r->pos);
            r->acc = dist3(p[2], p[0]);
            r->rate = dist3(p[2], p[1]) / (tseg[2] - tseg[1]);
            if (scene == SC_CAPTURE) capture_figures(r, P, L, rel, tseg);
        }
    }
    cd_data_free(d);
    cd_scenario_free(sc);
}

static void run_mujoco(int scene, run_result *r)
{
    const char *path = scene_xml[scene];
    char err[1000] = "";
    long h0 = heap_bytes();
    mjModel *m = mj_loadXML(path, NULL, err, (int)sizeof err);
    mjData *d;
    int body, nstep, k;
    double t0, tseg[3];
    scene_times(scene, tseg);
    if (!m) { snprintf(r->msg, sizeof r->msg, "%s: %s", path, err); return; }
    d = mj_makeData(m);
    r->heap = heap_bytes() - h0;
    if (m->nkey > 0) mj_resetDataKeyframe(m, d, 0); /* the initial state (capture: the target's velocity) */
    body = mj_name2id(m, mjOBJ_BODY, scene_body[scene]);
    if (scene == SC_GRASP) {
        static const char *jn[4] = {"left1", "left2", "right1", "right2"};
        static const double tau[4] = {0.2, 0.1, 0.2, 0.1};
        for (k = 0; k < 4; k++) d->qfrc_applied[m->jnt_dofadr[mj_name2id(m, mjOBJ_JOINT, jn[k])]] = tau[k];
    }
    {
        double p[3][3], P[4][3], L[4][3], rel[4][3];
        int seg;
        if (scene == SC_CAPTURE) mujoco_capture_measure(m, d, rel[0], P[0], L[0]);
        r->wall = 0;
        for (seg = 0; seg < 3; seg++) {
            nstep = (int)lround((tseg[seg] - d->time) / m->opt.timestep);
            t0 = now();
            for (k = 0; k < nstep; k++) mj_step(m, d);
            r->wall += now() - t0;
            memcpy(p[seg], d->xpos + 3 * body, sizeof p[seg]);
            if (scene == SC_CAPTURE) {
                mujoco_capture_measure(m, d, rel[seg + 1], P[seg + 1], L[seg + 1]);
                if (seg == 0) /* the fingers close from CAP_CLOSE */
                    for (k = 0; k < 4; k++) d->ctrl[mj_name2id(m, mjOBJ_ACTUATOR, cap_finger[k])] = cap_tau[k];
            }
        }
        r->ok = 1;
        r->tsim = d->time;
        r->steps = lround(d->time / m->opt.timestep);
        r->nrhs = r->steps;
        memcpy(r->pos, p[2], sizeof r->pos);
        r->acc = dist3(p[2], p[0]);
        r->rate = dist3(p[2], p[1]) / (tseg[2] - tseg[1]);
        if (scene == SC_CAPTURE) capture_figures(r, P, L, rel, tseg);
    }
    mj_deleteData(d);
    mj_deleteModel(m);
}

/* One run in a fresh process: this program re-executed as
 * `bench_speed --child ENGINE SCENE`, which writes its run_result to stdout
 * (a pipe); a fresh exec (not a bare fork) so that the peak resident memory
 * it reports is the run's own, not the parent's. */
static const char *self_path;

/* peak resident set of this process [kB] (Linux VmHWM; starts afresh at exec,
 * unlike getrusage's ru_maxrss, which keeps the pre-exec image's peak) */
static long vm_hwm_kb(void)
{
    FILE *f = fopen("/proc/self/status", "r");
    char line[256];
    long kb = -1;
    if (!f) return -1;
    while (fgets(line, sizeof line, f))
        if (sscanf(line, "VmHWM: %ld kB", &kb) == 1) break;
    fclose(f);
    return kb;
}

static int child_main(int engine, int scene)
{
    run_result r;
    memset(&r, 0, sizeof r);
    if (engine == ENG_CAPDYN) run_capdyn(scene, &r);
    else run_mujoco(scene, &r);
    r.hwm_kb = vm_hwm_kb();
    return fwrite(&r, sizeof r, 1, stdout) == 1 ? 0 : 1;
}

static run_result run_child(int engine, int scene)
{
    run_result r;
    int fd[2];
    pid_t pid;
    memset(&r, 0, sizeof r);
    if (pipe(fd) != 0) { snprintf(r.msg, sizeof r.msg, "pipe failed"); return r; }
    fflush(NULL);
    pid = fork();
    if (pid == 0) {
        char e[8], sc[8], hold[32];
        snprintf(e, sizeof e, "%d", engine);
        snprintf(sc, sizeof sc, "%d", scene);
        snprintf(hold, sizeof hold, "%.17g", T_HOLD);
        close(fd[0]);
        dup2(fd[1], STDOUT_FILENO);
        close(fd[1]);
        execl("/proc/self/exe", self_path, "--child", e, sc, hold, (char *)NULL);
        _exit(127);
    }
    close(fd[1]);
    if (pid < 0) { close(fd[0]); snprintf(r.msg, sizeof r.msg, "fork failed"); return r; }
    {
        int status;
        size_t got = 0;
        ssize_t k;
        while (got < sizeof r && (k = read(fd[0], (char *)&r + got, sizeof r - got)) > 0) got += (size_t)k;
        close(fd[0]);
        waitpid(pid, &status, 0);
        if (got != sizeof r) { memset(&r, 0, sizeof r); snprintf(r.msg, sizeof r.msg, "child died"); }
    }
    return r;
}

/* The twins must describe the same bodies: masses, principal inertias and
 * gravity compared before any timing (a twin edited on one side only fails
 * the bench instead of comparing different scenes). */
static int sort3_cmp(const void *a, const void *b) { return cmp_double(a, b); }

static int twin_check(int scene)
{
    static const char *grasp_cd[] = {"hand/left1", "hand/left2", "hand/right1", "hand/right2", "object"};
    static const char *grasp_mj[] = {"left1", "left2", "right1", "right2", "object"};
    static const char *inc_cd[] = {"block"}, *inc_mj[] = {"block"};
    static const char *cap_cd[] = {"chaser", "chaser/shoulder_yaw", "chaser/upper_arm", "chaser/forearm",
                                   "chaser/wrist_pitch", "chaser/wrist_yaw", "chaser/wrist_roll", "chaser/left1",
                                   "chaser/left2", "chaser/right1", "chaser/right2", "target"};
    static const char *cap_mj[] = {"chaser", "shoulder_yaw", "upper_arm", "forearm", "wrist_pitch", "wrist_yaw",
                                   "wrist_roll", "left1", "left2", "right1", "right2", "target"};
    const char **ncd = scene == SC_GRASP ? grasp_cd : scene == SC_INCLINE ? inc_cd : cap_cd;
    const char **nmj = scene == SC_GRASP ? grasp_mj : scene == SC_INCLINE ? inc_mj : cap_mj;
    int n = scene == SC_GRASP ? 5 : scene == SC_INCLINE ? 1 : 12, i, k, bad = 0;
    char err[1000] = "", extra[200] = "";
    cd_error e;
    cd_scenario *sc = cd_scenario_load(scene_toml[scene], NULL, 0, &e);
    mjModel *mm = mj_loadXML(scene_xml[scene], NULL, err, (int)sizeof err);
    double worst = 0;
    if (!sc || !mm) {
        fprintf(stderr, "bench_speed: twin check: %s\n", sc ? err : e.msg);
        cd_scenario_free(sc);
        if (mm) mj_deleteModel(mm);
        return 1;
    }
    for (i = 0; i < n; i++) {
        int bc = cd_model_body_id(sc->model, ncd[i]), bm = mj_name2id(mm, mjOBJ_BODY, nmj[i]);
        double ic[3], im[3];
        if (bc < 0 || bm < 0) { fprintf(stderr, "bench_speed: twin check: no body %s / %s\n", ncd[i], nmj[i]); bad = 1; continue; }
        for (k = 0; k < 3; k++) { ic[k] = sc->model->body_inertia[9 * bc + 4 * k]; im[k] = mm->body_inertia[3 * bm + k]; }
        qsort(ic, 3, sizeof(double), sort3_cmp);
        qsort(im, 3, sizeof(double), sort3_cmp);
        worst = fmax(worst, fabs(sc->model->body_mass[bc] - mm->body_mass[bm]) / sc->model->body_mass[bc]);
        for (k = 0; k < 3; k++) worst = fmax(worst, fabs(ic[k] - im[k]) / ic[k]);
    }
    for (k = 0; k < 3; k++) worst = fmax(worst, fabs(sc->model->gravity[k] - mm->opt.gravity[k]) / 9.81);
    if (scene == SC_CAPTURE) {
        /* the arm's PD gains (capdyn "pd" actuators, MuJoCo affine bias
         * -kp q - kd qdot) and the finger torques (capdyn "steps" tables:
         * 0, then cap_tau from CAP_CLOSE; MuJoCo: ctrl set by this program) */
        const cd_model *cm = sc->model;
        double wg = 0;
        char an[64];
        for (i = 0; i < 6; i++) {
            int a, am;
            snprintf(an, sizeof an, "chaser/%s", cap_arm[i]); /* a link actuator is named system/link */
            a = cd_model_actuator_id(cm, an);
            am = mj_name2id(mm, mjOBJ_ACTUATOR, cap_arm[i]);
            if (a < 0 || am < 0 || cm->act_type[a] != CD_ACT_PD) {
                fprintf(stderr, "bench_speed: twin check: no PD actuator %s\n", cap_arm[i]);
                bad = 1;
                continue;
            }
            wg = fmax(wg, fabs(cm->act_prm[4 * a + 1] + mm->actuator_biasprm[mjNBIAS * am + 1]) / cm->act_prm[4 * a + 1]);
            wg = fmax(wg, fabs(cm->act_prm[4 * a + 2] + mm->actuator_biasprm[mjNBIAS * am + 2]) / cm->act_prm[4 * a + 2]);
            wg = fmax(wg, fabs(cm->act_prm[4 * a + 3]) + fabs(cm->act_prm[4 * a]) + fabs(mm->actuator_biasprm[mjNBIAS * am]));
        }
        for (i = 0; i < 4; i++) {
            int a;
            const double *tt, *tv;
            snprintf(an, sizeof an, "chaser/%s", cap_finger[i]);
            a = cd_model_actuator_id(cm, an);
            if (a < 0 || cm->act_type[a] != CD_ACT_STEPS || cm->act_tbl_n[a] != 2 || mj_name2id(mm, mjOBJ_ACTUATOR, cap_finger[i]) < 0) {
                fprintf(stderr, "bench_speed: twin check: finger %s: expected a 2-row \"steps\" actuator and a MuJoCo motor\n",
                        cap_finger[i]);
                bad = 1;
                continue;
            }
            tt = cm->tbl_t + cm->act_tbl_adr[a];
            tv = cm->tbl_v + cm->act_tbl_adr[a];
            wg = fmax(wg, fabs(tv[0]) + fabs(tt[1] - CAP_CLOSE) + fabs(tv[1] - cap_tau[i]) / cap_tau[i]);
        }
        /* the initial state: every body's CoM in the world, the bar's
         * offset from the palm, the momenta */
        {
            cd_data *cd = cd_data_create(cm, sc->event_capacity, &e);
            mjData *md = mj_makeData(mm);
            double rc[3], rm[3], Pc[3], Pm[3], Lc[3], Lm[3], wx = 0, wm = 0;
            if (!cd) { fprintf(stderr, "bench_speed: twin check: %s\n", e.msg); bad = 1; }
            else {
                if (mm->nkey > 0) mj_resetDataKeyframe(mm, md, 0);
                capdyn_capture_measure(cm, cd, rc, Pc, Lc);
                mujoco_capture_measure(mm, md, rm, Pm, Lm);
                for (i = 0; i < n; i++) {
                    int bc = cd_model_body_id(cm, ncd[i]), bm = mj_name2id(mm, mjOBJ_BODY, nmj[i]);
                    if (bc >= 0 && bm >= 0) wx = fmax(wx, dist3(cd->body_c + 3 * bc, md->xipos + 3 * bm));
                }
                wx = fmax(wx, dist3(rc, rm));
                for (k = 0; k < 3; k++) {
                    wm = fmax(wm, fabs(Pc[k] - Pm[k]) / norm3(Pc));
                    wm = fmax(wm, fabs(Lc[k] - Lm[k]) / norm3(Lc));
                }
                if (wx > 1e-5 || wm > 1e-6) bad = 1;
                cd_data_free(cd);
            }
            mj_deleteData(md);
            if (wg > 1e-12) bad = 1;
            snprintf(extra, sizeof extra,
                     ";\n  arm PD gains, finger torques, closing time %.1e; initial CoMs %.1e m; initial momenta %.1e", wg, wx,
                     wm);
        }
    }
    if (worst > 1e-6) bad = 1;
    say("twin check %-8s masses, principal inertias, gravity: largest relative difference %.1e%s%s\n", scene_name[scene],
        worst, extra, bad ? "  MISMATCH" : "");
    cd_scenario_free(sc);
    mj_deleteModel(mm);
    return bad;
}

static int scene_on[NSCENE] = {1, 1, 1}; /* --scene NAME (repeatable) runs only the named ones */

static int bench_scenes(int reps)
{
    static double rtf[NSCENE][2][MAXREP], wps[NSCENE][2][MAXREP], ratio[NSCENE][MAXREP];
    static run_result last[NSCENE][2];
    static long rss[NSCENE][2];
    static double acc[NSCENE][2][MAXREP], rate[NSCENE][2][MAXREP];
    int rep, sc, eng, failed = 0;
    say("\n== scenes: capdyn (GSL, event-located stick-slip) vs MuJoCo %s (dt 2 ms), %d interleaved repetitions ==\n",
        mj_versionString(), reps);
    for (sc = 0; sc < NSCENE; sc++)
        if (scene_on[sc] && twin_check(sc)) return 1;
    for (rep = 0; rep < reps; rep++)
        for (sc = 0; sc < NSCENE; sc++) {
            int k;
            if (!scene_on[sc]) continue;
            for (k = 0; k < 2; k++) {
                /* alternate which engine goes first */
                run_result r;
                eng = (rep + k) % 2;
                r = run_child(eng, sc);
                if (!r.ok) {
                    fprintf(stderr, "bench_speed: %s %s failed: %s\n", eng ? "MuJoCo" : "capdyn", scene_name[sc], r.msg);
                    failed = 1;
                    continue;
                }
                rtf[sc][eng][rep] = r.tsim / r.wall;
                wps[sc][eng][rep] = r.wall / r.tsim;
                acc[sc][eng][rep] = r.acc;
                rate[sc][eng][rep] = r.rate;
                last[sc][eng] = r;
                if (r.hwm_kb > rss[sc][eng]) rss[sc][eng] = r.hwm_kb;
            }
            ratio[sc][rep] = rtf[sc][ENG_CAPDYN][rep] / rtf[sc][ENG_MUJOCO][rep];
        }
    if (failed) return 1;
    say("%-8s %-7s %11s %22s %7s %7s %8s %9s %6s %7s %10s %10s\n", "scene", "engine", "wall/sim-s", "RTF",
        "ratio", "ratio", "steps", "rhs", "RSS", "heap", "offset", "rate");
    say("%-8s %-7s %11s %22s %7s %7s %8s %9s %6s %7s %10s %10s\n", "", "", "[ms/s] med", "median (min..max)",
        "min", "median", "", "evals", "[MB]", "[kB]", "[um]", "[um/s]");
    for (sc = 0; sc < NSCENE; sc++)
        for (eng = 0; eng < 2 && scene_on[sc]; eng++) {
            const run_result *r = &last[sc][eng];
            char rb[40], r1[16] = "", r2[16] = "";
            double mx = rtf[sc][eng][0];
            int i;
            for (i = 1; i < reps; i++)
                if (rtf[sc][eng][i] > mx) mx = rtf[sc][eng][i];
            snprintf(rb, sizeof rb, "%.3g (%.3g..%.3g)", median_of(rtf[sc][eng], reps), min_of(rtf[sc][eng], reps), mx);
            if (eng == ENG_CAPDYN) {
                snprintf(r1, sizeof r1, "%.3g", min_of(ratio[sc], reps));
                snprintf(r2, sizeof r2, "%.3g", median_of(ratio[sc], reps));
            }
            say("%-8s %-7s %11.2f %22s %7s %7s %8ld %9ld %6.1f %7.0f %10.3g %10.3g\n", scene_name[sc],
                eng == ENG_CAPDYN ? "capdyn" : "MuJoCo", 1e3 * median_of(wps[sc][eng], reps), rb, r1, r2, r->steps,
                r->nrhs, rss[sc][eng] / 1024.0, r->heap / 1024.0, 1e6 * median_of(acc[sc][eng], reps),
                1e6 * median_of(rate[sc][eng], reps));
        }
    if (scene_on[SC_GRASP])
        say("final object position [mm]: grasp capdyn (%.4f, %.4f, %.4f), MuJoCo (%.4f, %.4f, %.4f)\n",
        1e3 * last[SC_GRASP][0].pos[0], 1e3 * last[SC_GRASP][0].pos[1], 1e3 * last[SC_GRASP][0].pos[2],
        1e3 * last[SC_GRASP][1].pos[0], 1e3 * last[SC_GRASP][1].pos[1], 1e3 * last[SC_GRASP][1].pos[2]);
    for (eng = 0; eng < 2 && scene_on[SC_CAPTURE]; eng++) {
        const run_result *r = &last[SC_CAPTURE][eng];
        say("capture %-7s bar centre - palm face centre at %g s (palm frame) (%.2f, %.2f, %.2f) mm: %s; "
            "momentum drift |dP| %.2e kg m/s (%.1e of |P| %.3g), |dL| %.2e kg m^2/s (%.1e of |L| %.3g)\n",
            eng == ENG_CAPDYN ? "capdyn" : "MuJoCo", CAP_END, 1e3 * r->rel[0], 1e3 * r->rel[1], 1e3 * r->rel[2],
            cap_held(r->rel) ? "held" : "NOT held", r->dP, r->dP / r->P0, r->P0, r->dL, r->dL / r->L0, r->L0);
    }
    say("offset: grasp = |object(end) - object(2 s)| over the %g s hold; incline = |block(10 s) - block(1 s)|;\n"
        "capture = |bar centre - palm face centre| at %g s (it starts at 50.2 mm);\n"
        "rate: creep rate over the second half of that span (grasp %g-%g s, incline 5.5-10 s); capture: the bar's\n"
        "speed relative to the palm (palm frame) over %g-%g s. capture held: the bar's centre between the finger\n"
        "bases (|y| < 50 mm), within 150 mm of the palm face (x), the bar across the fingers' plane (|z| < 150 mm).\n"
        "momentum drift: largest change of the whole model's linear momentum and angular momentum about its CoM\n"
        "from t = 0, at %g, %g and %g s (last repetition; no external force acts).\n"
        "ratio = capdyn RTF / MuJoCo RTF of the same repetition. RSS: peak resident memory of the process\n"
        "running one engine (both libraries mapped); heap: model + data allocated by the engine.\n",
        T_HOLD, CAP_END, T_CLOSE + 0.5 * T_HOLD, T_CLOSE + T_HOLD, CAP_LAST, CAP_END, CAP_CLOSE, CAP_LAST, CAP_END);
    return 0;
}

/* ---- forward-dynamics scaling --------------------------------------------- */
/* bench_chain (bench_chain.h) as MJCF, written to a temporary file and loaded */
static mjModel *mujoco_chain(int n)
{
    char path[] = "/tmp/capdyn_bench_chainXXXXXX", err[1000] = "";
    int fd = mkstemp(path), i;
    FILE *f;
    mjModel *m;
    if (fd < 0) { perror("mkstemp"); exit(1); }
    f = fdopen(fd, "w");
    fprintf(f, "<mujoco><option gravity=\"0 0 0\"/><worldbody><body name=\"base\"><freejoint/>"
               "<inertial pos=\"0 0 0\" mass=\"100\" diaginertia=\"20 20 20\"/>\n");
    for (i = 0; i < n; i++)
        fprintf(f, "<body pos=\"0.3 0 0\"><joint type=\"hinge\" axis=\"0 %d %d\"/>"
                   "<inertial pos=\"0.15 0 0\" mass=\"2\" diaginertia=\"0.01 0.05 0.05\"/>\n", i % 2, 1 - i % 2);
    for (i = 0; i <= n; i++) fprintf(f, "</body>");
    fprintf(f, "</worldbody></mujoco>\n");
    fclose(f);
    m = mj_loadXML(path, NULL, err, (int)sizeof err);
    remove(path);
    if (!m) { fprintf(stderr, "bench_speed: MuJoCo chain: %s\n", err); exit(1); }
    return m;
}

enum { FD_CRBA = 0, FD_ABA, FD_MJ, FD_FIX_CRBA, FD_FIX_ABA, NFD };

static int bench_fd(int reps)
{
    static const int sizes[] = {0, 1, 2, 3, 4, 6, 8, 10, 12, 14, 16, 20, 24, 32, 48, 64};
    const int nsize = (int)(sizeof sizes / sizeof sizes[0]);
    static double ns[32][NFD][MAXREP];
    int k, rep, meth, cross_free = -1, cross_fixed = -1;
    /* short timing blocks, many repetitions: on a shared machine the minima
     * then catch quiet moments (the crossover is judged on them) */
    reps = 3 * reps < MAXREP ? 3 * reps : MAXREP;
    say("\n== forward dynamics per call, free-floating chain (fixed-base columns: the same chain on a fixed base) ==\n");
    say("capdyn: cd_kinematics + cd_forward_dynamics_method; MuJoCo: mj_forward (no geoms, no contacts)\n");
    say("ns per call, median [min] of %d interleaved repetitions (3 x -r)\n", reps);
    say("%6s %5s %18s %18s %18s %9s | %18s %18s\n", "joints", "DoF", "capdyn CRBA", "capdyn ABA", "MuJoCo mj_forward",
        "best/MJ", "fixed CRBA", "fixed ABA");
    for (k = 0; k < nsize; k++) {
        int n = sizes[k], calls = 15000 / (n + 4) + 20, i;
        cd_error e;
        /* a fixed base without joints has nothing to solve: the same free
         * body stands in (its fixed-base columns are not printed) */
        cd_model *mf = bench_chain(n, 1), *mx = bench_chain(n, n == 0);
        cd_data *df = cd_data_create(mf, 0, &e), *dx = cd_data_create(mx, 0, &e);
        mjModel *mm = mujoco_chain(n);
        mjData *md = mj_makeData(mm);
        double med[NFD], mn[NFD];
        if (!df || !dx) { fprintf(stderr, "bench_speed: %s\n", e.msg); exit(1); }
        for (i = 0; i < n; i++) { md->qpos[7 + i] = 0.1 * i; md->qvel[6 + i] = 0.05; }
        for (rep = 0; rep < reps; rep++)
            for (meth = 0; meth < NFD; meth++) {
                int which = (meth + rep) % NFD, c;
                double t0 = now();
                switch (which) {
                case FD_CRBA:
                    for (c = 0; c < calls; c++) { cd_kinematics(mf, df); cd_forward_dynamics_method(mf, df, CD_FD_CRBA); }
                    break;
                case FD_ABA:
                    for (c = 0; c < calls; c++) { cd_kinematics(mf, df); cd_forward_dynamics_method(mf, df, CD_FD_ABA); }
                    break;
                case FD_MJ:
                    for (c = 0; c < calls; c++) mj_forward(mm, md);
                    break;
                case FD_FIX_CRBA:
                    for (c = 0; c < calls; c++) { cd_kinematics(mx, dx); cd_forward_dynamics_method(mx, dx, CD_FD_CRBA); }
                    break;
                default:
                    for (c = 0; c < calls; c++) { cd_kinematics(mx, dx); cd_forward_dynamics_method(mx, dx, CD_FD_ABA); }
                    break;
                }
                ns[k][which][rep] = (now() - t0) / calls * 1e9;
            }
        for (meth = 0; meth < NFD; meth++) { med[meth] = median_of(ns[k][meth], reps); mn[meth] = min_of(ns[k][meth], reps); }
        {
            char c[NFD][32];
            for (meth = 0; meth < NFD; meth++) snprintf(c[meth], sizeof c[meth], "%.0f [%.0f]", med[meth], mn[meth]);
            say("%6d %5d %18s %18s %18s %9.2f | %18s %18s\n", n, n + 6, c[FD_CRBA], c[FD_ABA], c[FD_MJ],
                (med[FD_CRBA] < med[FD_ABA] ? med[FD_CRBA] : med[FD_ABA]) / med[FD_MJ], n ? c[FD_FIX_CRBA] : "-",
                n ? c[FD_FIX_ABA] : "-");
        }
        /* crossover: the smallest size from which ABA stays faster, judged on
         * the minima (the runs least disturbed by other load on the machine) */
        if (mn[FD_ABA] < mn[FD_CRBA]) { if (cross_free < 0) cross_free = n + 6; } else cross_free = -1;
        if (n == 0) { /* a fixed base without joints has nothing to solve */
        } else if (mn[FD_FIX_ABA] < mn[FD_FIX_CRBA]) { if (cross_fixed < 0) cross_fixed = n; } else cross_fixed = -1;
        mj_deleteData(md);
        mj_deleteModel(mm);
        cd_data_free(df); cd_data_free(dx);
        cd_model_free(mf); cd_model_free(mx);
    }
    say("measured crossover (ABA minimum faster from here on): free base %d DoF, fixed base %d DoF; "
        "cd_forward_dynamics switches at %d DoF (cd_fd_aba_min_dof)\n", cross_free, cross_fixed, cd_fd_aba_min_dof());
    say("best/MJ = min(capdyn CRBA, capdyn ABA) / MuJoCo (< 1: capdyn faster)\n");
    return 0;
}

int main(int argc, char **argv)
{
    int reps = 5, i, do_fd = 1, do_scenes = 1, rc = 0;
    const char *out = NULL;
    char host[256] = "?";
    time_t t = time(NULL);
    char date[64];
    self_path = argv[0];
    if (argc == 5 && !strcmp(argv[1], "--child")) {
        T_HOLD = atof(argv[4]);
        return child_main(atoi(argv[2]), atoi(argv[3]));
    }
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "-r") && i + 1 < argc) reps = atoi(argv[++i]);
        else if (!strcmp(argv[i], "-o") && i + 1 < argc) out = argv[++i];
        else if (!strcmp(argv[i], "--hold") && i + 1 < argc) T_HOLD = atof(argv[++i]);
        else if (!strcmp(argv[i], "--fd-only")) do_scenes = 0;
        else if (!strcmp(argv[i], "--scenes-only")) do_fd = 0;
        else if (!strcmp(argv[i], "--scene") && i + 1 < argc) {
            static int first = 1;
            int k, found = -1;
            for (k = 0; k < NSCENE; k++)
                if (!strcmp(argv[i + 1], scene_name[k])) found = k;
            if (found < 0) {
                fprintf(stderr, "bench_speed: --scene: expected grasp, incline or capture, got '%s'\n", argv[i + 1]);
                return 2;
            }
            if (first) memset(scene_on, 0, sizeof scene_on);
            first = 0;
            scene_on[found] = 1;
            i++;
        }
        else {
            fprintf(stderr, "usage: %s [-r reps (1..%d, default 5)] [-o results.txt] [--hold seconds (grasp hold, default 10)]\n"
                            "       [--fd-only | --scenes-only] [--scene grasp|incline|capture ...]\n", argv[0], MAXREP);
            return 2;
        }
    }
    if (reps < 1 || reps > MAXREP) { fprintf(stderr, "bench_speed: -r: expected 1..%d, got %d\n", MAXREP, reps); return 2; }
    if (!(T_HOLD >= 1.0 && T_HOLD <= 1000.0)) { fprintf(stderr, "bench_speed: --hold: expected 1..1000 s\n"); return 2; }
    gsl_set_error_handler_off();
    if (out && !(out_file = fopen(out, "w"))) { perror(out); return 1; }
    gethostname(host, sizeof host - 1);
    strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", gmtime(&t));
    say("capdyn %s vs MuJoCo %s -- %s, host %s, %ld online CPUs\n", cd_version(), mj_versionString(), date, host,
        sysconf(_SC_NPROCESSORS_ONLN));
    {
        double la[3] = {0, 0, 0};
        if (getloadavg(la, 3) == 3) say("load average at start %.2f %.2f %.2f (other jobs on the machine skew medians; see the minima)\n", la[0], la[1], la[2]);
    }
    say("command:");
    for (i = 0; i < argc; i++) say(" %s", argv[i]);
    if (getenv("CAPDYN_BENCH_SET") && *getenv("CAPDYN_BENCH_SET")) say(" (CAPDYN_BENCH_SET='%s')", getenv("CAPDYN_BENCH_SET"));
    say("   (make bench runs it; %d repetitions, grasp hold %g s)\n", reps, T_HOLD);
    if (do_fd) rc |= bench_fd(reps);
    if (do_scenes) rc |= bench_scenes(reps);
    if (out_file) fclose(out_file);
    return rc;
}
