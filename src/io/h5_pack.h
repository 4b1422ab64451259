/* The results writer's own chunk filter: HDF5's shuffle + deflate, done by
 * capdyn so that each byte plane gets the deflate effort it repays
 * (h5_pack.c): planes that deflate would hardly shrink are stored. The
 * output is an ordinary zlib stream of the shuffled chunk:
 * any HDF5 reader (h5py, h5dump, capdyn's own) inflates it with the
 * standard deflate filter, nothing is lost. */
#ifndef CAPDYN_H5_PACK_H
#define CAPDYN_H5_PACK_H

#include <stddef.h>
#ifndef ZLIB_CONST
#define ZLIB_CONST
#endif
#include <zlib.h>

typedef struct {
    z_stream zs;
    int zs_ok;              /* deflateInit done (deflateEnd at free) */
    unsigned char *shuf;    /* the shuffled chunk (cap bytes) */
    unsigned char *out;     /* the compressed chunk (cap_out bytes) */
    size_t cap, cap_out;
    /* bytes of the byte planes packed so far: deflated, and stored */
    double n_deflated, n_stored;
} cd_h5_packer;

/* Allocates the buffers for chunks of up to max_bytes raw bytes and the
 * deflate state (all the memory a pack needs: cd_h5_pack allocates
 * nothing). Returns 0, or -1 when out of memory (p is then freed). */
int cd_h5_packer_init(cd_h5_packer *p, size_t max_bytes);
void cd_h5_packer_free(cd_h5_packer *p);

/* Shuffles n raw bytes of elements of elem bytes (HDF5's shuffle filter:
 * byte plane k holds byte k of every element; none for elem 1) and deflates
 * them into p->out as one zlib stream. The first nfill bytes hold data, the
 * rest are zeros (the unfilled rows of a partly filled chunk): each plane's
 * choice is made on its data, and its zero tail is deflated. Returns the
 * stream's size, or 0 when it does not fit (the caller then writes the
 * chunk through HDF5's own filters). */
size_t cd_h5_pack(cd_h5_packer *p, const unsigned char *raw, size_t n, size_t nfill, size_t elem);

/* The Shannon entropy in bits per byte of the byte histogram of b[0..n). */
double cd_h5_byte_entropy(const unsigned char *b, size_t n);

#endif
