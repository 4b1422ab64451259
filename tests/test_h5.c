/* HDF5 results writer (src/io/h5.c): layout, attributes, the committed-sample
 * protocol and the event table, with a model built by code.
 *
 * The scene: a free-floating 2-link "arm" driven by constant joint torques
 * (no gravity, no contact: its momentum is conserved), and a "ball" (a check
 * point of radius 0.1 m on a free body) shuttling at 1 m/s between two
 * walls (planes on a fixed "walls" system at x = -0.15 and x = +0.15), so
 * every 0.1 s there is an onset and a separation event.
 *
 * Crash safety is tested on byte copies of the file taken while the writer
 * is still open: a copy is exactly what a process killed at that moment
 * leaves on disk (tests/test_cli.c kills a real run with SIGKILL). */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <capdyn/io.h>
#include <hdf5.h>
#include "../src/io/h5_read.h"
#include "../src/io/h5_util.h"
#include "h5_test_util.h"
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

typedef struct { cd_model *m; cd_data *d; int arm, ball, walls; } scene;

static scene make_scene(int event_capacity)
{
    scene r;
    cd_error e;
    cd_system_desc s = cd_system_desc_default();
    cd_link_desc l = cd_link_desc_default();
    cd_actuator a;
    cd_contact_law law = cd_contact_law_default();
    double Rl[9] = {0, 0, 1, 0, 1, 0, -1, 0, 0};  /* shape z -> world +x */
    double Rr[9] = {0, 0, -1, 0, 1, 0, 1, 0, 0};  /* shape z -> world -x */
    double pl[3] = {-0.15, 0, 0}, pr[3] = {0.15, 0, 0}, zero[3] = {0, 0, 0};
    int b1, b2, shl, shr, lid;
    r.m = cd_model_create();
    cr_assert(r.m);
    /* arm: base 10 kg, two 1 kg links of 0.5 m about z */
    s.name = "arm";
    s.mass = 10.0;
    s.inertia[0] = s.inertia[4] = s.inertia[8] = 1.0;
    s.pos[1] = 2.0;
    r.arm = cd_model_add_system(r.m, &s, &e);
    cr_assert(r.arm >= 0, "%s", e.msg);
    l.name = "upper";
    l.parent = r.m->sys_body_adr[r.arm];
    l.pos[0] = 0.2;
    l.com[0] = 0.25;
    l.inertia[0] = 0.001; l.inertia[4] = l.inertia[8] = 0.02;
    b1 = cd_model_add_link(r.m, r.arm, &l, &e);
    cr_assert(b1 >= 0, "%s", e.msg);
    l.name = "fore";
    l.parent = b1;
    l.pos[0] = 0.5;
    b2 = cd_model_add_link(r.m, r.arm, &l, &e);
    cr_assert(b2 >= 0, "%s", e.msg);
    memset(&a, 0, sizeof a);
    a.type = CD_ACT_CONSTANT;
    a.tau0 = 0.5;
    cr_assert_eq(cd_model_set_actuator(r.m, b1, &a, &e), CD_OK, "%s", e.msg);
    a.tau0 = -0.3;
    cr_assert_eq(cd_model_set_actuator(r.m, b2, &a, &e), CD_OK, "%s", e.msg);
    /* walls */
    s = cd_system_desc_default();
    s.name = "walls";
    s.type = CD_BASE_FIXED;
    r.walls = cd_model_add_system(r.m, &s, &e);
    cr_assert(r.walls >= 0, "%s", e.msg);
    shl = cd_model_add_shape(r.m, r.m->sys_body_adr[r.walls], CD_SHAPE_PLANE, pl, Rl, NULL, NULL, 0, &e);
    shr = cd_model_add_shape(r.m, r.m->sys_body_adr[r.walls], CD_SHAPE_PLANE, pr, Rr, NULL, NULL, 0, &e);
    cr_assert(shl >= 0 && shr >= 0, "%s", e.msg);
    /* ball */
    s = cd_system_desc_default();
    s.name = "ball";
    s.vel[0] = 1.0;
    r.ball = cd_model_add_system(r.m, &s, &e);
    cr_assert(r.ball >= 0, "%s", e.msg);
    cr_assert(cd_model_add_checkpoint(r.m, r.m->sys_body_adr[r.ball], zero, 0.1, &e) >= 0, "%s", e.msg);
    law.K = 1e5;
    law.D = 2.0 * 0.05 * sqrt(law.K * 1.0);
    lid = cd_model_add_law(r.m, &law, &e);
    cr_assert(lid >= 0, "%s", e.msg);
    cr_assert(cd_model_add_pair(r.m, r.ball, -1, shl, lid, &e) >= 0, "%s", e.msg);
    cr_assert(cd_model_add_pair(r.m, r.ball, -1, shr, lid, &e) >= 0, "%s", e.msg);
    cr_assert_eq(cd_model_finalize(r.m, &e), CD_OK, "%s", e.msg);
    r.m->opt.rtol = 1e-10;
    r.m->opt.atol = 1e-12;
    r.m->opt.h_max = 1e-3;
    r.d = cd_data_create(r.m, event_capacity, &e);
    cr_assert(r.d, "%s", e.msg);
    return r;
}

static void free_scene(scene *r)
{
    cd_data_free(r->d);
    cd_model_free(r->m);
}

static void tmp_path(char *out, size_t n, const char *tag)
{
    snprintf(out, n, "/tmp/capdyn_test_h5_%ld_%s.h5", (long)getpid(), tag);
}

/* A byte copy of src: what a process killed now would leave on disk. */
static void copy_file(const char *src, const char *dst)
{
    FILE *in = fopen(src, "rb"), *out = fopen(dst, "wb");
    char buf[65536];
    size_t n;
    cr_assert(in && out, "copy %s -> %s", src, dst);
    while ((n = fread(buf, 1, sizeof buf, in)) > 0) cr_assert_eq(fwrite(buf, 1, n, out), n);
    fclose(in);
    fclose(out);
}

/* Test files are removed unless CAPDYN_KEEP_TEST_FILES is set (for h5dump). */
static void cleanup(const char *path)
{
    if (!getenv("CAPDYN_KEEP_TEST_FILES")) remove(path);
}

static hid_t open_ro(const char *path)
{
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS), f;
    H5Pset_file_locking(fapl, 0, 1);
    f = H5Fopen(path, H5F_ACC_RDONLY, fapl);
    H5Pclose(fapl);
    return f;
}




/* Runs the scene to t_end appending a sample every dt (the CLI's loop). */
static void run_sampled(scene *r, cd_h5_writer *w, double t_end, double dt, int flush_every_n)
{
    cd_error e;
    int i, n = (int)floor(t_end / dt + 0.5);
    for (i = 1; i <= n; i++) {
        cr_assert_eq(cd_sim_advance(r->m, r->d, i * dt, NULL, NULL, &e), CD_OK, "%s", e.msg);
        cr_assert_eq(cd_h5_append(w, r->m, r->d, &e), CD_OK, "%s", e.msg);
        if (flush_every_n > 0 && i % flush_every_n == 0) cr_assert_eq(cd_h5_flush(w, &e), CD_OK, "%s", e.msg);
    }
}

Test(h5, layout_shapes_and_attributes)
{
    /* 1 s sampled every 10 ms = 101 samples (t = 0 included). Shapes follow
     * docs/results-format.md: arm has 2 joints and 3 bodies, 2 contact slots
     * (one check point x two walls), 3 systems. */
    scene r = make_scene(0);
    cd_error e;
    char path[256], s[256];
    cd_h5_writer *w;
    hid_t f;
    hsize_t d[3];
    size_t n, i;
    double *t;
    tmp_path(path, sizeof path, "layout");
    w = cd_h5_create(path, r.m, NULL, &e);
    cr_assert(w, "%s", e.msg);
    cr_assert_eq(cd_h5_append(w, r.m, r.d, &e), CD_OK, "%s", e.msg);
    run_sampled(&r, w, 1.0, 0.01, 0);
    cr_assert_eq(cd_h5_close(w, r.m, r.d, CD_OK, "finished", &e), CD_OK, "%s", e.msg);

    f = open_ro(path);
    cr_assert(f >= 0, "reopen %s", path);
    cr_expect_eq(attr_ll(f, "committed_samples"), 101);
    cr_expect_eq(dims_of(f, "/time", d), 1);
    cr_expect_eq(d[0], 101);
    cr_expect_eq(dims_of(f, "/systems/arm/base_pos", d), 2);
    cr_expect(d[0] == 101 && d[1] == 3);
    cr_expect_eq(dims_of(f, "/systems/arm/base_quat", d), 2);
    cr_expect(d[1] == 4);
    cr_expect_eq(dims_of(f, "/systems/arm/q", d), 2);
    cr_expect(d[0] == 101 && d[1] == 2, "q is n x njoint, got %llu x %llu", (unsigned long long)d[0], (unsigned long long)d[1]);
    cr_expect_eq(dims_of(f, "/systems/arm/qd", d), 2);
    cr_expect_eq(dims_of(f, "/systems/arm/body_x", d), 3);
    cr_expect(d[0] == 101 && d[1] == 3 && d[2] == 3);
    cr_expect_eq(dims_of(f, "/systems/arm/body_quat", d), 3);
    cr_expect(d[2] == 4);
    cr_expect(H5Lexists(f, "/systems/ball/q", H5P_DEFAULT) == 0, "no joint datasets for a system without joints");
    cr_expect_eq(dims_of(f, "/contacts/fn", d), 2);
    cr_expect(d[0] == 101 && d[1] == 2);
    cr_expect_eq(dims_of(f, "/contacts/ft", d), 3);
    cr_expect(d[0] == 101 && d[1] == 2 && d[2] == 3);
    cr_expect_eq(dims_of(f, "/contacts/mode", d), 2);
    cr_expect_eq(dims_of(f, "/contacts/slots", d), 1);
    cr_expect_eq(d[0], 2);
    cr_expect_eq(dims_of(f, "/diagnostics/momentum", d), 3);
    cr_expect(d[0] == 101 && d[1] == 3 && d[2] == 3);
    cr_expect_eq(dims_of(f, "/diagnostics/nrhs", d), 1);
    cr_expect_eq(dims_of(f, "/model/bodies", d), 1);
    cr_expect_eq(d[0], (hsize_t)r.m->nbody);
    /* every event the run logged is in the table */
    cr_expect_eq(dims_of(f, "/events", d), 1);
    cr_expect_eq((long)d[0], r.d->ev_count, "events in file %llu, logged %ld", (unsigned long long)d[0], r.d->ev_count);
    cr_expect_gt(r.d->ev_count, 10, "the ball bounced (%ld events)", r.d->ev_count);
    cr_expect_eq(attr_ll(f, "committed_events"), r.d->ev_count);
    /* attributes */
    attr_s(f, "capdyn_version", s, sizeof s);
    cr_expect_str_eq(s, cd_version());
    attr_s(f, "created_utc", s, sizeof s);
    cr_expect(strlen(s) == 20 && s[4] == '-' && s[10] == 'T' && s[19] == 'Z', "ISO 8601 UTC, got '%s'", s);
    attr_s(f, "run_status", s, sizeof s);
    cr_expect_str_eq(s, cd_status_string(CD_OK));
    attr_s(f, "run_message", s, sizeof s);
    cr_expect_str_eq(s, "finished");
    cr_expect_eq(attr_ll(f, "stats_nsteps"), r.d->stats.nsteps);
    /* time: the sample instants exactly (cd_sim_advance lands on t_end) */
    t = read_all(f, "/time", &n);
    cr_assert_eq(n, 101);
    for (i = 0; i < n; i++) cr_expect_eq(t[i], i == 0 ? 0.0 : (double)i * 0.01, "t[%zu] = %.17g", i, t[i]);
    free(t);
    H5Fclose(f);
    cleanup(path);
    free_scene(&r);
}

Test(h5, values_round_trip_and_momentum_is_conserved_in_the_file)
{
    /* The last row holds d's final state bit for bit. The arm is free-floating
     * with internal torques only and no gravity: its linear momentum stays
     * zero and its angular momentum about the origin stays at its initial
     * value (zero, from rest); the stored diagnostics must show it within
     * 1e-10 of the momentum scale sum m_i |v_i| (issue 2, test 3 tolerance). */
    scene r = make_scene(0);
    cd_error e;
    char path[256];
    cd_h5_writer *w;
    hid_t f;
    size_t n, nq, nP, nL, i;
    double *pos, *q, *P, *L, scale = 0;
    int b;
    cd_sys_state x;
    tmp_path(path, sizeof path, "values");
    w = cd_h5_create(path, r.m, NULL, &e);
    cr_assert(w, "%s", e.msg);
    cr_assert_eq(cd_h5_append(w, r.m, r.d, &e), CD_OK, "%s", e.msg);
    run_sampled(&r, w, 0.5, 0.05, 3);
    cr_assert_eq(cd_h5_close(w, r.m, r.d, CD_OK, "", &e), CD_OK, "%s", e.msg);
    x = cd_state_of(r.m, r.d, r.arm);
    for (b = r.m->sys_body_adr[r.arm]; b < r.m->sys_body_adr[r.arm] + r.m->sys_nbody[r.arm]; b++) {
        const double *v = r.d->body_v + 3 * b;
        scale += r.m->body_mass[b] * sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    }
    cr_assert_gt(scale, 0.01, "the arm moves (momentum scale %g)", scale);

    f = open_ro(path);
    cr_assert(f >= 0);
    pos = read_all(f, "/systems/arm/base_pos", &n);
    cr_assert_eq(n, 11 * 3);
    for (i = 0; i < 3; i++) cr_expect_eq(pos[30 + i], x.pos[i]);
    q = read_all(f, "/systems/arm/q", &nq);
    cr_assert_eq(nq, 11 * 2);
    cr_expect_eq(q[20], x.q[0]);
    cr_expect_eq(q[21], x.q[1]);
    cr_expect_gt(fabs(q[20] - q[0]), 1e-3, "the joints moved");
    P = read_all(f, "/diagnostics/momentum", &nP);
    L = read_all(f, "/diagnostics/angular_momentum_origin", &nL);
    cr_assert_eq(nP, 11 * 3 * 3);
    for (i = 0; i < 11; i++) {
        const double *Pa = P + 9 * i + 3 * r.arm, *La = L + 9 * i + 3 * r.arm;
        double dp = sqrt(Pa[0] * Pa[0] + Pa[1] * Pa[1] + Pa[2] * Pa[2]);
        double dl = sqrt(La[0] * La[0] + La[1] * La[1] + La[2] * La[2]);
        cr_expect_lt(dp, 1e-10 * scale, "sample %zu: |P| = %.3e", i, dp);
        cr_expect_lt(dl, 1e-10 * scale, "sample %zu: |L_origin| = %.3e", i, dl);
    }
    free(pos); free(q); free(P); free(L);
    H5Fclose(f);
    cleanup(path);
    free_scene(&r);
}

Test(h5, only_committed_samples_are_on_disk_and_append_after_flush_works)
{
    /* The commit protocol: appends are buffered; a file copied (= killed)
     * before a flush shows the previous commit, after a flush the new count,
     * and appending after a flush continues the series seamlessly. */
    scene r = make_scene(0);
    cd_error e;
    char path[256], copy[256];
    cd_h5_writer *w;
    hid_t f;
    hsize_t d[3];
    size_t n, i;
    double *t;
    int k;
    tmp_path(path, sizeof path, "commit");
    tmp_path(copy, sizeof copy, "commit_copy");
    w = cd_h5_create(path, r.m, NULL, &e);
    cr_assert(w, "%s", e.msg);
    {
        /* issue 28: the file takes its name only with its first sample */
        struct stat sb;
        cr_expect_neq(stat(path, &sb), 0, "no file at the path before the first sample is committed");
    }

    cr_assert_eq(cd_h5_append(w, r.m, r.d, &e), CD_OK, "%s", e.msg);
    copy_file(path, copy);
    f = open_ro(copy);
    cr_assert(f >= 0, "a file killed right after its first sample is readable");
    cr_expect_eq(attr_ll(f, "committed_samples"), 1, "the first sample is committed at once");
    H5Fclose(f);
    for (k = 1; k <= 4; k++) {
        cr_assert_eq(cd_sim_advance(r.m, r.d, 0.01 * k, NULL, NULL, &e), CD_OK, "%s", e.msg);
        cr_assert_eq(cd_h5_append(w, r.m, r.d, &e), CD_OK, "%s", e.msg);
    }
    copy_file(path, copy);
    f = open_ro(copy);
    cr_assert(f >= 0, "a file killed between commits is readable");
    cr_expect_eq(attr_ll(f, "committed_samples"), 1, "nothing more committed before the next flush");
    dims_of(f, "/time", d);
    cr_expect_eq(d[0], 1);
    H5Fclose(f);

    cr_assert_eq(cd_h5_flush(w, &e), CD_OK, "%s", e.msg);
    copy_file(path, copy);
    f = open_ro(copy);
    cr_assert(f >= 0);
    cr_expect_eq(attr_ll(f, "committed_samples"), 5);
    dims_of(f, "/contacts/ft", d);
    cr_expect(d[0] == 5 && d[1] == 2 && d[2] == 3);
    H5Fclose(f);

    for (k = 5; k <= 7; k++) {
        cr_assert_eq(cd_sim_advance(r.m, r.d, 0.01 * k, NULL, NULL, &e), CD_OK, "%s", e.msg);
        cr_assert_eq(cd_h5_append(w, r.m, r.d, &e), CD_OK, "%s", e.msg);
    }
    cr_assert_eq(cd_h5_flush(w, &e), CD_OK, "%s", e.msg);
    copy_file(path, copy);
    f = open_ro(copy);
    cr_assert(f >= 0);
    cr_expect_eq(attr_ll(f, "committed_samples"), 8);
    t = read_all(f, "/time", &n);
    cr_assert_eq(n, 8);
    for (i = 0; i < n; i++) cr_expect_eq(t[i], i == 0 ? 0.0 : 0.01 * (double)i, "t[%zu] = %.17g", i, t[i]);
    free(t);
    {
        char s[64];
        attr_s(f, "run_status", s, sizeof s);
        cr_expect_str_eq(s, "running", "a killed run says it did not finish");
    }
    H5Fclose(f);
    cr_assert_eq(cd_h5_close(w, r.m, r.d, CD_EINTERRUPT, "stopped", &e), CD_OK, "%s", e.msg);
    f = open_ro(path);
    cr_assert(f >= 0);
    {
        char s[64];
        attr_s(f, "run_status", s, sizeof s);
        cr_expect_str_eq(s, cd_status_string(CD_EINTERRUPT));
    }
    H5Fclose(f);
    cleanup(path);
    cleanup(copy);
    free_scene(&r);
}

Test(h5, a_full_buffer_commits_by_itself)
{
    /* 1500 samples without any cd_h5_flush: the writer buffers at most 1024
     * rows (a whole number of chunks of its widest series, more than half
     * of 1024: alloc_buffers), so a copy taken then holds more than 1500 - 1024
     * committed samples, a whole number of buffers after the first sample's
     * commit, and never more rows than the counter admits beyond the
     * pending buffer. */
    scene r = make_scene(0);
    cd_error e;
    char path[256], copy[256];
    cd_h5_writer *w;
    hid_t f;
    long long c;
    int k;
    tmp_path(path, sizeof path, "full");
    tmp_path(copy, sizeof copy, "full_copy");
    w = cd_h5_create(path, r.m, NULL, &e);
    cr_assert(w, "%s", e.msg);
    for (k = 0; k < 1500; k++) {
        cr_assert_eq(cd_sim_advance(r.m, r.d, 1e-4 * k, NULL, NULL, &e), CD_OK, "%s", e.msg);
        cr_assert_eq(cd_h5_append(w, r.m, r.d, &e), CD_OK, "%s", e.msg);
    }
    copy_file(path, copy);
    f = open_ro(copy);
    cr_assert(f >= 0);
    c = attr_ll(f, "committed_samples");
    cr_expect(c > 1500 - 1024 && c <= 1500, "committed %lld", c);
    H5Fclose(f);
    cr_assert_eq(cd_h5_close(w, r.m, r.d, CD_OK, "", &e), CD_OK, "%s", e.msg);
    cleanup(path);
    cleanup(copy);
    free_scene(&r);
}

Test(h5, ring_overflow_is_counted_as_lost_events)
{
    /* An event log of 2 entries and a single append after 1 s of bouncing
     * (~20 events): the table keeps the 2 events still in the ring and
     * /events@lost counts the others: written + lost = ev_count exactly. */
    scene r = make_scene(2);
    cd_error e;
    char path[256];
    cd_h5_writer *w;
    hid_t f, ds;
    hsize_t d[3];
    long long lost;
    tmp_path(path, sizeof path, "lost");
    w = cd_h5_create(path, r.m, NULL, &e);
    cr_assert(w, "%s", e.msg);
    cr_assert_eq(cd_sim_advance(r.m, r.d, 1.0, NULL, NULL, &e), CD_OK, "%s", e.msg);
    cr_assert_eq(cd_h5_append(w, r.m, r.d, &e), CD_OK, "%s", e.msg);
    cr_assert_eq(cd_h5_close(w, r.m, r.d, CD_OK, "", &e), CD_OK, "%s", e.msg);
    cr_assert_gt(r.d->ev_count, 4);
    f = open_ro(path);
    cr_assert(f >= 0);
    dims_of(f, "/events", d);
    ds = H5Dopen2(f, "/events", H5P_DEFAULT);
    lost = attr_ll(ds, "lost");
    H5Dclose(ds);
    cr_expect_eq(d[0], 2);
    cr_expect_eq((long)(d[0] + (hsize_t)lost), r.d->ev_count, "written %llu + lost %lld vs %ld",
                 (unsigned long long)d[0], lost, r.d->ev_count);
    H5Fclose(f);
    cleanup(path);
    free_scene(&r);
}

Test(h5, event_table_matches_the_log)
{
    /* The first event is the ball touching the right wall: onset of slot 1
     * (second pair), open -> stick, at t = (0.15 - 0.1) / 1 m/s = 0.05 s
     * (check point radius 0.1 m, located to 1e-10 s; 1e-9 allowed). */
    typedef struct { double t; int kind, slot, body_a, body_b, mode_from, mode_to; double x, fn, ft; } ev_t;
    scene r = make_scene(0);
    cd_error e;
    char path[256];
    cd_h5_writer *w;
    hid_t f, ds, ct;
    hsize_t d[3];
    ev_t *ev;
    tmp_path(path, sizeof path, "events");
    w = cd_h5_create(path, r.m, NULL, &e);
    cr_assert(w, "%s", e.msg);
    run_sampled(&r, w, 0.3, 0.1, 1);
    cr_assert_eq(cd_h5_close(w, r.m, r.d, CD_OK, "", &e), CD_OK, "%s", e.msg);
    f = open_ro(path);
    cr_assert(f >= 0);
    dims_of(f, "/events", d);
    cr_assert_eq((long)d[0], r.d->ev_count);
    cr_assert_geq(d[0], 2);
    /* read with plain ints for the enum members: build a matching compound */
    ds = H5Dopen2(f, "/events", H5P_DEFAULT);
    {
        hid_t ft = H5Dget_type(ds), kt;
        int idx = H5Tget_member_index(ft, "kind");
        kt = H5Tget_member_type(ft, (unsigned)idx);
        cr_expect_eq(H5Tget_class(kt), H5T_ENUM, "kind is an HDF5 enum");
        ct = H5Tcreate(H5T_COMPOUND, sizeof(ev_t));
        H5Tinsert(ct, "t", HOFFSET(ev_t, t), H5T_NATIVE_DOUBLE);
        H5Tinsert(ct, "kind", HOFFSET(ev_t, kind), kt);
        H5Tinsert(ct, "slot", HOFFSET(ev_t, slot), H5T_NATIVE_INT);
        H5Tinsert(ct, "fn", HOFFSET(ev_t, fn), H5T_NATIVE_DOUBLE);
        H5Tclose(kt);
        H5Tclose(ft);
    }
    ev = calloc((size_t)d[0], sizeof *ev);
    cr_assert(H5Dread(ds, ct, H5S_ALL, H5S_ALL, H5P_DEFAULT, ev) >= 0);
    cr_expect_eq(ev[0].kind, CD_EV_ONSET);
    cr_expect_eq(ev[0].slot, 1);
    cr_expect_lt(fabs(ev[0].t - 0.05), 1e-9, "onset at %.12g s", ev[0].t);
    cr_expect_eq(ev[1].kind, CD_EV_SEPARATION);
    cr_expect_eq(ev[1].t, cd_data_event(r.d, 1)->t);
    free(ev);
    H5Tclose(ct);
    H5Dclose(ds);
    H5Fclose(f);
    cleanup(path);
    free_scene(&r);
}

Test(h5, scenario_attributes_and_a_text_too_large_for_an_attribute)
{
    /* Scenario facts become root attributes; a 100 kB scenario text (more
     * than HDF5's 64 KiB object-header limit) goes to the dataset
     * /scenario_text, byte for byte, and the attribute points to it. */
    scene r = make_scene(0);
    cd_error e;
    char path[256], s[256], *big, *back;
    cd_scenario sc;
    cd_h5_writer *w;
    hid_t f, ds;
    hsize_t d[3];
    size_t i, n = 100000;
    big = malloc(n + 1);
    for (i = 0; i < n; i++) big[i] = (char)('a' + (char)(i % 26));
    big[n] = 0;
    memset(&sc, 0, sizeof sc);
    sc.model = r.m;
    sc.path = (char *)"scenarios/big.toml";
    sc.title = (char *)"big \xc2\xb5 scenario";  /* UTF-8 */
    sc.text = big;
    sc.overrides = (char *)"simulation.duration=1\n";
    sc.duration = 1.0;
    sc.output_dt = 0.01;
    tmp_path(path, sizeof path, "bigtext");
    w = cd_h5_create(path, r.m, &sc, &e);
    cr_assert(w, "%s", e.msg);
    cr_assert_eq(cd_h5_close(w, r.m, r.d, CD_OK, "", &e), CD_OK, "%s", e.msg);
    f = open_ro(path);
    cr_assert(f >= 0);
    attr_s(f, "title", s, sizeof s);
    cr_expect_str_eq(s, "big \xc2\xb5 scenario");
    attr_s(f, "scenario_path", s, sizeof s);
    cr_expect_str_eq(s, "scenarios/big.toml");
    attr_s(f, "overrides", s, sizeof s);
    cr_expect_str_eq(s, "simulation.duration=1\n");
    attr_s(f, "scenario_text", s, sizeof s);
    cr_expect(strncmp(s, "@dataset /scenario_text", 23) == 0, "attribute points to the dataset: %s", s);
    cr_expect_eq(dims_of(f, "/scenario_text", d), 1);
    cr_expect_eq(d[0], n);
    back = calloc(1, n + 1);
    ds = H5Dopen2(f, "/scenario_text", H5P_DEFAULT);
    cr_assert(H5Dread(ds, H5T_NATIVE_CHAR, H5S_ALL, H5S_ALL, H5P_DEFAULT, back) >= 0);
    cr_expect(memcmp(back, big, n) == 0, "the text round-trips");
    H5Dclose(ds);
    H5Fclose(f);
    free(back);
    free(big);
    cleanup(path);
    free_scene(&r);
}

Test(h5, unwritable_path_fails_at_create)
{
    /* A path in a missing directory: CD_EIO, the message names the path, no file. */
    scene r = make_scene(0);
    cd_error e;
    const char *bad = "/nonexistent_capdyn_dir/x/results.h5";
    cd_h5_writer *w = cd_h5_create(bad, r.m, NULL, &e);
    cr_expect_null(w);
    cr_expect_eq(e.status, CD_EIO);
    cr_expect(strstr(e.msg, bad) != NULL, "message names the path: %s", e.msg);
    cr_expect_neq(access(bad, F_OK), 0);
    free_scene(&r);
}

Test(h5, append_rejects_another_model)
{
    /* A writer created for one model refuses data of a different layout. */
    scene r = make_scene(0), r2;
    cd_error e;
    char path[256];
    cd_h5_writer *w;
    cd_model *m2 = cd_model_create();
    cd_system_desc s = cd_system_desc_default();
    cd_data *d2;
    tmp_path(path, sizeof path, "mismatch");
    w = cd_h5_create(path, r.m, NULL, &e);
    cr_assert(w, "%s", e.msg);
    s.name = "lonely";
    cr_assert(cd_model_add_system(m2, &s, &e) >= 0);
    cr_assert_eq(cd_model_finalize(m2, &e), CD_OK);
    d2 = cd_data_create(m2, 0, &e);
    cr_assert(d2);
    cr_expect_eq(cd_h5_append(w, m2, d2, &e), CD_EINVAL);
    cr_expect_eq(cd_h5_close(w, r.m, r.d, CD_OK, "", &e), CD_OK, "%s", e.msg);
    r2.m = m2;
    r2.d = d2;
    free_scene(&r2);
    cleanup(path);
    free_scene(&r);
}

/* ---- write failures (disk full, file size limit) ------------------------------ */

/* Appends samples k0..k1 of the scene at t = k * 0.01 s; returns the first
 * status that is not CD_OK (or CD_OK). */
static cd_status append_range(scene *r, cd_h5_writer *w, int k0, int k1, cd_error *e)
{
    cd_status st;
    int k;
    for (k = k0; k <= k1; k++) {
        if (k > 0 && (st = cd_sim_advance(r->m, r->d, 0.01 * k, NULL, NULL, e)) != CD_OK) return st;
        if ((st = cd_h5_append(w, r->m, r->d, e)) != CD_OK) return st;
    }
    return CD_OK;
}

/* The committed rows of /time must be exactly t = 0.01 k (the sample times
 * the scene was advanced to: cd_sim_advance ends exactly at t_end). */
static void expect_committed_times(const char *path, long n_expected)
{
    cd_error e;
    cd_h5r *r = cd_h5r_open(path, &e);
    double *t;
    long k;
    cr_assert_not_null(r, "%s", e.msg);
    cr_expect_eq(r->n, n_expected, "committed samples %ld, expected %ld", r->n, n_expected);
    t = cd_h5r_series(r, "/time", NULL, &e);
    cr_assert_not_null(t, "%s", e.msg);
    for (k = 0; k < r->n; k++) cr_expect_eq(t[k], 0.01 * (double)k, "t[%ld] = %.17g", k, t[k]);
    free(t);
    {
        char *st = cd_h5r_attr_str(r, "/", "run_status");
        cr_assert_not_null(st);
        cr_expect_str_neq(st, "ok", "a run whose last commit failed never says ok");
        free(st);
    }
    cd_h5r_close(r);
}

Test(h5, disk_full_stops_before_writing_and_the_file_stays_consistent)
{
    /* The free-space check before a commit (statvfs): with a reserve larger
     * than any disk it refuses the second commit as on a full disk. Nothing
     * is written then, so the file opens without h5clear and holds the 21
     * samples of the first commit, bit for bit; the final status is an I/O
     * error even though the caller says "ok" (its last samples were never
     * committed). */
    scene r = make_scene(0);
    cd_error e;
    char path[256];
    cd_h5_writer *w;
    tmp_path(path, sizeof path, "diskfull");
    w = cd_h5_create(path, r.m, NULL, &e);
    cr_assert(w, "%s", e.msg);
    cr_assert_eq(append_range(&r, w, 0, 20, &e), CD_OK, "%s", e.msg);
    cr_assert_eq(cd_h5_flush(w, &e), CD_OK, "%s", e.msg);
    cd_h5_writer_set_space_check(w, 1, 1e30);
    cr_assert_eq(append_range(&r, w, 21, 25, &e), CD_OK, "appends only buffer: %s", e.msg);
    cr_expect_eq(cd_h5_flush(w, &e), CD_EIO);
    cr_expect(strstr(e.msg, "disk full") && strstr(e.msg, path) && strstr(e.msg, "21 samples"),
              "message: %s", e.msg);
    cr_expect_eq(cd_h5_append(w, r.m, r.d, &e), CD_EIO, "later appends are refused");
    cr_expect(strstr(e.msg, "disk full") != NULL, "with the first error: %s", e.msg);
    cr_expect_eq(cd_h5_close(w, r.m, r.d, CD_OK, "finished", &e), CD_EIO);
    cr_expect(strstr(e.msg, "disk full") != NULL, "close repeats the first error: %s", e.msg);
    expect_committed_times(path, 21);
    {
        cd_h5r *rd = cd_h5r_open(path, &e);
        char *msg;
        cr_assert_not_null(rd, "%s", e.msg);
        msg = cd_h5r_attr_str(rd, "/", "run_message");
        cr_assert_not_null(msg);
        cr_expect(strstr(msg, "disk full") != NULL, "run_message: %s", msg);
        free(msg);
        msg = cd_h5r_attr_str(rd, "/", "run_status");
        cr_expect_str_eq(msg, cd_status_string(CD_EIO));
        free(msg);
        cd_h5r_close(rd);
    }
    cleanup(path);
    free_scene(&r);
}

Test(h5, a_failed_write_keeps_the_committed_rows_after_h5clear, .timeout = 30)
{
    /* The worst case, which the space check cannot foresee (a disk quota):
     * a real write failure. A child process commits 31 samples, lowers its
     * file size limit to the current size + 4 KiB (SIGXFSZ ignored: the
     * write fails with EFBIG), turns the space check off and commits
     * 40 more. The writer must report the failure naming the file and
     * h5clear, refuse later calls, close without crashing (then the child
     * calls H5close(), which crashed at exit before), and leave a file whose
     * 31 committed rows are readable after `h5clear --increment=0` with a
     * status that is not "ok". */
    scene r = make_scene(0);
    char path[256], cmd[600];
    pid_t pid;
    int st;
    tmp_path(path, sizeof path, "fsize");
    fflush(NULL);
    pid = fork();
    cr_assert(pid >= 0);
    if (pid == 0) {
        cd_error e;
        cd_h5_writer *w = cd_h5_create(path, r.m, NULL, &e);
        struct stat sb;
        struct rlimit rl;
        cd_status s1, s2;
        if (!w) _exit(10);
        if (append_range(&r, w, 0, 30, &e) != CD_OK || cd_h5_flush(w, &e) != CD_OK) _exit(11);
        if (stat(path, &sb) != 0) _exit(12);
        signal(SIGXFSZ, SIG_IGN);
        if (getrlimit(RLIMIT_FSIZE, &rl) != 0) _exit(13);
        rl.rlim_cur = (rlim_t)sb.st_size + 4096;
        if (setrlimit(RLIMIT_FSIZE, &rl) != 0) _exit(13);
        cd_h5_writer_set_space_check(w, 0, 0);
        s1 = append_range(&r, w, 31, 70, &e);
        if (s1 == CD_OK) s1 = cd_h5_flush(w, &e);
        if (s1 != CD_EIO) _exit(14);
        if (!strstr(e.msg, path) || !strstr(e.msg, "h5clear") || !strstr(e.msg, "31 samples")) {
            fprintf(stderr, "message: %s\n", e.msg);
            _exit(15);
        }
        if (cd_h5_append(w, r.m, r.d, &e) != CD_EIO) _exit(16);
        s2 = cd_h5_close(w, r.m, r.d, CD_OK, "finished", &e);
        if (s2 != CD_EIO) _exit(17);
        H5close();
        _exit(0);
    }
    cr_assert_eq(waitpid(pid, &st, 0), pid);
    cr_assert(WIFEXITED(st), "the child was killed by signal %d", WIFSIGNALED(st) ? WTERMSIG(st) : 0);
    cr_assert_eq(WEXITSTATUS(st), 0, "child check %d failed (see the test's source)", WEXITSTATUS(st));
    snprintf(cmd, sizeof cmd, "h5clear --increment=0 '%s' >/dev/null 2>&1", path);
    cr_assert_eq(system(cmd), 0, "h5clear --increment=0 failed");
    expect_committed_times(path, 31);
    cleanup(path);
    free_scene(&r);
}
