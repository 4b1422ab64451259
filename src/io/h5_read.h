/* Private reader of capdyn HDF5 results (docs/results-format.md), used by
 * `capdyn info` and `capdyn export`. Not part of the public API.
 *
 * Readers trust only the committed rows: n = min(/committed_samples, rows on
 * disk), and the same for events (/committed_events). Everything returned is
 * owned by the reader (freed by cd_h5r_close) unless said otherwise.
 *
 * Files are untrusted: every size and index read from a file is checked
 * before use (a damaged file gives NULL and a message), but libhdf5 itself
 * may still crash on a damaged file; read untrusted files in a child process
 * as `capdyn info`/`export` do (docs/reliability.md, "Untrusted results
 * files"). */
#ifndef CD_H5_READ_H
#define CD_H5_READ_H

#include "capdyn/model.h"
#include "capdyn/sim.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    char group[128];      /* /systems/<group> */
    char name[128];       /* the system's own name */
    int base_free;        /* 1 free-floating, 0 fixed */
    int njoint, body_first, nbody;
} cd_h5r_sys;

typedef struct {
    int system, parent, joint_type;
    char name[64], full_name[128];
    double mass, com[3], inertia[9];
} cd_h5r_body;

typedef struct { int body; double pos[3], radius; } cd_h5r_cp;

typedef struct {
    int body, type;
    double pos[3], rot[9], size[3];
    int vert_adr, vert_num;
} cd_h5r_shape;

typedef struct {
    int checkpoint, shape, body_a, body_b;
    char body_a_name[128], body_b_name[128], shape_type[16];
} cd_h5r_slot;

typedef struct {
    long long id;         /* the file handle (hid_t) */
    long n;               /* committed samples */
    long nrows;           /* rows on disk (>= n after a kill inside a commit) */
    long nev;             /* committed events */
    long long ev_lost;
    int nsys, nbody, ncp, nshape, nvert, nslot;
    cd_h5r_sys *sys;
    cd_h5r_body *body;
    cd_h5r_cp *cp;
    cd_h5r_shape *shape;
    double *vert;         /* (nvert x 3) */
    cd_h5r_slot *slot;
} cd_h5r;

/* Opens a results file read-only (without file locking, so a file that a
 * run is still writing can be inspected; for SWMR reading when the format
 * allows it, so that chunks a killed commit wrote past the superblock's
 * end-of-allocation are read) and reads and checks the static tables.
 * Returns NULL with err filled (CD_EIO) if it is not a readable capdyn file. */
cd_h5r *cd_h5r_open(const char *path, cd_error *err);
void cd_h5r_close(cd_h5r *r);

/* 1 if the object (dataset or group) exists. */
int cd_h5r_exists(const cd_h5r *r, const char *path);
/* The first r->n rows of a time series as doubles (integers converted),
 * malloc'ed (caller frees); *rowlen = elements per row. NULL (err filled)
 * if missing, or if its shape or type is not what the schema
 * (src/io/h5_schema.h) and the model tables say. */
double *cd_h5r_series(const cd_h5r *r, const char *path, size_t *rowlen, cd_error *err);
/* The same, its first min(nrows, r->n) rows only (nrows < 0: all committed):
 * for a reader that needs a row or two, without reading (and inflating)
 * the whole series. */
double *cd_h5r_series_head(const cd_h5r *r, const char *path, long nrows, size_t *rowlen, cd_error *err);
/* A one-dimensional dataset of n elements (e.g. the (nslot) peaks over
 * steps, h5_schema.h) as doubles into v: 0; -1 if it does not exist; -2 if
 * its shape is not (n) or it does not read. */
int cd_h5r_vec(const cd_h5r *r, const char *path, double *v, long n);
/* Attributes of an object ("/" for the file). The string is malloc'ed
 * (caller frees); NULL if missing. The numeric readers return 0 on success,
 * -1 if missing. cd_h5r_text follows the "@dataset /name" indirection used
 * for texts too large for an attribute. */
char *cd_h5r_attr_str(const cd_h5r *r, const char *obj, const char *name);
char *cd_h5r_text(const cd_h5r *r, const char *name);
int cd_h5r_attr_f64(const cd_h5r *r, const char *obj, const char *name, double *v);
int cd_h5r_attr_f64v(const cd_h5r *r, const char *obj, const char *name, double *v, int n);
int cd_h5r_attr_i64(const cd_h5r *r, const char *obj, const char *name, long long *v);
/* The committed events, malloc'ed (caller frees); *n their number. */
cd_event *cd_h5r_events(const cd_h5r *r, long *n, cd_error *err);
/* System index by its name or group name; -1 if none. */
int cd_h5r_system(const cd_h5r *r, const char *name);
/* Reads every dataset of the file in full (every row on disk, not only the
 * committed ones), as h5dump would. 0 if all read; -1 with err (CD_EIO,
 * naming path and the first dataset that does not read) otherwise. */
int cd_h5r_verify(const cd_h5r *r, const char *path, cd_error *err);

#ifdef __cplusplus
}
#endif
#endif
