/* Internal: helpers shared by the HDF5 writer and reader. */
#ifndef CD_H5_UTIL_H
#define CD_H5_UTIL_H
#include <hdf5.h>
#include "capdyn/io.h"

/* Silences HDF5's automatic error printing for the duration of one call
 * (the library never prints) and restores the caller's handler after. */
typedef struct { H5E_auto2_t func; void *data; } cd_h5_quiet;

static inline void cd_h5_quiet_begin(cd_h5_quiet *q)
{
    (void)H5Eget_auto2(H5E_DEFAULT, &q->func, &q->data);
    (void)H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}
static inline void cd_h5_quiet_end(const cd_h5_quiet *q) { (void)H5Eset_auto2(H5E_DEFAULT, q->func, q->data); }

/* Internal knobs of the results writer (src/io/h5.c), for tests.
 * Before each commit the writer checks that the file system has room for
 * it (statvfs) and that the file stays under the file size limit
 * (RLIMIT_FSIZE); reserve adds bytes to what the check asks for (a huge
 * value makes the next commit stop as on a full disk); on = 0 turns the
 * check off, so that a test can make a real write fail. */
void cd_h5_writer_set_space_check(cd_h5_writer *w, int on, double reserve);

#endif
