/* HDF5 results writer (include/capdyn/io.h; layout in docs/results-format.md).
 *
 * Kill safety (docs/reliability.md, "Results files"). HDF5 1.10 has no
 * journal, so the writer keeps these rules that together make every
 * committed sample survive a kill at any write, and every dataset of a
 * file at the requested name readable (tests/test_results_safety.c kills
 * a run at every one of its writes):
 *  0. The file is written under a temporary name and takes its name only
 *     after its first commit (the layout and the first sample, which the
 *     first cd_h5_append commits at once) is flushed (issue 28: renamed
 *     after the layout alone, a kill inside the first commit left a file
 *     with no dataset that read).
 *  1. The file is touched ONLY inside a commit: samples and events are
 *     buffered by cd_h5_append; a commit (cd_h5_flush, or a full buffer)
 *     writes every pending row and flushes (H5Fflush), then rewrites the
 *     counters /committed_events and /committed_samples (the latter last)
 *     in place and flushes again. Readers trust only committed rows.
 *  2. Space is never reused (file space strategy NONE). A commit rewrites
 *     the last, partly filled chunk of every series; a deflated chunk whose
 *     size changed moves to new space (one of the same size is rewritten
 *     in place). With HDF5's default strategy the space it
 *     left was handed to the next chunk written in the same commit while
 *     the chunk index on disk still pointed there: a kill before the index
 *     was flushed left committed rows that no longer decompressed, or read
 *     as zeros (measured: 49 of 262 kill points damaged committed rows).
 *     Now the old copy stays intact until the new index is on disk; the
 *     file grows by the rewritten chunks (+6 % for the Fig. 5 grasp).
 *  3. No metadata grows after the layout: every attribute, including those
 *     written at close (t_final, stats_*, closed_utc, the status), exists
 *     from the start at its final size and is rewritten in place. HDF5
 *     flushes metadata in address order, so an object header written before
 *     the new continuation block it points to (which lies at the end of the
 *     file) made the whole root unreadable when the run was killed between
 *     the two writes.
 *  4. No chunk index grows past one B-tree node: HDF5 writes a split node's
 *     parent (a lower address) before its new children, so a kill between
 *     them left the committed rows of the wide contact series unreadable
 *     (measured on the whole Fig. 5 run: 9 of 507 kill points, all in the
 *     commit where /contacts/ft etc. passed 64 chunks). Chunks are sized
 *     from the run's expected sample count (CD_H5_MAX_CHUNKS).
 *  5. Every chunk index exists before the first commit (make_chunk_index:
 *     the event table's would otherwise be created by its first event).
 *  6. Before a commit the superblock's end of allocation is moved past
 *     what the commit can add (reserve_eoa), so that no chunk index on disk
 *     points past it and a plain (non-SWMR) HDF5 open reads every dataset
 *     after a kill inside a commit.
 * What is not covered: a run longer than expected (a library caller
 * without a scenario, sc == NULL), or so long that 60 chunks of 4 MiB do
 * not hold a series, splits the index again; the window is a few writes
 * per split.
 * A process killed by a signal keeps what it already passed to write(2);
 * nothing here calls fsync, so a power loss is not covered.
 *
 * The file never replaces the scenario nor another run's file: see
 * claim_output(). The superblock is version 2 (the space strategy needs
 * it), which has no "file open for writing" flag that HDF5 1.10 checks, so
 * a file left by a killed writer opens without h5clear.
 *
 * Non-finite outputs: cd_h5_append stores the sample, then refuses a row
 * with an inf or NaN (CD_ENUMERIC naming the dataset, the element and the
 * time), so that a run never ends "ok" with non-finite results.
 *
 * Write failures (docs/results-format.md, "When writing fails"). Before a
 * commit writes anything, check_space() asks the file system (statvfs) and
 * the file size limit (RLIMIT_FSIZE) for room for a generous estimate of
 * it; without room the writer stops ("stopped") while the file is still
 * as of its last commit, and still closes it with an I/O error status. A
 * write that fails anyway (a quota) marks the writer "failed": nothing more
 * is written to the file (its descriptor is pointed at /dev/null so that
 * HDF5's close succeeds and leaves nothing half destroyed in its id table),
 * and the file may need `h5clear --increment=0` to be read. The final
 * status is written last, after the data commit succeeded, and in place
 * (fixed-size attributes), so a file never says "ok" when its last commit
 * failed.
 * An allocation that fails (capdyn's, or HDF5's as its error stack or
 * errno says: note_h5_error) is reported as out of memory, CD_ENOMEM,
 * never as a disk problem.
 *
 * HDF5 prints its error stack by default; every public call here silences
 * the automatic printing for its own duration (saved and restored), so the
 * library never prints. */
#define _DEFAULT_SOURCE /* flock */
#define _POSIX_C_SOURCE 200809L
#include "capdyn/io.h"
#include "../math/cd_math.h"

#include <hdf5.h>
#include "h5_util.h"
#include "h5_schema.h"
#include "h5_pack.h"
#include <errno.h>
#include <stdint.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <fcntl.h>
#include <libgen.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <time.h>
#include <unistd.h>

#define CD_H5_FORMAT_VERSION 1
#define CD_H5_NAMELEN 64   /* fixed-length name fields in the static tables */
#define CD_H5_ATTR_MAX 60000 /* larger texts go to a dataset (object header limit 64 KiB) */
/* The status attributes are created at their final size (fixed-length
 * strings), so that writing the final status rewrites them in place and
 * allocates nothing in the file. */
#define CD_H5_STATUS_LEN 48
#define CD_H5_MESSAGE_LEN 1024
#define CD_H5_UTC_LEN 32
/* HDF5's v1 B-tree chunk index holds 64 chunks in a node (istore_k 32).
 * Splitting a node writes the parent before the new children (address
 * order), which a kill between the two leaves pointing at nothing: chunks
 * are sized so that a run stays below 60 chunks per series (margin for the
 * rows appended after a failure) when that keeps chunks under 4 MiB. */
#define CD_H5_MAX_CHUNKS 60
#define CD_H5_MAX_CHUNK_BYTES (4u << 20)
/* Room a commit keeps beyond its own estimate: metadata (chunk index nodes,
 * object header continuations) and the closing attributes. */
#define CD_H5_SPACE_MARGIN (512.0 * 1024.0)

enum { T_F64 = CD_H5_F64, T_I64 = CD_H5_I64, T_I8 = CD_H5_I8 };

/* One time series: a dataset (n x tail...) extended on every commit, and a
 * buffer of rows not yet written. */
typedef struct {
    hid_t dset;
    int rank;             /* 1 + number of tail dimensions */
    hsize_t tail[2];
    size_t rowlen;        /* elements per row */
    int type;             /* T_F64, T_I64, T_I8 */
    unsigned char *buf;   /* cap_rows x rowlen elements */
    long long chunk_rows; /* rows per chunk */
    unsigned char *chunk; /* the rows of the last chunk written, zeros after them
                           * (chunk_rows x rowlen elements; only when the
                           * writer packs its chunks itself, h5_pack.c) */
} h5_series;

/* series indices of one system, by series id (-1: not in this system) */
typedef struct {
    int idx[CD_SER_COUNT];
} sys_series;

struct cd_h5_writer {
    hid_t file;
    int has_capture, capture_set;  /* the layout has the capture_* attributes; a verdict was given */
    int has_control;               /* ... and the [control] figures of merit (docs/capture.md) */
    cd_h5_capture capture;
    char capture_verdict[16];
    double *step_peak;            /* CD_H5_STEP_COUNT x nslot (cd_h5_set_step_peaks), NULL until given */
    int nsys, nbody, nslot, ny;   /* of the model the file was created for */
    h5_series *ser;
    int nser, capser;
    int cap_rows, nbuf;           /* row buffer capacity and rows pending */
    long long nwritten;           /* rows on disk (= committed after a commit) */
    long long ncommitted;         /* the committed_samples of the last good commit */
    /* series indices */
    int s[CD_SER_COUNT];          /* series index of each id outside /systems (-1: none) */
    sys_series *s_sys;
    /* events */
    hid_t ev_dset, ev_mtype, ev_ftype, kind_enum, mode_enum, owner_enum;
    cd_event *evbuf;
    long ev_nbuf, ev_capbuf;
    long long ev_written;
    long ev_next;                 /* total-count index of the next event to take from d */
    long long ev_lost;
    struct timespec wall0;
    char *path;                   /* for messages and the free-space check */
    int lock_fd;                  /* holds flock(LOCK_EX) on the file while it is written */
    int sink_fd;                  /* /dev/null, opened with the writer for detach_file (-1: none) */
    /* failed: an HDF5 write failed; the file on disk may be damaged beyond
     * its last commit and nothing more is written to it.
     * stopped: the space check refused a commit before writing anything;
     * the file is consistent (as of its last commit) and still takes the
     * closing attributes. */
    int failed, stopped;
    /* oom: an allocation failed during this public call (capdyn's own, or
     * HDF5's error stack says so): a failed write is reported as out of
     * memory, not as a disk problem (writer_quiet_begin) */
    int oom;
    char why[512];                /* the first error, repeated by later calls */
    int space_check;              /* check free space before each commit (default 1) */
    double reserve;               /* bytes the check keeps free beyond its estimate */
    long long expect_rows;        /* samples the run expects (duration / output_dt + 2), 0 if unknown */
    int compress;                 /* deflate the sample series (simulation.compress, default 1) */
    cd_h5_packer pack;            /* compress: the chunks' shuffle + deflate (h5_pack.c) */
    hid_t fail_dset;              /* a packed chunk whose write failed (fail_len > 0): its */
    long long fail_off;           /* dataset, first row, and stream (still in pack.out) */
    size_t fail_len;
    /* The file is written under a temporary name until its first commit
     * (the layout and the first sample) is flushed: claim_tmp is that name,
     * claim_target the name it then takes (NULL once renamed). */
    char *claim_tmp, *claim_target;
    int claim_keep;               /* keep claim_tmp at the end (its rename failed) */
};

/* ---- out of memory, told apart from a failed write ---------------------------
 * Every public call of the writer replaces HDF5's automatic error printing
 * with note_h5_error (writer_quiet_begin), which HDF5 calls with the error
 * stack of every API call that fails: when the innermost record of that
 * stack (the error's origin) is an allocation failure (minor H5E_CANTALLOC,
 * which HDF5 1.10 files under the failing layer's major, e.g. H5E_PLIST; or
 * H5E_RESOURCE / H5E_NOSPACE), or errno is ENOMEM (a failed malloc; a
 * failed write leaves ENOSPC, EDQUOT, EFBIG or EIO), w->oom is set. capdyn's own
 * allocations on the writer's paths set it through note_oom. A failed
 * write then says "out of memory" (write_failed). */
static herr_t innermost_alloc(unsigned n, const H5E_error2_t *e, void *client)
{
    if (n == 0 && (e->min_num == H5E_CANTALLOC || (e->maj_num == H5E_RESOURCE && e->min_num == H5E_NOSPACE)))
        *(int *)client = 1;
    return 0;
}
static herr_t note_h5_error(hid_t estack, void *client)
{
    int oom = errno == ENOMEM;
    (void)H5Ewalk2(estack, H5E_WALK_UPWARD, innermost_alloc, &oom);
    if (oom) ((struct cd_h5_writer *)client)->oom = 1;
    return 0;
}
/* capdyn's own allocation failed, inside a writer call: the writer of that
 * call (the client of the error handler writer_quiet_begin set) is told */
static void note_oom(void)
{
    H5E_auto2_t f = NULL;
    void *c = NULL;
    if (H5Eget_auto2(H5E_DEFAULT, &f, &c) >= 0 && f == note_h5_error && c) ((struct cd_h5_writer *)c)->oom = 1;
}
static void writer_quiet_begin(cd_h5_quiet *q, struct cd_h5_writer *w)
{
    (void)H5Eget_auto2(H5E_DEFAULT, &q->func, &q->data);
    (void)H5Eset_auto2(H5E_DEFAULT, note_h5_error, w);
    w->oom = 0;
    errno = 0;
}

/* ---- error plumbing --------------------------------------------------------- */

#define seterr cd_error_set

/* ---- attributes ---------------------------------------------------------------- */
static hid_t str_type(size_t len)
{
    hid_t t = H5Tcopy(H5T_C_S1);
    if (t < 0) return t;
    H5Tset_size(t, len > 0 ? len : 1);
    H5Tset_strpad(t, H5T_STR_NULLTERM);
    H5Tset_cset(t, H5T_CSET_UTF8); /* titles and names may be UTF-8; ASCII is a subset */
    return t;
}

static int attr_write(hid_t obj, const char *name, hid_t ftype, hid_t mtype, int n, const void *v)
{
    hid_t sp, a;
    hsize_t dim = (hsize_t)n;
    herr_t r;
    if (H5Aexists(obj, name) > 0) {
        a = H5Aopen(obj, name, H5P_DEFAULT);
        /* a string of another length needs a new attribute */
        if (a >= 0) {
            hid_t t = H5Aget_type(a);
            hid_t s = H5Aget_space(a);
            int same = H5Tget_size(t) == H5Tget_size(ftype) &&
                       H5Sget_simple_extent_npoints(s) == (hssize_t)(n > 0 ? n : 1);
            H5Tclose(t);
            H5Sclose(s);
            if (same) {
                r = H5Awrite(a, mtype, v);
                H5Aclose(a);
                return r < 0 ? -1 : 0;
            }
            H5Aclose(a);
        }
        if (H5Adelete(obj, name) < 0) return -1;
    }
    sp = n > 0 ? H5Screate_simple(1, &dim, NULL) : H5Screate(H5S_SCALAR);
    if (sp < 0) return -1;
    a = H5Acreate2(obj, name, ftype, sp, H5P_DEFAULT, H5P_DEFAULT);
    H5Sclose(sp);
    if (a < 0) return -1;
    r = H5Awrite(a, mtype, v);
    H5Aclose(a);
    return r < 0 ? -1 : 0;
}

static int attr_str(hid_t obj, const char *name, const char *s)
{
    hid_t t;
    int r;
    if (!s) s = "";
    t = str_type(strlen(s) + 1);
    if (t < 0) return -1;
    r = attr_write(obj, name, t, t, 0, s);
    H5Tclose(t);
    return r;
}
/* A string attribute of a fixed size (len bytes with the NUL; longer text
 * is cut), rewritten in place when it already has that size. */
static int attr_str_fixed(hid_t obj, const char *name, const char *s, size_t len)
{
    char *buf = calloc(1, len);
    hid_t t;
    int r;
    if (!buf) { note_oom(); return -1; }
    snprintf(buf, len, "%s", s ? s : "");
    t = str_type(len);
    if (t < 0) { free(buf); return -1; }
    r = attr_write(obj, name, t, t, 0, buf);
    H5Tclose(t);
    free(buf);
    return r;
}
static int attr_i64(hid_t obj, const char *name, long long v)
{ return attr_write(obj, name, H5T_STD_I64LE, H5T_NATIVE_LLONG, 0, &v); }
static int attr_int(hid_t obj, const char *name, int v)
{ return attr_write(obj, name, H5T_STD_I32LE, H5T_NATIVE_INT, 0, &v); }
static int attr_f64(hid_t obj, const char *name, double v)
{ return attr_write(obj, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 0, &v); }
static int attr_f64v(hid_t obj, const char *name, int n, const double *v)
{ return attr_write(obj, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, n, v); }

/* An array of n strings, each at most len-1 characters. */
static int attr_strv(hid_t obj, const char *name, int n, const char *const *v, size_t len)
{
    char *flat;
    hid_t t;
    int i, r;
    if (n < 0) return -1;
    flat = calloc((size_t)n, len);
    if (!flat) { note_oom(); return -1; }
    for (i = 0; i < n; i++) snprintf(flat + (size_t)i * len, len, "%s", v[i]);
    t = str_type(len);
    r = attr_write(obj, name, t, t, n, flat);
    H5Tclose(t);
    free(flat);
    return r;
}

/* A text that may exceed the attribute size limit: an attribute when it fits,
 * else a 1-D char dataset of that name at the root and an attribute pointing to it. */
static int attr_text(hid_t file, const char *name, const char *s)
{
    size_t n;
    hid_t sp, ds;
    hsize_t dim;
    char note[160];
    herr_t r;
    if (!s) s = "";
    n = strlen(s);
    if (n < CD_H5_ATTR_MAX) return attr_str(file, name, s);
    dim = (hsize_t)n;
    sp = H5Screate_simple(1, &dim, NULL);
    if (sp < 0) return -1;
    ds = H5Dcreate2(file, name, H5T_NATIVE_CHAR, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    H5Sclose(sp);
    if (ds < 0) return -1;
    r = H5Dwrite(ds, H5T_NATIVE_CHAR, H5S_ALL, H5S_ALL, H5P_DEFAULT, s);
    H5Dclose(ds);
    if (r < 0) return -1;
    snprintf(note, sizeof note, "@dataset /%s (%lu bytes)", name, (unsigned long)n);
    return attr_str(file, name, note);
}

/* ---- static tables ------------------------------------------------------------ */
typedef struct {
    int id, system, parent, joint_type, dof;
    char name[CD_H5_NAMELEN], full_name[2 * CD_H5_NAMELEN];
    double mass, com[3], inertia[9], joint_pos[3], joint_rot[9], axis[3];
} body_row;

typedef struct {
    int id, body;
    double pos[3], radius;
} cp_row;

typedef struct {
    int id, body, type;
    char type_name[16];
    double pos[3], rot[9], size[3];
    int vert_adr, vert_num;
} shape_row;

typedef struct {
    int slot, checkpoint, shape, law, body_a, body_b;
    char body_a_name[2 * CD_H5_NAMELEN], body_b_name[2 * CD_H5_NAMELEN], shape_type[16];
    double cp_pos[3], cp_radius;
    double K, D, p, q, Kt, Dt, mu_s, mu_k;
} slot_row;

static hid_t arr_type(hid_t base, hsize_t n) { return H5Tarray_create2(base, 1, &n); }

/* compound member helpers: closes the member type after insertion */
static void ins(hid_t ct, const char *name, size_t off, hid_t t) { H5Tinsert(ct, name, off, t); }
static void ins_arr(hid_t ct, const char *name, size_t off, hsize_t n)
{
    hid_t a = arr_type(H5T_NATIVE_DOUBLE, n);
    H5Tinsert(ct, name, off, a);
    H5Tclose(a);
}
static void ins_str(hid_t ct, const char *name, size_t off, size_t len)
{
    hid_t s = str_type(len);
    H5Tinsert(ct, name, off, s);
    H5Tclose(s);
}

static int write_table(hid_t loc, const char *name, hid_t mtype, size_t n, const void *rows)
{
    hsize_t dim = (hsize_t)n;
    hid_t ft = H5Tcopy(mtype), sp, ds;
    herr_t r = 0;
    if (ft < 0) return -1;
    H5Tpack(ft);
    sp = H5Screate_simple(1, &dim, NULL);
    ds = sp >= 0 ? H5Dcreate2(loc, name, ft, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT) : -1;
    if (ds >= 0 && n > 0) r = H5Dwrite(ds, mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, rows);
    if (ds >= 0) H5Dclose(ds);
    if (sp >= 0) H5Sclose(sp);
    H5Tclose(ft);
    return (ds < 0 || r < 0) ? -1 : 0;
}

static void full_name(const cd_model *m, int b, char *out, size_t len)
{
    int s = m->body_sys[b];
    if (m->body_parent[b] < 0) snprintf(out, len, "%s", m->sys_name[s]);
    else snprintf(out, len, "%s/%s", m->sys_name[s], m->body_name[b]);
}

static int write_model_tables(hid_t file, const cd_model *m)
{
    hid_t g = H5Gcreate2(file, "model", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), ct;
    int i, rc = 0;
    body_row *br;
    cp_row *cr;
    shape_row *sr;
    if (g < 0) return -1;
    /* bodies */
    br = calloc((size_t)(m->nbody ? m->nbody : 1), sizeof *br);
    cr = calloc((size_t)(m->ncp ? m->ncp : 1), sizeof *cr);
    sr = calloc((size_t)(m->nshape ? m->nshape : 1), sizeof *sr);
    if (!br || !cr || !sr) { note_oom(); rc = -1; goto out; }
    for (i = 0; i < m->nbody; i++) {
        body_row *r = br + i;
        r->id = i;
        r->system = m->body_sys[i];
        r->parent = m->body_parent[i];
        r->joint_type = m->body_jnt_type[i];
        r->dof = m->body_dof[i];
        snprintf(r->name, sizeof r->name, "%s", m->body_name[i]);
        full_name(m, i, r->full_name, sizeof r->full_name);
        r->mass = m->body_mass[i];
        memcpy(r->com, m->body_com + 3 * i, sizeof r->com);
        memcpy(r->inertia, m->body_inertia + 9 * i, sizeof r->inertia);
        memcpy(r->joint_pos, m->body_jnt_pos + 3 * i, sizeof r->joint_pos);
        memcpy(r->joint_rot, m->body_jnt_rot + 9 * i, sizeof r->joint_rot);
        memcpy(r->axis, m->body_axis + 3 * i, sizeof r->axis);
    }
    ct = H5Tcreate(H5T_COMPOUND, sizeof(body_row));
    ins(ct, "id", HOFFSET(body_row, id), H5T_NATIVE_INT);
    ins(ct, "system", HOFFSET(body_row, system), H5T_NATIVE_INT);
    ins(ct, "parent", HOFFSET(body_row, parent), H5T_NATIVE_INT);
    ins(ct, "joint_type", HOFFSET(body_row, joint_type), H5T_NATIVE_INT);
    ins(ct, "dof", HOFFSET(body_row, dof), H5T_NATIVE_INT);
    ins_str(ct, "name", HOFFSET(body_row, name), sizeof br->name);
    ins_str(ct, "full_name", HOFFSET(body_row, full_name), sizeof br->full_name);
    ins(ct, "mass", HOFFSET(body_row, mass), H5T_NATIVE_DOUBLE);
    ins_arr(ct, "com", HOFFSET(body_row, com), 3);
    ins_arr(ct, "inertia", HOFFSET(body_row, inertia), 9);
    ins_arr(ct, "joint_pos", HOFFSET(body_row, joint_pos), 3);
    ins_arr(ct, "joint_rot", HOFFSET(body_row, joint_rot), 9);
    ins_arr(ct, "axis", HOFFSET(body_row, axis), 3);
    if (write_table(g, "bodies", ct, (size_t)m->nbody, br) < 0) rc = -1;
    H5Tclose(ct);
    /* check points */
    for (i = 0; i < m->ncp; i++) {
        cr[i].id = i;
        cr[i].body = m->cp_body[i];
        memcpy(cr[i].pos, m->cp_pos + 3 * i, sizeof cr[i].pos);
        cr[i].radius = m->cp_radius[i];
    }
    ct = H5Tcreate(H5T_COMPOUND, sizeof(cp_row));
    ins(ct, "id", HOFFSET(cp_row, id), H5T_NATIVE_INT);
    ins(ct, "body", HOFFSET(cp_row, body), H5T_NATIVE_INT);
    ins_arr(ct, "pos", HOFFSET(cp_row, pos), 3);
    ins(ct, "radius", HOFFSET(cp_row, radius), H5T_NATIVE_DOUBLE);
    if (write_table(g, "checkpoints", ct, (size_t)m->ncp, cr) < 0) rc = -1;
    H5Tclose(ct);
    /* shapes */
    for (i = 0; i < m->nshape; i++) {
        sr[i].id = i;
        sr[i].body = m->shape_body[i];
        sr[i].type = m->shape_type[i];
        snprintf(sr[i].type_name, sizeof sr[i].type_name, "%s", cd_shape_type_name((cd_shape_type)m->shape_type[i]));
        memcpy(sr[i].pos, m->shape_pos + 3 * i, sizeof sr[i].pos);
        memcpy(sr[i].rot, m->shape_rot + 9 * i, sizeof sr[i].rot);
        memcpy(sr[i].size, m->shape_size + 3 * i, sizeof sr[i].size);
        sr[i].vert_adr = m->shape_vert_adr[i];
        sr[i].vert_num = m->shape_vert_num[i];
    }
    ct = H5Tcreate(H5T_COMPOUND, sizeof(shape_row));
    ins(ct, "id", HOFFSET(shape_row, id), H5T_NATIVE_INT);
    ins(ct, "body", HOFFSET(shape_row, body), H5T_NATIVE_INT);
    ins(ct, "type", HOFFSET(shape_row, type), H5T_NATIVE_INT);
    ins_str(ct, "type_name", HOFFSET(shape_row, type_name), sizeof sr->type_name);
    ins_arr(ct, "pos", HOFFSET(shape_row, pos), 3);
    ins_arr(ct, "rot", HOFFSET(shape_row, rot), 9);
    ins_arr(ct, "size", HOFFSET(shape_row, size), 3);
    ins(ct, "vert_adr", HOFFSET(shape_row, vert_adr), H5T_NATIVE_INT);
    ins(ct, "vert_num", HOFFSET(shape_row, vert_num), H5T_NATIVE_INT);
    if (write_table(g, "shapes", ct, (size_t)m->nshape, sr) < 0) rc = -1;
    H5Tclose(ct);
    /* convex-hull vertices (nvert x 3) */
    {
        hsize_t dims[2] = {(hsize_t)m->nvert, 3};
        hid_t sp = H5Screate_simple(2, dims, NULL);
        hid_t ds = sp >= 0 ? H5Dcreate2(g, "vertices", H5T_IEEE_F64LE, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT) : -1;
        if (ds < 0 || (m->nvert > 0 && H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, m->vert) < 0))
            rc = -1;
        if (ds >= 0) H5Dclose(ds);
        if (sp >= 0) H5Sclose(sp);
    }
    if (attr_f64v(g, "gravity", 3, m->gravity) < 0) rc = -1;
out:
    free(br);
    free(cr);
    free(sr);
    H5Gclose(g);
    return rc;
}

static int write_slot_table(hid_t g, const cd_model *m)
{
    slot_row *r = calloc((size_t)(m->nslot ? m->nslot : 1), sizeof *r);
    hid_t ct;
    int k, rc;
    if (!r) { note_oom(); return -1; }
    for (k = 0; k < m->nslot; k++) {
        int cp = m->slot_cp[k], sh = m->slot_shape[k];
        const cd_contact_law *L = &m->law[m->slot_law[k]];
        r[k].slot = k;
        r[k].checkpoint = cp;
        r[k].shape = sh;
        r[k].law = m->slot_law[k];
        r[k].body_a = m->cp_body[cp];
        r[k].body_b = m->shape_body[sh];
        full_name(m, r[k].body_a, r[k].body_a_name, sizeof r[k].body_a_name);
        full_name(m, r[k].body_b, r[k].body_b_name, sizeof r[k].body_b_name);
        snprintf(r[k].shape_type, sizeof r[k].shape_type, "%s", cd_shape_type_name((cd_shape_type)m->shape_type[sh]));
        memcpy(r[k].cp_pos, m->cp_pos + 3 * cp, sizeof r[k].cp_pos);
        r[k].cp_radius = m->cp_radius[cp];
        r[k].K = L->K; r[k].D = L->D; r[k].p = L->p; r[k].q = L->q;
        r[k].Kt = L->Kt; r[k].Dt = L->Dt; r[k].mu_s = L->mu_s; r[k].mu_k = L->mu_k;
    }
    ct = H5Tcreate(H5T_COMPOUND, sizeof(slot_row));
    ins(ct, "slot", HOFFSET(slot_row, slot), H5T_NATIVE_INT);
    ins(ct, "checkpoint", HOFFSET(slot_row, checkpoint), H5T_NATIVE_INT);
    ins(ct, "shape", HOFFSET(slot_row, shape), H5T_NATIVE_INT);
    ins(ct, "law", HOFFSET(slot_row, law), H5T_NATIVE_INT);
    ins(ct, "body_a", HOFFSET(slot_row, body_a), H5T_NATIVE_INT);
    ins(ct, "body_b", HOFFSET(slot_row, body_b), H5T_NATIVE_INT);
    ins_str(ct, "body_a_name", HOFFSET(slot_row, body_a_name), sizeof r->body_a_name);
    ins_str(ct, "body_b_name", HOFFSET(slot_row, body_b_name), sizeof r->body_b_name);
    ins_str(ct, "shape_type", HOFFSET(slot_row, shape_type), sizeof r->shape_type);
    ins_arr(ct, "cp_pos", HOFFSET(slot_row, cp_pos), 3);
    ins(ct, "cp_radius", HOFFSET(slot_row, cp_radius), H5T_NATIVE_DOUBLE);
    ins(ct, "K", HOFFSET(slot_row, K), H5T_NATIVE_DOUBLE);
    ins(ct, "D", HOFFSET(slot_row, D), H5T_NATIVE_DOUBLE);
    ins(ct, "p", HOFFSET(slot_row, p), H5T_NATIVE_DOUBLE);
    ins(ct, "q", HOFFSET(slot_row, q), H5T_NATIVE_DOUBLE);
    ins(ct, "Kt", HOFFSET(slot_row, Kt), H5T_NATIVE_DOUBLE);
    ins(ct, "Dt", HOFFSET(slot_row, Dt), H5T_NATIVE_DOUBLE);
    ins(ct, "mu_s", HOFFSET(slot_row, mu_s), H5T_NATIVE_DOUBLE);
    ins(ct, "mu_k", HOFFSET(slot_row, mu_k), H5T_NATIVE_DOUBLE);
    rc = write_table(g, "slots", ct, (size_t)m->nslot, r);
    H5Tclose(ct);
    free(r);
    return rc;
}

/* ---- time series ----------------------------------------------------------------- */
static size_t type_size(int t) { return t == T_F64 ? sizeof(double) : t == T_I64 ? sizeof(long long) : 1; }
static hid_t mem_type(int t) { return t == T_F64 ? H5T_NATIVE_DOUBLE : t == T_I64 ? H5T_NATIVE_LLONG : H5T_NATIVE_SCHAR; }
static hid_t file_type(int t) { return t == T_F64 ? H5T_IEEE_F64LE : t == T_I64 ? H5T_STD_I64LE : H5T_STD_I8LE; }

/* Creates an extendible (0 x tail) dataset; returns its series index or -1. */
static int add_series(cd_h5_writer *w, hid_t loc, const char *name, int type, int ntail, hsize_t t0,
                      hsize_t t1, const char *units, const char *desc)
{
    h5_series *s;
    hsize_t dims[3] = {0, t0, t1}, maxd[3] = {H5S_UNLIMITED, t0, t1}, chunk[3];
    hid_t sp, dcpl;
    size_t rowbytes;
    int rank = 1 + ntail;
    if (w->nser == w->capser) {
        int nc = w->capser ? 2 * w->capser : 32;
        h5_series *ns = realloc(w->ser, (size_t)nc * sizeof *ns);
        if (!ns) { w->oom = 1; return -1; }
        w->ser = ns;
        w->capser = nc;
    }
    s = w->ser + w->nser;
    memset(s, 0, sizeof *s);
    s->dset = -1;
    s->rank = rank;
    s->tail[0] = ntail > 0 ? t0 : 1;
    s->tail[1] = ntail > 1 ? t1 : 1;
    s->rowlen = (size_t)(s->tail[0] * s->tail[1]);
    s->type = type;
    rowbytes = s->rowlen * type_size(type);
    /* chunks of about 32 KiB along time: a few hundred rows for narrow series */
    chunk[0] = (hsize_t)(32768 / rowbytes);
    if (chunk[0] < 16) chunk[0] = 16;
    if (chunk[0] > 4096) chunk[0] = 4096;
    /* ... but no more than CD_H5_MAX_CHUNKS chunks for the rows the run is
     * expected to write (kill safety: the chunk index then never splits a
     * node, see the top of the file), up to CD_H5_MAX_CHUNK_BYTES a chunk */
    if (w->expect_rows > 0) {
        long long need = (w->expect_rows + CD_H5_MAX_CHUNKS - 1) / CD_H5_MAX_CHUNKS;
        long long cap = (long long)(CD_H5_MAX_CHUNK_BYTES / rowbytes);
        if (need > cap) need = cap;
        if (need > (long long)chunk[0]) chunk[0] = (hsize_t)need;
    }
    chunk[1] = t0;
    chunk[2] = t1;
    s->chunk_rows = (long long)chunk[0];
    sp = H5Screate_simple(rank, dims, maxd);
    dcpl = H5Pcreate(H5P_DATASET_CREATE);
    if (sp < 0 || dcpl < 0) goto fail;
    if (H5Pset_chunk(dcpl, rank, chunk) < 0) goto fail;
    if (w->compress) {
        if (type != T_I8) H5Pset_shuffle(dcpl);
        if (H5Pset_deflate(dcpl, 1) < 0) goto fail;
    }
    s->dset = H5Dcreate2(loc, name, file_type(type), sp, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    if (s->dset < 0) goto fail;
    if (units) attr_str(s->dset, "units", units);
    if (desc) attr_str(s->dset, "description", desc);
    H5Pclose(dcpl);
    H5Sclose(sp);
    w->nser++;
    return w->nser - 1;
fail:
    if (dcpl >= 0) H5Pclose(dcpl);
    if (sp >= 0) H5Sclose(sp);
    return -1;
}

static double *row_f64(cd_h5_writer *w, int si)
{
    h5_series *s = w->ser + si;
    return (double *)(void *)(s->buf + (size_t)w->nbuf * s->rowlen * sizeof(double));
}
static long long *row_i64(cd_h5_writer *w, int si)
{
    h5_series *s = w->ser + si;
    return (long long *)(void *)(s->buf + (size_t)w->nbuf * s->rowlen * sizeof(long long));
}
static signed char *row_i8(cd_h5_writer *w, int si)
{
    h5_series *s = w->ser + si;
    return (signed char *)(s->buf + (size_t)w->nbuf * s->rowlen);
}

/* Writes nrows rows from buf at row row0 of series s through HDF5 (its
 * filters, if the dataset has them). */
static int write_slab(const h5_series *s, long long row0, long long nrows, const void *buf)
{
    hsize_t off[3] = {(hsize_t)row0, 0, 0}, cnt[3];
    hid_t fs = H5Dget_space(s->dset), ms;
    herr_t r;
    if (fs < 0) return -1;
    cnt[0] = (hsize_t)nrows;
    cnt[1] = s->tail[0];
    cnt[2] = s->tail[1];
    if (H5Sselect_hyperslab(fs, H5S_SELECT_SET, off, NULL, cnt, NULL) < 0) { H5Sclose(fs); return -1; }
    ms = H5Screate_simple(s->rank, cnt, NULL);
    r = ms >= 0 ? H5Dwrite(s->dset, mem_type(s->type), ms, fs, H5P_DEFAULT, buf) : -1;
    if (ms >= 0) H5Sclose(ms);
    H5Sclose(fs);
    return r < 0 ? -1 : 0;
}

/* Writes rows [start, start + n) of series s, whose chunks the writer packs
 * itself (h5_pack.c): every chunk they touch is written whole
 * (H5Dwrite_chunk, all filters applied), the rows it had before from
 * s->chunk. A chunk the commit leaves partly filled keeps its rows in
 * s->chunk (zeros after them, as HDF5 fills) for the next commit, which
 * rewrites that chunk (rule 2); a chunk of pending rows only is packed
 * from the buffer. A chunk that does not pack goes through HDF5's own
 * filters. */
static int write_chunks(cd_h5_writer *w, h5_series *s, long long start, int n)
{
    cd_h5_packer *p = &w->pack;
    const size_t rowbytes = s->rowlen * type_size(s->type);
    const size_t bytes = (size_t)s->chunk_rows * rowbytes;
    long long c, c0 = start / s->chunk_rows, c1 = (start + n - 1) / s->chunk_rows;
    for (c = c0; c <= c1; c++) {
        long long r0 = c * s->chunk_rows, r1 = r0 + s->chunk_rows, a = start > r0 ? start : r0;
        long long b = start + n < r1 ? start + n : r1;
        hsize_t off[3] = {(hsize_t)r0, 0, 0};
        const unsigned char *raw = s->chunk;
        size_t len;
        if (a == r0 && b == r1) { /* a whole chunk of pending rows: packed where it is */
            raw = s->buf + (size_t)(a - start) * rowbytes;
        } else { /* rows after the last chunk's, and zeros after them */
            memcpy(s->chunk + (size_t)(a - r0) * rowbytes, s->buf + (size_t)(a - start) * rowbytes,
                   (size_t)(b - a) * rowbytes);
            memset(s->chunk + (size_t)(b - r0) * rowbytes, 0, (size_t)(r1 - b) * rowbytes);
        }
        len = cd_h5_pack(p, raw, bytes, (size_t)(b - r0) * rowbytes, type_size(s->type));
        if (len > 0) {
            if (H5Dwrite_chunk(s->dset, H5P_DEFAULT, 0, off, len, p->out) < 0) {
                /* kept for the close (writer_free): the space is allocated,
                 * the write did not happen */
                w->fail_dset = s->dset;
                w->fail_off = r0;
                w->fail_len = len;
                return -1;
            }
        } else if (write_slab(s, r0, b - r0, raw) < 0) { /* through HDF5's filters: the chunk's rows */
            return -1;
        }
    }
    return 0;
}

/* Writes the pending rows of series s at rows [start, start + n). */
static int write_rows(cd_h5_writer *w, h5_series *s, long long start, int n)
{
    hsize_t dims[3];
    dims[0] = (hsize_t)(start + n);
    dims[1] = s->tail[0];
    dims[2] = s->tail[1];
    if (H5Dset_extent(s->dset, dims) < 0) return -1;
    if (n == 0) return 0;
    if (s->chunk) return write_chunks(w, s, start, n);
    return write_slab(s, start, n, s->buf);
}

/* The event table's chunk index exists from the layout on (issue 28). HDF5
 * creates the index of a chunked dataset only with its first chunk; a first
 * event in a later commit would create its root node at the end of the file
 * and rewrite the dataset's header to point there, and HDF5 writes the
 * header first (address order): a kill between the two left the event
 * table unreadable ("wrong B-tree signature"). So one zero row is written
 * and flushed, then the table is cut back to 0 rows: the chunk leaves the
 * index, the (empty) root node stays. */
static int make_chunk_index(cd_h5_writer *w)
{
    hsize_t one = 1, zero = 0;
    cd_event e;
    herr_t r;
    memset(&e, 0, sizeof e);
    if (H5Dset_extent(w->ev_dset, &one) < 0) return -1;
    r = H5Dwrite(w->ev_dset, w->ev_mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, &e);
    if (r < 0 || H5Dflush(w->ev_dset) < 0 || H5Dset_extent(w->ev_dset, &zero) < 0) return -1;
    return 0;
}

static int write_events(cd_h5_writer *w)
{
    hsize_t dim, off, cnt;
    hid_t fs, ms;
    herr_t r;
    if (w->ev_nbuf == 0) return 0;
    dim = (hsize_t)(w->ev_written + w->ev_nbuf);
    if (H5Dset_extent(w->ev_dset, &dim) < 0) return -1;
    off = (hsize_t)w->ev_written;
    cnt = (hsize_t)w->ev_nbuf;
    fs = H5Dget_space(w->ev_dset);
    if (fs < 0) return -1;
    if (H5Sselect_hyperslab(fs, H5S_SELECT_SET, &off, NULL, &cnt, NULL) < 0) { H5Sclose(fs); return -1; }
    ms = H5Screate_simple(1, &cnt, NULL);
    r = ms >= 0 ? H5Dwrite(w->ev_dset, w->ev_mtype, ms, fs, H5P_DEFAULT, w->evbuf) : -1;
    if (ms >= 0) H5Sclose(ms);
    H5Sclose(fs);
    if (r < 0) return -1;
    w->ev_written += w->ev_nbuf;
    w->ev_nbuf = 0;
    return 0;
}

/* ---- space check ------------------------------------------------------------------ */
/* Rows a commit rewrites of one extendible dataset: every chunk the rows
 * [from, from + n) touch (a partly filled chunk is rewritten whole). */
static double chunk_bytes(long long from, long long n, long long chunk_rows, double row_bytes)
{
    long long first, last;
    if (n <= 0 || chunk_rows <= 0) return 0.0;
    first = from / chunk_rows;
    last = (from + n - 1) / chunk_rows;
    /* deflate can expand incompressible data by ~0.1 %; a rewritten chunk
     * may go to a new place: count it in full */
    return (double)(last - first + 1) * ((double)chunk_rows * row_bytes * 1.01 + 64.0);
}

/* A generous upper bound of the bytes the next commit adds to the file. */
static double commit_bytes(const cd_h5_writer *w)
{
    double b = CD_H5_SPACE_MARGIN;
    int i;
    for (i = 0; i < w->nser; i++) {
        const h5_series *s = w->ser + i;
        b += chunk_bytes(w->nwritten, w->nbuf, s->chunk_rows, (double)(s->rowlen * type_size(s->type)));
        b += w->nbuf > 0 ? 4096.0 : 0.0; /* chunk index node */
    }
    if (w->ev_nbuf > 0 && w->ev_ftype >= 0)
        b += chunk_bytes(w->ev_written, w->ev_nbuf, 512, (double)H5Tget_size(w->ev_ftype)) + 4096.0;
    return b;
}

static double mb(double bytes) { return bytes / 1048576.0; }

/* Before a commit writes anything: is there room for it on the file system
 * and under the file size limit (ulimit -f)? If not, stop the writer while
 * the file is still consistent (nothing committed so far is lost) instead
 * of letting HDF5 fail half way through writing its metadata, which can
 * leave a file that needs h5clear and whose last commit is damaged. A disk
 * quota or another process filling the disk is not seen here: the write
 * then fails (w->failed). */
static int check_space(const cd_h5_writer *w, double need, char *why, size_t len)
{
    double avail = -1.0;
    hsize_t size = 0;
    struct rlimit rl;
    struct statvfs vfs;
    void *handle = NULL;
    int have_vfs;
    if (!w->space_check) return 0;
    if (H5Fget_filesize(w->file, &size) < 0) size = 0;
    if (getrlimit(RLIMIT_FSIZE, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY &&
        (double)size + need > (double)rl.rlim_cur) {
        snprintf(why, len,
                 "results file '%s': the next write (up to %.2f MB) would pass the file size limit "
                 "(ulimit -f: %.2f MB, file %.2f MB); stopped before writing, the file keeps the %lld "
                 "samples committed so far",
                 w->path, mb(need), mb((double)rl.rlim_cur), mb((double)size), w->ncommitted);
        return -1;
    }
    /* the file's own descriptor: right even if the path was renamed */
    if (H5Fget_vfd_handle(w->file, H5P_DEFAULT, &handle) >= 0 && handle)
        have_vfs = fstatvfs(*(int *)handle, &vfs) == 0;
    else
        have_vfs = statvfs(w->path, &vfs) == 0;
    if (have_vfs) avail = (double)vfs.f_bavail * (double)vfs.f_frsize;
    if (have_vfs && avail < need) {
        snprintf(why, len,
                 "results file '%s': disk full: %.2f MB free, the next write needs up to %.2f MB; "
                 "stopped before writing, the file keeps the %lld samples committed so far",
                 w->path, mb(avail), mb(need), w->ncommitted);
        return -1;
    }
    return 0;
}

static cd_status refused(cd_h5_writer *w, cd_error *err)
{
    seterr(err, CD_EIO, "%s", w->why[0] ? w->why : "results file: an earlier write failed");
    return CD_EIO;
}

static cd_status write_failed(cd_h5_writer *w, cd_error *err, const char *what)
{
    w->failed = 1;
    if (w->oom) {
        snprintf(w->why, sizeof w->why,
                 "results file '%s': out of memory while %s; the file is as of its last commit (%lld samples) "
                 "and may need 'h5clear --increment=0 %s' before it can be read",
                 w->path, what, w->ncommitted, w->path);
        seterr(err, CD_ENOMEM, "%s", w->why);
        return CD_ENOMEM;
    }
    snprintf(w->why, sizeof w->why,
             "results file '%s': %s failed (disk full, quota or I/O error); the file is as of its last "
             "commit (%lld samples) and may need 'h5clear --increment=0 %s' before it can be read",
             w->path, what, w->ncommitted, w->path);
    seterr(err, CD_EIO, "%s", w->why);
    return CD_EIO;
}

/* The file takes its name (rule 0 at the top of the file): called once its
 * first commit is flushed. Under the directory lock, as in claim_output, a
 * target that another writer took meanwhile (it holds the file's lock) is
 * refused; then this writer stops and its temporary file is removed. */
static cd_status name_file(cd_h5_writer *w, cd_error *err)
{
    char *dcopy = malloc(strlen(w->claim_target) + 1);
    int dir_fd = -1, fd, busy = 0;
    if (!dcopy) {
        seterr(err, CD_ENOMEM, "out of memory");
        return CD_ENOMEM;
    }
    strcpy(dcopy, w->claim_target);
    dir_fd = open(dirname(dcopy), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    free(dcopy);
    if (dir_fd >= 0) (void)flock(dir_fd, LOCK_EX);
    fd = open(w->claim_target, O_RDONLY | O_NOCTTY | O_CLOEXEC);
    if (fd >= 0) {
        busy = flock(fd, LOCK_EX | LOCK_NB) != 0 && errno == EWOULDBLOCK;
        close(fd); /* drops the probe's lock */
    }
    if (busy) {
        snprintf(w->why, sizeof w->why,
                 "cannot write results file '%s': another run is writing it (the file is locked); "
                 "choose another -o or wait for that run to end",
                 w->path);
    } else if (rename(w->claim_tmp, w->claim_target) != 0) {
        snprintf(w->why, sizeof w->why, "cannot create results file '%s': renaming '%s' onto it failed: %s; "
                 "the results so far are in '%s'", w->path, w->claim_tmp, strerror(errno), w->claim_tmp);
        w->claim_keep = 1;
    } else {
        free(w->claim_tmp);
        w->claim_tmp = NULL;
    }
    if (dir_fd >= 0) close(dir_fd);
    if (!w->claim_tmp) return CD_OK;
    w->failed = 1;
    seterr(err, CD_EIO, "%s", w->why);
    return CD_EIO;
}

/* ---- rule 6: the end of allocation on disk covers the next commit ---------- */
/* The "end of allocation" (EOA) a plain HDF5 reader trusts is the one in the
 * superblock, which HDF5 writes last in a flush; a commit first writes its
 * new chunks beyond it, then the chunk index nodes that point there. A kill
 * between the two left a file that HDF5 opened in plain (non-SWMR) mode
 * refused to read past the old EOA ("addr overflow": h5dump, h5py without
 * swmr=True). So before a commit the file is extended (sparse, ftruncate)
 * to the current EOA plus a bound of what the commit adds, and the
 * superblock's EOA field is set to that end (in place, checksum updated).
 * HDF5 then allocates below it, and its own superblock written at the end
 * of the flush sets the true EOA again. The superblock is version 2 (the
 * space strategy needs it): signature, version 2, offset and length sizes 8,
 * flags, base address, extension address, EOA at byte 28, root header
 * address, then a Jenkins lookup3 checksum of the 44 bytes before it. A
 * superblock that does not parse or whose checksum does not verify is left
 * alone (the commit proceeds as before, with the window). */
static uint32_t rot32(uint32_t x, int k) { return (x << k) | (x >> (32 - k)); }

/* Bob Jenkins' lookup3 hash (hashlittle, initial value 0), which HDF5 uses
 * for its metadata checksums. */
static uint32_t lookup3(const unsigned char *k, size_t len)
{
    uint32_t a, b, c;
    a = b = c = 0xdeadbeefu + (uint32_t)len;
    while (len > 12) {
        a += k[0] + ((uint32_t)k[1] << 8) + ((uint32_t)k[2] << 16) + ((uint32_t)k[3] << 24);
        b += k[4] + ((uint32_t)k[5] << 8) + ((uint32_t)k[6] << 16) + ((uint32_t)k[7] << 24);
        c += k[8] + ((uint32_t)k[9] << 8) + ((uint32_t)k[10] << 16) + ((uint32_t)k[11] << 24);
        a -= c; a ^= rot32(c, 4); c += b;
        b -= a; b ^= rot32(a, 6); a += c;
        c -= b; c ^= rot32(b, 8); b += a;
        a -= c; a ^= rot32(c, 16); c += b;
        b -= a; b ^= rot32(a, 19); a += c;
        c -= b; c ^= rot32(b, 4); b += a;
        len -= 12;
        k += 12;
    }
    if (len == 0) return c;
    {
        uint32_t t[3] = {0, 0, 0};
        size_t i;
        for (i = 0; i < len; i++) t[i / 4] += (uint32_t)k[i] << (8 * (i % 4));
        a += t[0];
        b += t[1];
        c += t[2];
    }
    c ^= b; c -= rot32(b, 14);
    a ^= c; a -= rot32(c, 11);
    b ^= a; b -= rot32(a, 25);
    c ^= b; c -= rot32(b, 16);
    a ^= c; a -= rot32(c, 4);
    b ^= a; b -= rot32(a, 14);
    c ^= b; c -= rot32(b, 24);
    return c;
}

static uint64_t get_le(const unsigned char *p, int n)
{
    uint64_t v = 0;
    int i;
    for (i = n - 1; i >= 0; i--) v = (v << 8) | p[i];
    return v;
}
static void put_le(unsigned char *p, uint64_t v, int n)
{
    int i;
    for (i = 0; i < n; i++, v >>= 8) p[i] = (unsigned char)(v & 0xff);
}

/* Reads the superblock of the file open at fd: 0 and its EOA if it is a
 * version 2 superblock at offset 0 whose checksum verifies, else -1. */
static int sb_read(int fd, unsigned char sb[48], uint64_t *eoa)
{
    static const unsigned char sig[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};
    if (fd < 0 || pread(fd, sb, 48, 0) != 48) return -1;
    if (memcmp(sb, sig, 8) != 0 || sb[8] != 2 || sb[9] != 8 || sb[10] != 8 || get_le(sb + 12, 8) != 0) return -1;
    if (lookup3(sb, 44) != (uint32_t)get_le(sb + 44, 4)) return -1;
    *eoa = get_le(sb + 28, 8);
    return 0;
}

static void reserve_eoa(cd_h5_writer *w, double need)
{
    unsigned char sb[48];
    uint64_t disk_eoa, end;
    haddr_t eoa;
    struct stat st;
    struct rlimit rl;
    if (need <= 0 || need > 1e15 || H5Fget_eoa(w->file, &eoa) < 0 || sb_read(w->lock_fd, sb, &disk_eoa) < 0 ||
        fstat(w->lock_fd, &st) != 0)
        return;
    end = (uint64_t)eoa + (uint64_t)need;
    if (end < disk_eoa) end = disk_eoa;
    /* never past the file size limit (that would be SIGXFSZ, not an error) */
    if (getrlimit(RLIMIT_FSIZE, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY && (double)end > (double)rl.rlim_cur) return;
    if ((uint64_t)st.st_size < end && ftruncate(w->lock_fd, (off_t)end) != 0) return;
    put_le(sb + 28, end, 8);
    put_le(sb + 44, lookup3(sb, 44), 4);
    (void)pwrite(w->lock_fd, sb, 48, 0); /* one write of 48 bytes: whole or not at all */
}

/* After a commit and after the close: the file ends at the EOA its
 * superblock says again (the reserve is cut), so that between commits its
 * size is what HDF5 wrote. */
static void trim_to_eoa(int fd)
{
    unsigned char sb[48];
    uint64_t eoa;
    struct stat st;
    if (sb_read(fd, sb, &eoa) == 0 && fstat(fd, &st) == 0 && (uint64_t)st.st_size > eoa)
        (void)ftruncate(fd, (off_t)eoa);
}

/* The commit protocol (see the top of the file). */
static cd_status commit(cd_h5_writer *w, cd_error *err)
{
    int i;
    hid_t ev;
    char what[96];
    if (w->failed || w->stopped) return refused(w, err);
    if (check_space(w, commit_bytes(w) + w->reserve, w->why, sizeof w->why) < 0) {
        w->stopped = 1;
        seterr(err, CD_EIO, "%s", w->why);
        return CD_EIO;
    }
    reserve_eoa(w, commit_bytes(w));
    for (i = 0; i < w->nser; i++)
        if (write_rows(w, w->ser + i, w->nwritten, w->nbuf) < 0) {
            snprintf(what, sizeof what, "writing %d samples", w->nbuf);
            return write_failed(w, err, what);
        }
    if (write_events(w) < 0) return write_failed(w, err, "writing the event table");
    w->nwritten += w->nbuf;
    w->nbuf = 0;
    ev = w->ev_dset;
    if (attr_i64(ev, "lost", w->ev_lost) < 0 || H5Fflush(w->file, H5F_SCOPE_GLOBAL) < 0)
        return write_failed(w, err, "flushing the samples");
    if (attr_i64(w->file, "committed_events", w->ev_written) < 0 ||
        attr_i64(w->file, "committed_samples", w->nwritten) < 0 || H5Fflush(w->file, H5F_SCOPE_GLOBAL) < 0)
        return write_failed(w, err, "committing the sample counters");
    w->ncommitted = w->nwritten;
    trim_to_eoa(w->lock_fd); /* the reserve of rule 6 is not needed any more */
    /* the layout and the first sample are on disk: the file takes its name */
    if (w->claim_tmp && w->ncommitted > 0) return name_file(w, err);
    return CD_OK;
}

void cd_h5_writer_set_space_check(cd_h5_writer *w, int on, double reserve)
{
    if (!w) return;
    w->space_check = on != 0;
    w->reserve = reserve > 0 ? reserve : 0.0;
}

/* ---- lifetime ---------------------------------------------------------------------- */
/* After a failed write: point the file's descriptor (HDF5's default sec2
 * driver keeps one) at /dev/null. Closing flushes HDF5's dirty caches once
 * more; those writes then neither touch the file on disk again (it stays
 * as the failure left it: its last commit plus what the failed flush got
 * out) nor fail. A close that fails would leave the file in HDF5's id
 * table half destroyed, and HDF5's clean-up at exit (or H5close) would then
 * crash on it. Reads of /dev/null give zeros; everything a close needs is
 * in HDF5's caches for files of this size. The /dev/null descriptor was
 * opened with the writer (sink_fd): a process whose descriptors ran out
 * before the failure can still detach (test cli::a_failed_chunk_write_with_
 * no_descriptor_left_reads_as_committed). */
static void detach_file(cd_h5_writer *w)
{
    void *h = NULL;
    int sink = w->sink_fd, r;
    if (H5Fget_vfd_handle(w->file, H5P_DEFAULT, &h) < 0 || !h) return;
    if (sink < 0) sink = open("/dev/null", O_RDWR | O_CLOEXEC); /* the writer could not open it */
    if (sink < 0) return;
    r = dup2(sink, *(int *)h);
    if (sink != w->sink_fd) close(sink);
    if (r < 0) return; /* still the real file: write nothing more to it */
    /* A packed chunk whose write failed (write_chunks) had its file space
     * allocated: HDF5's end of allocation is then past the end of file it
     * wrote, and its close would truncate the file up to it, which
     * /dev/null refuses (EINVAL): the close failed. Written again, now to
     * /dev/null, the chunk takes new space at the end and its write
     * succeeds, so that the two ends agree again, as after a write HDF5
     * makes from its chunk cache, which the close writes once more. */
    if (w->fail_len > 0) {
        hsize_t off[3] = {(hsize_t)w->fail_off, 0, 0};
        (void)H5Dwrite_chunk(w->fail_dset, H5P_DEFAULT, 0, off, w->fail_len, w->pack.out);
    }
}

static void writer_free(cd_h5_writer *w)
{
    int i;
    if (!w) return;
    if (w->failed && w->file >= 0) detach_file(w);
    for (i = 0; i < w->nser; i++) {
        if (w->ser[i].dset >= 0) H5Dclose(w->ser[i].dset);
        free(w->ser[i].buf);
        free(w->ser[i].chunk);
    }
    cd_h5_packer_free(&w->pack);
    free(w->ser);
    free(w->s_sys);
    free(w->evbuf);
    free(w->step_peak);
    if (w->ev_dset >= 0) H5Dclose(w->ev_dset);
    if (w->ev_mtype >= 0) H5Tclose(w->ev_mtype);
    if (w->ev_ftype >= 0) H5Tclose(w->ev_ftype);
    if (w->kind_enum >= 0) H5Tclose(w->kind_enum);
    if (w->mode_enum >= 0) H5Tclose(w->mode_enum);
    if (w->owner_enum >= 0) H5Tclose(w->owner_enum);
    if (w->file >= 0) H5Fclose(w->file);
    if (!w->failed && w->file >= 0) trim_to_eoa(w->lock_fd);
    /* a file that never got its name holds no committed sample */
    if (w->claim_tmp && !w->claim_keep) unlink(w->claim_tmp);
    free(w->claim_tmp);
    free(w->claim_target);
    if (w->lock_fd >= 0) close(w->lock_fd);
    if (w->sink_fd >= 0) close(w->sink_fd);
    free(w->path);
    free(w);
}

/* A group name for system s: its own name when usable as one HDF5 link name
 * (non-empty, no '/', not "." and unique), else "system_<s>". */
static void sys_group_name(const cd_model *m, int s, char *out, size_t len)
{
    const char *n = m->sys_name[s];
    int ok = n && n[0] && !strchr(n, '/') && strcmp(n, ".") != 0 && strlen(n) < len, j;
    for (j = 0; ok && j < m->nsys; j++)
        if (j != s && strcmp(m->sys_name[j], n) == 0) ok = 0;
    if (ok) snprintf(out, len, "%s", n);
    else snprintf(out, len, "system_%d", s);
}

static int create_event_types(cd_h5_writer *w)
{
    int k, v;
    hid_t ct;
    w->kind_enum = H5Tenum_create(H5T_NATIVE_INT);
    w->mode_enum = H5Tenum_create(H5T_NATIVE_INT);
    w->owner_enum = H5Tenum_create(H5T_NATIVE_INT);
    if (w->kind_enum < 0 || w->mode_enum < 0 || w->owner_enum < 0) return -1;
    for (k = 0; k < CD_OWNER_NKINDS; k++) {
        v = k;
        H5Tenum_insert(w->owner_enum, cd_owner_kind_name((cd_owner_kind)k), &v);
    }
    for (k = 0; k < CD_EV_NKINDS; k++) {
        v = k;
        H5Tenum_insert(w->kind_enum, cd_event_kind_name((cd_event_kind)k), &v);
    }
    for (k = 0; k <= CD_MODE_SLIP; k++) {
        v = k;
        H5Tenum_insert(w->mode_enum, cd_slot_mode_name((cd_slot_mode)k), &v);
    }
    ct = H5Tcreate(H5T_COMPOUND, sizeof(cd_event));
    if (ct < 0) return -1;
    ins(ct, "t", HOFFSET(cd_event, t), H5T_NATIVE_DOUBLE);
    ins(ct, "kind", HOFFSET(cd_event, kind), w->kind_enum);
    ins(ct, "slot", HOFFSET(cd_event, slot), H5T_NATIVE_INT);
    ins(ct, "body_a", HOFFSET(cd_event, body_a), H5T_NATIVE_INT);
    ins(ct, "body_b", HOFFSET(cd_event, body_b), H5T_NATIVE_INT);
    ins(ct, "mode_from", HOFFSET(cd_event, mode_from), w->mode_enum);
    ins(ct, "mode_to", HOFFSET(cd_event, mode_to), w->mode_enum);
    ins(ct, "x", HOFFSET(cd_event, x), H5T_NATIVE_DOUBLE);
    ins(ct, "fn", HOFFSET(cd_event, fn), H5T_NATIVE_DOUBLE);
    ins(ct, "ft", HOFFSET(cd_event, ft), H5T_NATIVE_DOUBLE);
    ins(ct, "owner_kind", HOFFSET(cd_event, owner_kind), w->owner_enum);
    ins(ct, "owner", HOFFSET(cd_event, owner), H5T_NATIVE_INT);
    w->ev_mtype = ct;
    w->ev_ftype = H5Tcopy(ct);
    if (w->ev_ftype < 0) return -1;
    H5Tpack(w->ev_ftype);
    return 0;
}

/* Creates every series of group g listed in cd_h5_series_defs (h5_schema.h)
 * under loc, its indices into idx (by series id); a series whose rows would
 * be empty (no joints) is left out (-1). njoint, nbody: of system sys. */
static int add_group_series(cd_h5_writer *w, hid_t loc, cd_h5_group g, const cd_model *m, int njoint, int nbody,
                            int *idx)
{
    int k, nt;
    long t[2];
    for (k = 0; k < CD_SER_COUNT; k++) {
        const cd_h5_series_def *def = cd_h5_series_defs + k;
        if (def->group != g) continue;
        cd_h5_shape_rowlen(def->shape, m->nsys, m->nslot, njoint, nbody, m->nu, &nt, t);
        idx[k] = -1;
        if (nt > 0 && t[0] == 0) continue; /* q and qd of a system without joints */
        idx[k] = add_series(w, loc, def->name, def->type, nt, (hsize_t)t[0], (hsize_t)t[1], def->units,
                            def->description);
        if (idx[k] < 0) return -1;
    }
    return 0;
}

/* The (nslot) datasets of the peaks over steps (h5_schema.h): contiguous
 * and allocated now, NaN, so that cd_h5_close only rewrites their bytes in
 * place (rule 3 at the top of this file). */
static int create_step_peaks(hid_t gc, int nslot)
{
    hsize_t dim = (hsize_t)nslot;
    double nan = NAN;
    hid_t sp = H5Screate_simple(1, &dim, NULL), dcpl = H5Pcreate(H5P_DATASET_CREATE);
    int k, rc = 0;
    if (sp < 0 || dcpl < 0 || H5Pset_alloc_time(dcpl, H5D_ALLOC_TIME_EARLY) < 0 ||
        H5Pset_fill_time(dcpl, H5D_FILL_TIME_ALLOC) < 0 || H5Pset_fill_value(dcpl, H5T_NATIVE_DOUBLE, &nan) < 0)
        rc = -1;
    for (k = 0; rc == 0 && k < CD_H5_STEP_COUNT; k++) {
        hid_t ds = H5Dcreate2(gc, cd_h5_step_peak_names[k], H5T_IEEE_F64LE, sp, H5P_DEFAULT, dcpl, H5P_DEFAULT);
        if (ds < 0 || attr_str(ds, "units", cd_h5_step_peak_units[k]) < 0) rc = -1;
        if (ds >= 0) H5Dclose(ds);
    }
    if (dcpl >= 0) H5Pclose(dcpl);
    if (sp >= 0) H5Sclose(sp);
    return rc;
}

/* the peaks over steps given by the run, in place */
static int write_step_peaks(cd_h5_writer *w)
{
    int k, rc = 0;
    for (k = 0; k < CD_H5_STEP_COUNT; k++) {
        char path[64];
        hid_t ds;
        snprintf(path, sizeof path, "/contacts/%s", cd_h5_step_peak_names[k]);
        ds = H5Dopen2(w->file, path, H5P_DEFAULT);
        if (ds < 0 || H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT,
                               w->step_peak + (size_t)k * (size_t)w->nslot) < 0)
            rc = -1;
        if (ds >= 0) H5Dclose(ds);
    }
    return rc;
}

void cd_h5_set_step_peaks(cd_h5_writer *w, int nslot, const cd_h5_step_peaks *p)
{
    const double *src[CD_H5_STEP_COUNT];
    int k, i;
    if (!w || !p || nslot != w->nslot || nslot < 1) return;
    if (!w->step_peak) {
        w->step_peak = malloc(sizeof(double) * CD_H5_STEP_COUNT * (size_t)nslot);
        if (!w->step_peak) {
            w->oom = 1;
            return;
        }
    }
    src[CD_H5_STEP_FN_MAX] = p->fn_max;
    src[CD_H5_STEP_FN_BODY] = p->fn_body;
    src[CD_H5_STEP_FN_ONSET] = p->fn_onset;
    src[CD_H5_STEP_FT_MAX] = p->ft_max;
    src[CD_H5_STEP_T_BODY] = p->t_body;
    src[CD_H5_STEP_T_ONSET] = p->t_onset;
    for (k = 0; k < CD_H5_STEP_COUNT; k++)
        for (i = 0; i < nslot; i++) w->step_peak[(size_t)k * (size_t)nslot + (size_t)i] = src[k] ? src[k][i] : NAN;
}

static int create_layout(cd_h5_writer *w, const cd_model *m)
{
    hid_t g, gs, gc, gd;
    int s, k, ok = 1;
    for (k = 0; k < CD_SER_COUNT; k++) w->s[k] = -1;
    if (add_group_series(w, w->file, CD_G_ROOT, m, 0, 0, w->s) < 0) return -1;
    /* systems */
    g = H5Gcreate2(w->file, "systems", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (g < 0) return -1;
    attr_int(g, "count", m->nsys);
    for (s = 0; ok && s < m->nsys; s++) {
        char name[128];
        sys_series *ss = w->s_sys + s;
        int nj = m->sys_nbody[s] - 1, b0 = m->sys_body_adr[s], i;
        hsize_t nb = (hsize_t)m->sys_nbody[s];
        const char **jn;
        sys_group_name(m, s, name, sizeof name);
        gs = H5Gcreate2(g, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        if (gs < 0) { ok = 0; break; }
        attr_str(gs, "name", m->sys_name[s]);
        attr_int(gs, "index", s);
        attr_str(gs, "base_type", m->sys_base_type[s] == CD_BASE_FREE ? "free" : "fixed");
        attr_int(gs, "njoint", nj);
        attr_int(gs, "body_first", b0);
        attr_int(gs, "nbody", (int)nb);
        jn = malloc((size_t)(m->sys_nbody[s]) * sizeof *jn);
        if (!jn) {
            w->oom = 1;
            ok = 0;
        } else {
            for (i = 0; i < (int)nb; i++) jn[i] = m->body_name[b0 + i];
            attr_strv(gs, "body_names", (int)nb, jn, CD_H5_NAMELEN);
            if (nj > 0) attr_strv(gs, "joint_names", nj, jn + 1, CD_H5_NAMELEN);
            free(jn);
        }
        for (k = 0; k < CD_SER_COUNT; k++) ss->idx[k] = -1;
        if (add_group_series(w, gs, CD_G_SYSTEM, m, nj, (int)nb, ss->idx) < 0) ok = 0;
        H5Gclose(gs);
    }
    H5Gclose(g);
    if (!ok) return -1;
    /* contacts */
    gc = H5Gcreate2(w->file, "contacts", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (gc < 0) return -1;
    attr_int(gc, "nslot", m->nslot);
    {
        static const char *const mode_names[3] = {"open", "stick", "slip"};
        attr_strv(gc, "mode_names", 3, mode_names, 8);
    }
    if (write_slot_table(gc, m) < 0) ok = 0;
    if (ok && m->nslot > 0 && add_group_series(w, gc, CD_G_CONTACTS, m, 0, 0, w->s) < 0) ok = 0;
    if (ok && m->nslot > 0 && create_step_peaks(gc, m->nslot) < 0) ok = 0;
    H5Gclose(gc);
    if (!ok) return -1;
    /* events */
    {
        hsize_t dim = 0, maxd = H5S_UNLIMITED, chunk = 512;
        hid_t sp = H5Screate_simple(1, &dim, &maxd), dcpl = H5Pcreate(H5P_DATASET_CREATE);
        const char *kn[CD_EV_NKINDS];
        int k;
        if (sp < 0 || dcpl < 0) return -1;
        H5Pset_chunk(dcpl, 1, &chunk);
        H5Pset_deflate(dcpl, 4);
        w->ev_dset = H5Dcreate2(w->file, "events", w->ev_ftype, sp, H5P_DEFAULT, dcpl, H5P_DEFAULT);
        H5Pclose(dcpl);
        H5Sclose(sp);
        if (w->ev_dset < 0 || make_chunk_index(w) < 0) return -1;
        for (k = 0; k < CD_EV_NKINDS; k++) kn[k] = cd_event_kind_name((cd_event_kind)k);
        attr_strv(w->ev_dset, "kind_names", CD_EV_NKINDS, kn, 24);
        attr_i64(w->ev_dset, "lost", 0);
        attr_str(w->ev_dset, "units", "t [s], x [m], fn [N], ft [N]");
    }
    /* actuators: their inputs and torques (only when the model has some) */
    if (m->nu > 0) {
        hid_t ga = H5Gcreate2(w->file, "actuators", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        const char **an = malloc((size_t)m->nu * sizeof *an);
        if (!an) w->oom = 1;
        if (ga < 0 || !an) { free(an); if (ga >= 0) H5Gclose(ga); return -1; }
        attr_int(ga, "nactuator", m->nu);
        for (k = 0; k < m->nu; k++) an[k] = m->act_name[k] ? m->act_name[k] : "";
        attr_strv(ga, "names", m->nu, an, 128);
        free(an);
        ok = add_group_series(w, ga, CD_G_ACTUATORS, m, 0, 0, w->s) == 0;
        H5Gclose(ga);
        if (!ok) return -1;
    }
    /* diagnostics */
    gd = H5Gcreate2(w->file, "diagnostics", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (gd < 0) return -1;
    ok = add_group_series(w, gd, CD_G_DIAGNOSTICS, m, 0, 0, w->s) == 0;
    H5Gclose(gd);
    return ok ? 0 : -1;
}

static int alloc_buffers(cd_h5_writer *w)
{
    size_t rowbytes = 0;
    int i;
    for (i = 0; i < w->nser; i++) rowbytes += w->ser[i].rowlen * type_size(w->ser[i].type);
    /* at most 1024 rows and about 8 MiB pending; a full buffer forces a commit */
    w->cap_rows = (int)((8u << 20) / (rowbytes ? rowbytes : 1));
    if (w->cap_rows > 1024) w->cap_rows = 1024;
    if (w->cap_rows < 1) w->cap_rows = 1;
    /* ... a whole number of chunks of the series with the widest rows, so
     * that the commits of a full buffer (at multiples of cap_rows rows, see
     * cd_h5_append) end on their chunk boundaries: the chunk a commit leaves
     * partly filled is packed again at the next one (rule 2), which cost
     * 35 % more packing on the Fig. 5 grasp before */
    {
        size_t widest = 0;
        long long cr = 0;
        for (i = 0; i < w->nser; i++) {
            size_t rb = w->ser[i].rowlen * type_size(w->ser[i].type);
            if (rb > widest) { widest = rb; cr = w->ser[i].chunk_rows; }
        }
        if (cr > 0 && cr <= w->cap_rows) w->cap_rows -= (int)(w->cap_rows % cr);
    }
    for (i = 0; i < w->nser; i++) {
        w->ser[i].buf = malloc((size_t)w->cap_rows * w->ser[i].rowlen * type_size(w->ser[i].type));
        if (!w->ser[i].buf) { w->oom = 1; return -1; }
    }
    /* compressed: the writer packs the chunks of every series itself
     * (h5_pack.c) when the file's types are the memory's bytes (a
     * little-endian host); each series keeps a copy of its last chunk. All
     * of them: a chunk HDF5 wrote from its filters straight to the file (one
     * larger than its 1 MiB chunk cache) and whose write failed could not be
     * written again at the close, which then failed (detach_file). */
    if (w->compress && H5Tequal(H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE) > 0 &&
        H5Tequal(H5T_NATIVE_LLONG, H5T_STD_I64LE) > 0) {
        size_t most = 0;
        for (i = 0; i < w->nser; i++) {
            size_t b = (size_t)w->ser[i].chunk_rows * w->ser[i].rowlen * type_size(w->ser[i].type);
            w->ser[i].chunk = calloc(b, 1);
            if (!w->ser[i].chunk) { w->oom = 1; return -1; }
            if (b > most) most = b;
        }
        if (cd_h5_packer_init(&w->pack, most) < 0) { w->oom = 1; return -1; }
    }
    return 0;
}

static void utc_now(char *out, size_t len)
{
    time_t now = time(NULL);
    struct tm tmv;
    if (gmtime_r(&now, &tmv)) strftime(out, len, "%Y-%m-%dT%H:%M:%SZ", &tmv);
    else snprintf(out, len, "unknown");
}

/* The attributes written at close. They are created with the layout
 * (d == NULL: placeholders, NaN and -1, closed_utc "") at their final size,
 * so that closing rewrites them in place and adds no metadata (rule 3 at
 * the top of this file). Readers trust them once run_status is not
 * "running". */
/* The capture verdict (cd_h5_set_capture), placeholders when c == NULL. */
static int write_capture_attrs(hid_t f, const cd_h5_capture *c, int control)
{
    double nan3[3] = {NAN, NAN, NAN};
    int rc = 0;
    if (control) { /* a [control] run's figures of merit (docs/capture.md) */
        rc |= attr_f64v(f, "capture_dP", 3, c ? c->dP : nan3);
        rc |= attr_f64v(f, "capture_dL", 3, c ? c->dL : nan3);
        rc |= attr_f64(f, "capture_base_angle_max", c ? c->base_angle_max : NAN);
        rc |= attr_f64(f, "capture_base_rate_end", c ? c->base_rate_end : NAN);
        rc |= attr_f64(f, "capture_t_trigger", c ? c->t_trigger : NAN);
        rc |= attr_f64(f, "capture_t_rigidise", c ? c->t_rigidise : NAN);
        rc |= attr_f64(f, "capture_v_rel_end", c ? c->v_rel_end : NAN);
        rc |= attr_f64(f, "capture_w_rel_end", c ? c->w_rel_end : NAN);
        rc |= attr_f64(f, "capture_tau_arm_max", c ? c->tau_arm_max : NAN);
    }
    rc |= attr_str_fixed(f, "capture_verdict", c ? c->verdict : "", 16);
    rc |= attr_f64(f, "capture_t", c ? c->t : NAN);
    rc |= attr_f64(f, "capture_peak_fn", c ? c->peak_fn : NAN);
    rc |= attr_f64(f, "capture_peak_tau", c ? c->peak_tau : NAN);
    rc |= attr_f64v(f, "capture_offset", 3, c ? c->offset : nan3);
    rc |= attr_f64(f, "capture_epsilon", c ? c->epsilon : NAN);
    rc |= attr_int(f, "capture_n_stick", c ? c->n_stick : -1);
    rc |= attr_int(f, "capture_n_slip", c ? c->n_slip : -1);
    return rc;
}

void cd_h5_set_capture(cd_h5_writer *w, const cd_h5_capture *c)
{
    if (!w || !c) return;
    w->capture = *c;
    snprintf(w->capture_verdict, sizeof w->capture_verdict, "%s", c->verdict ? c->verdict : "");
    w->capture.verdict = w->capture_verdict;
    w->capture_set = 1;
}

static int write_closing_attrs(hid_t f, const cd_data *d)
{
    const cd_stats *s = d ? &d->stats : NULL;
    char when[CD_H5_UTC_LEN];
    int rc = 0;
    if (d) utc_now(when, sizeof when);
    else when[0] = 0;
    rc |= attr_f64(f, "t_final", d ? d->t : NAN);
    rc |= attr_i64(f, "stats_nrhs", s ? s->nrhs : -1);
    rc |= attr_i64(f, "stats_nsteps", s ? s->nsteps : -1);
    rc |= attr_i64(f, "stats_nrejected", s ? s->nrejected : -1);
    rc |= attr_i64(f, "stats_nevents", s ? s->nevents : -1);
    rc |= attr_i64(f, "stats_nlocate_steps", s ? s->nlocate_steps : -1);
    rc |= attr_i64(f, "stats_nwarn_geom", s ? s->nwarn_geom : -1);
    rc |= attr_i64(f, "stats_nwarn_dwell", s ? s->nwarn_dwell : -1);
    rc |= attr_i64(f, "stats_nrenorm", s ? s->nrenorm : -1);
    rc |= attr_i64(f, "stats_njac", s ? s->njac : -1);
    rc |= attr_i64(f, "stats_nswitch_stiff", s ? s->nswitch_stiff : -1);
    rc |= attr_i64(f, "stats_nswitch_explicit", s ? s->nswitch_explicit : -1);
    rc |= attr_f64(f, "stats_t_stiff", s ? s->t_stiff : NAN);
    rc |= attr_f64(f, "stats_h_last", s ? s->h_last : NAN);
    rc |= attr_f64(f, "stats_h_min", s ? (s->nsteps > 0 && isfinite(s->h_min_seen) ? s->h_min_seen : 0.0) : NAN);
    rc |= attr_f64(f, "stats_h_max", s ? s->h_max_seen : NAN);
    rc |= attr_str_fixed(f, "closed_utc", when, CD_H5_UTC_LEN);
    return rc;
}

static int write_root_attrs(cd_h5_writer *w, const cd_model *m, const cd_scenario *sc)
{
    hid_t f = w->file;
    char when[64];
    int rc = 0;
    utc_now(when, sizeof when);
    rc |= attr_str(f, "format", "capdyn-results");
    rc |= attr_int(f, "format_version", CD_H5_FORMAT_VERSION);
    rc |= attr_str(f, "capdyn_version", cd_version());
    rc |= attr_str(f, "created_utc", when);
    rc |= attr_str(f, "title", sc && sc->title ? sc->title : "");
    rc |= attr_str(f, "scenario_path", sc && sc->path ? sc->path : "");
    rc |= attr_text(f, "scenario_text", sc && sc->text ? sc->text : "");
    rc |= attr_text(f, "overrides", sc && sc->overrides ? sc->overrides : "");
    rc |= attr_f64(f, "duration", sc ? sc->duration : 0.0);
    rc |= attr_f64(f, "output_dt", sc ? sc->output_dt : 0.0);
    rc |= attr_int(f, "nsys", m->nsys);
    rc |= attr_int(f, "nbody", m->nbody);
    rc |= attr_int(f, "ncheckpoint", m->ncp);
    rc |= attr_int(f, "nshape", m->nshape);
    rc |= attr_int(f, "nslot", m->nslot);
    rc |= attr_int(f, "ny", m->ny);
    rc |= attr_str(f, "stepper", cd_stepper_name(m->opt.stepper));
    rc |= attr_f64(f, "rtol", m->opt.rtol);
    rc |= attr_f64(f, "atol", m->opt.atol);
    rc |= attr_f64(f, "h_max", m->opt.h_max);
    rc |= attr_f64(f, "event_tol", m->opt.event_tol);
    rc |= attr_f64(f, "dwell", m->opt.dwell);
    rc |= attr_f64v(f, "gravity", 3, m->gravity);
    rc |= attr_str_fixed(f, "run_status", "running", CD_H5_STATUS_LEN);
    rc |= attr_int(f, "run_status_code", -1);
    rc |= attr_str_fixed(f, "run_message", "the run has not finished (or was killed, or writing the file failed)",
                         CD_H5_MESSAGE_LEN);
    rc |= attr_i64(f, "committed_events", 0);
    rc |= attr_i64(f, "committed_samples", 0);
    rc |= write_closing_attrs(f, NULL);
    if (sc && sc->capture_hand >= 0 && sc->capture_object >= 0) {
        w->has_capture = 1;
        w->has_control = sc->control != NULL;
        rc |= write_capture_attrs(f, NULL, w->has_control);
    }
    return rc ? -1 : 0;
}

/* ---- output path safety -------------------------------------------------------- */
/* Where a new results file goes (docs/reliability.md, "Output path safety").
 * The file is written under a temporary name in the directory of the
 * target and renamed onto the target once its layout is on disk, so that
 *  - an existing file at the target is replaced only by a complete,
 *    readable file, never truncated (a run killed while creating its file
 *    leaves the old one and a temporary ".NAME.tmp-PID-N");
 *  - from then on the run writes under the requested name: a killed run
 *    leaves its committed samples there, and `capdyn info` reads a file a
 *    run is still writing;
 *  - a file another run is writing is never touched: the writer holds an
 *    exclusive flock on its file until it closes, and a new writer checks
 *    that lock (while holding a lock on the directory, until its rename)
 *    and refuses the target if it is held;
 *  - the target is never the scenario (same device and inode, so also
 *    through a symbolic or hard link) nor something other than a regular
 *    file; a symbolic link is followed (the file it names is replaced).
 * HDF5's own file locking is turned off for the writer (it would conflict
 * with this lock, which is taken on another descriptor). */
typedef struct {
    char *target;   /* the file to replace (the path, or where its symlink points) */
    char *tmp;      /* the temporary name, NULL once renamed */
    int dir_fd;     /* locked while the target is checked and replaced */
    int lock_fd;    /* the temporary file, flock'ed */
} out_claim;

static void claim_release(out_claim *c)
{
    if (c->tmp) {
        unlink(c->tmp);
        free(c->tmp);
        c->tmp = NULL;
    }
    if (c->lock_fd >= 0) close(c->lock_fd);
    if (c->dir_fd >= 0) close(c->dir_fd);
    c->lock_fd = c->dir_fd = -1;
    free(c->target);
    c->target = NULL;
}

static int claim_output(const char *path, const cd_scenario *sc, out_claim *c, cd_error *err)
{
    struct stat st, ss;
    char *dcopy = NULL, *bcopy = NULL, *dir, *base;
    int exists, i;
    c->target = c->tmp = NULL;
    c->dir_fd = c->lock_fd = -1;
    if (lstat(path, &st) == 0 && S_ISLNK(st.st_mode)) {
        c->target = realpath(path, NULL);
        if (!c->target) {
            seterr(err, CD_EIO, "cannot create results file '%s': it is a symbolic link to a missing file", path);
            return -1;
        }
    } else {
        c->target = malloc(strlen(path) + 1);
        if (c->target) strcpy(c->target, path);
    }
    if (!c->target) goto nomem;
    exists = stat(c->target, &st) == 0;
    if (exists && S_ISDIR(st.st_mode)) {
        seterr(err, CD_EIO, "cannot create results file '%s': it is a directory", path);
        goto fail;
    }
    if (exists && !S_ISREG(st.st_mode)) {
        seterr(err, CD_EIO, "cannot create results file '%s': it exists and is not a regular file", path);
        goto fail;
    }
    if (exists && sc && sc->path && stat(sc->path, &ss) == 0 && ss.st_dev == st.st_dev && ss.st_ino == st.st_ino) {
        seterr(err, CD_EIO, "cannot write results to '%s': it is the scenario file '%s' (choose another -o)", path,
               sc->path);
        goto fail;
    }
    dcopy = malloc(strlen(c->target) + 1);
    bcopy = malloc(strlen(c->target) + 1);
    if (!dcopy || !bcopy) goto nomem;
    strcpy(dcopy, c->target);
    strcpy(bcopy, c->target);
    dir = dirname(dcopy);
    base = basename(bcopy);
    c->dir_fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (c->dir_fd < 0) {
        seterr(err, CD_EIO, "cannot create results file '%s': %s", path, strerror(errno));
        goto fail;
    }
    (void)flock(c->dir_fd, LOCK_EX); /* best effort: not every file system has it */
    if (exists) {
        int fd = open(c->target, O_RDONLY | O_NOCTTY | O_CLOEXEC);
        if (fd >= 0) {
            int busy = flock(fd, LOCK_EX | LOCK_NB) != 0 && errno == EWOULDBLOCK;
            close(fd); /* drops the probe's lock */
            if (busy) {
                seterr(err, CD_EIO,
                       "cannot write results file '%s': another run is writing it (the file is locked); "
                       "choose another -o or wait for that run to end",
                       path);
                goto fail;
            }
        }
    }
    c->tmp = malloc(strlen(dir) + strlen(base) + 64);
    if (!c->tmp) goto nomem;
    for (i = 0; i < 100; i++) {
        sprintf(c->tmp, "%s/.%s.tmp-%ld-%d", dir, base, (long)getpid(), i);
        c->lock_fd = open(c->tmp, O_RDWR | O_CREAT | O_EXCL | O_NOCTTY | O_CLOEXEC, 0666);
        if (c->lock_fd >= 0 || errno != EEXIST) break;
    }
    if (c->lock_fd < 0) {
        seterr(err, CD_EIO, "cannot create results file '%s': %s", path, strerror(errno));
        free(c->tmp);
        c->tmp = NULL;
        goto fail;
    }
    (void)flock(c->lock_fd, LOCK_EX | LOCK_NB);
    free(dcopy);
    free(bcopy);
    return 0;
nomem:
    seterr(err, CD_ENOMEM, "out of memory");
fail:
    free(dcopy);
    free(bcopy);
    claim_release(c);
    return -1;
}

cd_h5_writer *cd_h5_create(const char *path, const cd_model *m, const cd_scenario *sc, cd_error *err)
{
    cd_h5_writer *w;
    cd_h5_quiet q;
    out_claim c;
    hid_t fcpl, fapl;
    if (!path || !m || !m->finalized) {
        seterr(err, CD_EINVAL, "cd_h5_create: path or model missing, or model not finalized");
        return NULL;
    }
    /* the title is a root attribute, which HDF5 keeps in the object header (64 KiB) */
    if (sc && sc->title && strlen(sc->title) > CD_TITLE_MAX) {
        seterr(err, CD_EINVAL, "cannot create results file '%s': the scenario's title is %zu bytes long, at most %d fit",
               path, strlen(sc->title), CD_TITLE_MAX);
        return NULL;
    }
    if (claim_output(path, sc, &c, err) < 0) return NULL;
    w = calloc(1, sizeof *w);
    if (!w) {
        claim_release(&c);
        seterr(err, CD_ENOMEM, "out of memory");
        return NULL;
    }
    w->file = w->ev_dset = w->ev_mtype = w->ev_ftype = w->kind_enum = w->mode_enum = w->owner_enum = -1;
    w->lock_fd = w->sink_fd = -1;
    w->space_check = 1;
    w->path = malloc(strlen(path) + 1);
    if (w->path) strcpy(w->path, path);
    w->compress = sc ? !sc->no_compress : 1;
    if (sc && sc->output_dt > 0 && sc->duration > 0 && sc->duration / sc->output_dt < 1e12)
        w->expect_rows = (long long)(sc->duration / sc->output_dt) + 2;
    w->nsys = m->nsys;
    w->nbody = m->nbody;
    w->nslot = m->nslot;
    w->ny = m->ny;
    clock_gettime(CLOCK_MONOTONIC, &w->wall0);
    w->s_sys = calloc((size_t)m->nsys, sizeof *w->s_sys);
    if (!w->s_sys || !w->path) {
        free(w->s_sys);
        free(w->path);
        free(w);
        claim_release(&c);
        seterr(err, CD_ENOMEM, "out of memory");
        return NULL;
    }
    writer_quiet_begin(&q, w);
    /* rule 2 (top of the file): never reuse freed space */
    fcpl = H5Pcreate(H5P_FILE_CREATE);
    fapl = H5Pcreate(H5P_FILE_ACCESS);
    /* a property that could not be set (out of memory) fails the create:
     * HDF5 1.10 leaves such a list damaged */
    if (fcpl >= 0 && H5Pset_file_space_strategy(fcpl, H5F_FSPACE_STRATEGY_NONE, 0, (hsize_t)1) < 0) {
        H5Pclose(fcpl);
        fcpl = -1;
    }
    if (fapl >= 0 && H5Pset_file_locking(fapl, 0, 1) < 0) {
        H5Pclose(fapl);
        fapl = -1;
    }
    w->file = fcpl >= 0 && fapl >= 0 ? H5Fcreate(c.tmp, H5F_ACC_TRUNC, fcpl, fapl) : -1;
    if (fcpl >= 0) H5Pclose(fcpl);
    if (fapl >= 0) H5Pclose(fapl);
    if (w->file < 0) {
        int oom = w->oom;
        cd_h5_quiet_end(&q);
        writer_free(w);
        claim_release(&c);
        if (oom)
            seterr(err, CD_ENOMEM, "cannot create results file '%s': out of memory", path);
        else
            seterr(err, CD_EIO, "cannot create results file '%s': HDF5 refused to create it", path);
        return NULL;
    }
    /* an allocation that failed anywhere in the layout (some attribute
     * writes are not checked one by one) fails it too: no file lacks a part
     * of its layout */
    if (create_event_types(w) < 0 || write_root_attrs(w, m, sc) < 0 || write_model_tables(w->file, m) < 0 ||
        create_layout(w, m) < 0 || alloc_buffers(w) < 0 || w->oom ||
        H5Fflush(w->file, H5F_SCOPE_GLOBAL) < 0) {
        int oom = w->oom;
        w->failed = 1; /* closed without writing more, then removed */
        writer_free(w);
        cd_h5_quiet_end(&q);
        claim_release(&c);
        if (oom)
            seterr(err, CD_ENOMEM, "cannot write the layout of results file '%s': out of memory", path);
        else
            seterr(err, CD_EIO,
                   "cannot write the layout of results file '%s' (disk full, file size limit or HDF5 error)", path);
        return NULL;
    }
    cd_h5_quiet_end(&q);
    /* the file keeps its temporary name until its first commit (name_file);
     * the directory lock is dropped meanwhile, the file's lock is held
     * until writer_free */
    w->claim_tmp = c.tmp;
    w->claim_target = c.target;
    w->lock_fd = c.lock_fd;
    c.tmp = c.target = NULL;
    c.lock_fd = -1;
    claim_release(&c);
    /* opened now: after a failed write the close must not go to the file,
     * and a process out of descriptors by then could open nothing
     * (detach_file); when even this open fails, detach_file tries again */
    w->sink_fd = open("/dev/null", O_RDWR | O_CLOEXEC);
    return w;
}

/* Takes the events logged since the last call from d's ring buffer. */
static int take_events(cd_h5_writer *w, const cd_data *d)
{
    long held = d->ev_count < d->ev_cap ? d->ev_count : d->ev_cap;
    long first = d->ev_count - held, g;
    if (d->ev_count < w->ev_next) w->ev_next = 0; /* d was reset: start over */
    if (w->ev_next < first) {
        w->ev_lost += first - w->ev_next; /* overwritten in the ring before we saw them */
        w->ev_next = first;
    }
    for (g = w->ev_next; g < d->ev_count; g++) {
        const cd_event *e = cd_data_event(d, g - first);
        if (!e) continue;
        if (w->ev_nbuf == w->ev_capbuf) {
            long nc = w->ev_capbuf ? 2 * w->ev_capbuf : 256;
            cd_event *nb = realloc(w->evbuf, (size_t)nc * sizeof *nb);
            if (!nb) { w->oom = 1; return -1; }
            w->evbuf = nb;
            w->ev_capbuf = nc;
        }
        w->evbuf[w->ev_nbuf++] = *e;
    }
    w->ev_next = d->ev_count;
    return 0;
}

/* Every number of the row just buffered must be finite: a sample with an inf
 * or NaN (an energy that overflowed, a state that blew up) is kept in the
 * file, and the first such value is named as the error. */
static cd_status check_finite(cd_h5_writer *w, double t, cd_error *err)
{
    int i;
    size_t k;
    for (i = 0; i < w->nser; i++) {
        const h5_series *s = w->ser + i;
        const double *v;
        if (s->type != T_F64) continue;
        v = (const double *)(const void *)(s->buf + (size_t)(w->nbuf - 1) * s->rowlen * sizeof(double));
        for (k = 0; k < s->rowlen; k++)
            if (!isfinite(v[k])) {
                char name[256] = "?";
                cd_h5_quiet q;
                cd_h5_quiet_begin(&q);
                (void)H5Iget_name(s->dset, name, sizeof name);
                cd_h5_quiet_end(&q);
                seterr(err, CD_ENUMERIC, "non-finite output: %s element %lu of the sample at t = %.9g s is %s (sample %lld)",
                       name, (unsigned long)k, t, isnan(v[k]) ? "NaN" : v[k] > 0 ? "+inf" : "-inf",
                       w->nwritten + w->nbuf - 1);
                return CD_ENUMERIC;
            }
    }
    return CD_OK;
}

cd_status cd_h5_append(cd_h5_writer *w, const cd_model *m, const cd_data *d, cd_error *err)
{
    int s, k, b, i;
    struct timespec now;
    cd_status fin;
    if (!w || !m || !d) {
        seterr(err, CD_EINVAL, "cd_h5_append: NULL argument");
        return CD_EINVAL;
    }
    if (m->nsys != w->nsys || m->nbody != w->nbody || m->nslot != w->nslot || m->ny != w->ny) {
        seterr(err, CD_EINVAL, "cd_h5_append: the model is not the one the file was created for");
        return CD_EINVAL;
    }
    if (w->failed || w->stopped) return refused(w, err);
    row_f64(w, w->s[CD_SER_TIME])[0] = d->t;
    for (s = 0; s < m->nsys; s++) {
        const sys_series *ss = w->s_sys + s;
        cd_sys_state x = cd_state_of(m, d, s);
        int b0 = m->sys_body_adr[s], nb = m->sys_nbody[s];
        double *p = row_f64(w, ss->idx[CD_SER_BASE_POS]), *qt = row_f64(w, ss->idx[CD_SER_BASE_QUAT]), *v = row_f64(w, ss->idx[CD_SER_BASE_VEL]),
               *av = row_f64(w, ss->idx[CD_SER_BASE_ANGVEL]);
        if (x.pos) {
            memcpy(p, x.pos, 3 * sizeof(double));
            memcpy(qt, x.quat, 4 * sizeof(double));
            memcpy(v, x.vel, 3 * sizeof(double));
            memcpy(av, x.angvel, 3 * sizeof(double));
        } else {
            /* a fixed base keeps its initial pose and does not move */
            memcpy(p, m->sys_pos0 + 3 * s, 3 * sizeof(double));
            memcpy(qt, m->sys_quat0 + 4 * s, 4 * sizeof(double));
            memset(v, 0, 3 * sizeof(double));
            memset(av, 0, 3 * sizeof(double));
        }
        if (ss->idx[CD_SER_Q] >= 0) {
            int va = m->sys_v_adr[s] + (x.pos ? 6 : 0); /* the joints' generalized forces */
            size_t nj = (size_t)x.njoint * sizeof(double);
            memcpy(row_f64(w, ss->idx[CD_SER_Q]), x.q, nj);
            memcpy(row_f64(w, ss->idx[CD_SER_QD]), x.qd, nj);
            memcpy(row_f64(w, ss->idx[CD_SER_TAU]), d->tau + va, nj);
            memcpy(row_f64(w, ss->idx[CD_SER_TAU_ACTUATOR]), d->qfrc_actuator + va, nj);
            memcpy(row_f64(w, ss->idx[CD_SER_TAU_PASSIVE]), d->qfrc_passive + va, nj);
            memcpy(row_f64(w, ss->idx[CD_SER_TAU_APPLIED]), d->qfrc_applied + va, nj);
        }
        {
            double *bx = row_f64(w, ss->idx[CD_SER_BODY_X]), *bc = row_f64(w, ss->idx[CD_SER_BODY_C]), *bq = row_f64(w, ss->idx[CD_SER_BODY_QUAT]);
            for (i = 0; i < nb; i++) {
                b = b0 + i;
                memcpy(bx + 3 * i, d->body_x + 3 * b, 3 * sizeof(double));
                memcpy(bc + 3 * i, d->body_c + 3 * b, 3 * sizeof(double));
                cd_m3_to_quat(bq + 4 * i, d->body_R + 9 * b);
            }
        }
    }
    if (m->nu > 0) {
        size_t nb = (size_t)m->nu * sizeof(double);
        memcpy(row_f64(w, w->s[CD_SER_CTRL]), d->ctrl, nb);
        memcpy(row_f64(w, w->s[CD_SER_ACT_FORCE]), d->act_force, nb);
        memcpy(row_f64(w, w->s[CD_SER_ACT_VELOCITY]), d->act_velocity, nb);
    }
    if (m->nslot > 0) {
        size_t n1 = (size_t)m->nslot * sizeof(double), n3 = 3 * n1;
        signed char *mo = row_i8(w, w->s[CD_SER_MODE]);
        memcpy(row_f64(w, w->s[CD_SER_FN]), d->slot_fn, n1);
        memcpy(row_f64(w, w->s[CD_SER_FT]), d->slot_ft, n3);
        memcpy(row_f64(w, w->s[CD_SER_PENETRATION]), d->slot_x, n1);
        memcpy(row_f64(w, w->s[CD_SER_PENETRATION_RATE]), d->slot_xdot, n1);
        memcpy(row_f64(w, w->s[CD_SER_POINT]), d->slot_point, n3);
        memcpy(row_f64(w, w->s[CD_SER_NORMAL]), d->slot_normal, n3);
        memcpy(row_f64(w, w->s[CD_SER_SLIP_VELOCITY]), d->slot_vt, n3);
        for (k = 0; k < m->nslot; k++) /* slots the broad phase skipped: their full outputs */
            if (d->slot_far[k])
                cd_contact_slot_outputs(m, d, k, row_f64(w, w->s[CD_SER_PENETRATION]) + k,
                                        row_f64(w, w->s[CD_SER_PENETRATION_RATE]) + k, NULL,
                                        row_f64(w, w->s[CD_SER_POINT]) + 3 * k, row_f64(w, w->s[CD_SER_NORMAL]) + 3 * k,
                                        row_f64(w, w->s[CD_SER_SLIP_VELOCITY]) + 3 * k);
        for (k = 0; k < m->nslot; k++) mo[k] = (signed char)d->slot_mode[k];
    }
    {
        double *ke = row_f64(w, w->s[CD_SER_KE]), *pe = row_f64(w, w->s[CD_SER_PE]), *P = row_f64(w, w->s[CD_SER_MOMENTUM]),
               *Lc = row_f64(w, w->s[CD_SER_L_COM]), *Lo = row_f64(w, w->s[CD_SER_L_ORIGIN]), *com = row_f64(w, w->s[CD_SER_COM]);
        for (s = 0; s < m->nsys; s++) {
            cd_momentum(m, d, s, ke + s, P + 3 * s, Lc + 3 * s, Lo + 3 * s, com + 3 * s);
            pe[s] = cd_potential_energy(m, d, s);
        }
    }
    row_f64(w, w->s[CD_SER_STEP_SIZE])[0] = d->stats.h_last;
    row_i64(w, w->s[CD_SER_NRHS])[0] = d->stats.nrhs;
    row_i64(w, w->s[CD_SER_NSTEPS])[0] = d->stats.nsteps;
    row_i64(w, w->s[CD_SER_NREJECTED])[0] = d->stats.nrejected;
    row_i64(w, w->s[CD_SER_NEVENTS])[0] = d->stats.nevents;
    clock_gettime(CLOCK_MONOTONIC, &now);
    row_f64(w, w->s[CD_SER_WALL_TIME])[0] = (double)(now.tv_sec - w->wall0.tv_sec) + 1e-9 * (double)(now.tv_nsec - w->wall0.tv_nsec);
    if (take_events(w, d) < 0) {
        seterr(err, CD_ENOMEM, "results file '%s': out of memory buffering the events of the sample at t = %.9g s",
               w->path, d->t);
        return CD_ENOMEM;
    }
    w->nbuf++;
    fin = check_finite(w, d->t, err); /* the row is kept either way */
    /* a row count that is a multiple of the buffer's rows commits (aligned
     * with the widest series' chunks, see alloc_buffers; it comes within
     * cap_rows rows of any commit, so the buffer never overflows); so does
     * the first sample, after which the file takes its name */
    if ((w->nwritten + w->nbuf) % w->cap_rows == 0 || w->claim_tmp) {
        cd_h5_quiet q;
        cd_status st;
        cd_error cerr;
        writer_quiet_begin(&q, w);
        st = commit(w, fin == CD_OK ? err : &cerr);
        cd_h5_quiet_end(&q);
        if (st != CD_OK) return st;
    }
    return fin;
}

cd_status cd_h5_flush(cd_h5_writer *w, cd_error *err)
{
    cd_h5_quiet q;
    cd_status st;
    if (!w) {
        seterr(err, CD_EINVAL, "cd_h5_flush: NULL writer");
        return CD_EINVAL;
    }
    writer_quiet_begin(&q, w);
    st = commit(w, err);
    cd_h5_quiet_end(&q);
    return st;
}

/* Closing: commit the data first, then the statistics, then the status
 * (in place, fixed size) last, each step flushed before the next, so that a
 * file whose final commit failed never says "ok". If a write failed, the
 * file is left alone (its last commit is what is on disk); if the space
 * check stopped the writer, the file is consistent and gets the closing
 * attributes, with an I/O error status, if there is still room for them. */
cd_status cd_h5_close(cd_h5_writer *w, const cd_model *m, const cd_data *d, cd_status run_status,
                      const char *message, cd_error *err)
{
    cd_h5_quiet q;
    cd_status st = CD_OK;
    cd_error tmp;
    hid_t f;
    int rc = 0;
    if (!w) return CD_OK;
    if (!err) err = &tmp;
    writer_quiet_begin(&q, w);
    f = w->file;
    if (!w->failed && !w->stopped) {
        cd_status cst;
        /* the last events (logged after the last sample) still belong in the table */
        if (d && m && take_events(w, d) < 0) {
            seterr(err, CD_ENOMEM, "results file '%s': out of memory buffering the last events", w->path);
            st = CD_ENOMEM;
        }
        cst = commit(w, st == CD_OK ? err : &tmp);
        if (cst != CD_OK && st == CD_OK) st = cst;
    } else {
        st = refused(w, err);
    }
    /* a writer stopped by the space check writes these (a few kB, most in
     * place) if there is still room for them */
    if (!w->failed && (!w->stopped || check_space(w, 65536.0, tmp.msg, sizeof tmp.msg) == 0)) {
        if (d) rc |= write_closing_attrs(f, d);
        if (w->has_capture && w->capture_set) rc |= write_capture_attrs(f, &w->capture, w->has_control);
        if (w->step_peak) rc |= write_step_peaks(w);
        if (!d) {
            char when[CD_H5_UTC_LEN];
            utc_now(when, sizeof when);
            rc |= attr_str_fixed(f, "closed_utc", when, CD_H5_UTC_LEN);
        }
        if (rc || H5Fflush(f, H5F_SCOPE_GLOBAL) < 0) {
            if (st == CD_OK) st = write_failed(w, err, "writing the final statistics");
            else w->failed = 1;
        } else {
            /* the status last. A run whose last samples could not be
             * committed is never reported as a success: the writer's error
             * is the status, with how the run itself ended after it. */
            cd_status fst = run_status;
            const char *fmsg = message ? message : "";
            char both[CD_H5_MESSAGE_LEN];
            /* a run that ends "ok" with a non-finite summary did not end well */
            if (st == CD_OK && run_status == CD_OK && d &&
                (!isfinite(d->t) || !isfinite(d->stats.h_last) || !isfinite(d->stats.h_max_seen))) {
                fst = CD_ENUMERIC;
                snprintf(both, sizeof both, "non-finite summary at the end of the run: t_final = %g, stats_h_last = %g, "
                         "stats_h_max = %g", d->t, d->stats.h_last, d->stats.h_max_seen);
                fmsg = both;
                seterr(err, CD_ENUMERIC, "%s", both);
                st = CD_ENUMERIC;
            }
            if (st != CD_OK) {
                fst = st;
                if (run_status == CD_OK || strcmp(fmsg, err->msg) == 0)
                    snprintf(both, sizeof both, "%s", err->msg);
                else
                    snprintf(both, sizeof both, "%s (the run: %s: %s)", err->msg, cd_status_string(run_status), fmsg);
                fmsg = both;
            }
            if (attr_str_fixed(f, "run_status", cd_status_string(fst), CD_H5_STATUS_LEN) < 0 ||
                attr_int(f, "run_status_code", (int)fst) < 0 ||
                attr_str_fixed(f, "run_message", fmsg, CD_H5_MESSAGE_LEN) < 0 ||
                H5Fflush(f, H5F_SCOPE_GLOBAL) < 0) {
                if (st == CD_OK) st = write_failed(w, err, "writing the run status");
                else w->failed = 1;
            }
        }
    }
    /* a run without samples: the file takes its name once all is flushed */
    if (!w->failed && w->claim_tmp) {
        cd_status nst = name_file(w, st == CD_OK ? err : &tmp);
        if (st == CD_OK) st = nst;
    }
    writer_free(w);
    cd_h5_quiet_end(&q);
    return st;
}
