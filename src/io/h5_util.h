/* Internal: helpers shared by the HDF5 writer and reader. */
#ifndef CD_H5_UTIL_H
#define CD_H5_UTIL_H
#include <hdf5.h>

/* Silences HDF5's automatic error printing for the duration of one call
 * (the library never prints) and restores the caller's handler after. */
typedef struct { H5E_auto2_t func; void *data; } cd_h5_quiet;

static inline void cd_h5_quiet_begin(cd_h5_quiet *q)
{
    (void)H5Eget_auto2(H5E_DEFAULT, &q->func, &q->data);
    (void)H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}
static inline void cd_h5_quiet_end(const cd_h5_quiet *q) { (void)H5Eset_auto2(H5E_DEFAULT, q->func, q->data); }

#endif
