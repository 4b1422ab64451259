/* The results writer's chunk filter (h5_pack.h).
 *
 * Why: with HDF5's own shuffle + deflate (level 1), compressing the results
 * took three quarters of a `capdyn run` of the Fig. 5 grasp (12 s at 1 kHz,
 * 44 contact slots, 80 MB of samples: 1.30 s of wall time against 0.33 s
 * uncompressed; docs/performance.md section 18). Most of it went to byte
 * planes that deflate hardly shrinks: the low bytes of the mantissas of the
 * contact points, normals and slip velocities. After the shuffle each byte
 * plane of a chunk holds one byte of every element, and the entropy H of its
 * byte histogram bounds what coding the bytes one by one can gain (to H / 8
 * of the plane):
 *   - H below CD_PACK_H_STORE bits per byte (exponents, high mantissa bytes,
 *     zeros, small integers): deflate with matches (level 1), as HDF5 did;
 *   - above it: stored (deflate level 0, a copy); coding would gain at most
 *     1 - CD_PACK_H_STORE / 8 of such a plane (measured: 22 % on the Fig. 5
 *     run, at about 10 ns a byte).
 * All planes go into one zlib stream (deflateParams between them), so the
 * chunk is an ordinary shuffle + deflate chunk that every HDF5 reader
 * inflates: the file's layout and filters are those of before, only the
 * effort deflate spends on each plane is capdyn's choice. */
#include "h5_pack.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define CD_PACK_H_STORE 6.0

double cd_h5_byte_entropy(const unsigned char *b, size_t n)
{
    size_t hist[256] = {0}, i;
    double h = 0;
    if (n == 0) return 0.0;
    for (i = 0; i < n; i++) hist[b[i]]++;
    for (i = 0; i < 256; i++)
        if (hist[i]) {
            double p = (double)hist[i] / (double)n;
            h -= p * log2(p);
        }
    return h;
}

void cd_h5_packer_free(cd_h5_packer *p)
{
    if (!p) return;
    if (p->zs_ok) deflateEnd(&p->zs);
    free(p->shuf);
    free(p->out);
    memset(p, 0, sizeof *p);
}

int cd_h5_packer_init(cd_h5_packer *p, size_t max_bytes)
{
    memset(p, 0, sizeof *p);
    if (max_bytes == 0) max_bytes = 1;
    p->cap = max_bytes;
    /* a stored block costs 5 bytes per 64 KiB, a switch of parameters a
     * block end; compressBound covers the rest */
    p->cap_out = (size_t)compressBound((uLong)max_bytes) + 64 * 16 + 1024;
    p->shuf = malloc(p->cap);
    p->out = malloc(p->cap_out);
    if (!p->shuf || !p->out) { cd_h5_packer_free(p); return -1; }
    if (deflateInit2(&p->zs, 1, Z_DEFLATED, 15, 8, Z_DEFAULT_STRATEGY) != Z_OK) {
        cd_h5_packer_free(p);
        return -1;
    }
    p->zs_ok = 1;
    return 0;
}

/* deflates n bytes at b at the given level (0: stored) into the stream */
static int put(cd_h5_packer *p, const unsigned char *b, size_t n, int level)
{
    z_stream *z = &p->zs;
    if (n == 0) return 0;
    if (deflateParams(z, level, Z_DEFAULT_STRATEGY) != Z_OK) return -1;
    z->next_in = b;
    z->avail_in = (uInt)n;
    if (deflate(z, Z_NO_FLUSH) != Z_OK || z->avail_in != 0) return -1;
    if (level) p->n_deflated += (double)n;
    else p->n_stored += (double)n;
    return 0;
}

size_t cd_h5_pack(cd_h5_packer *p, const unsigned char *raw, size_t n, size_t nfill, size_t elem)
{
    size_t ne, nf, k, j;
    const unsigned char *src = raw;
    z_stream *z = &p->zs;
    if (!p->zs_ok || n > p->cap || elem == 0 || n % elem || nfill > n) return 0;
    ne = n / elem;
    nf = (nfill + elem - 1) / elem; /* elements holding data */
    if (elem == 8) { /* HDF5's shuffle: byte k of element j goes to k * ne + j */
        unsigned char *d0 = p->shuf, *d1 = d0 + ne, *d2 = d1 + ne, *d3 = d2 + ne, *d4 = d3 + ne, *d5 = d4 + ne,
                      *d6 = d5 + ne, *d7 = d6 + ne;
        for (j = 0; j < ne; j++) { /* one pass over the elements, eight sequential streams */
            const unsigned char *e = raw + 8 * j;
            d0[j] = e[0], d1[j] = e[1], d2[j] = e[2], d3[j] = e[3];
            d4[j] = e[4], d5[j] = e[5], d6[j] = e[6], d7[j] = e[7];
        }
        src = p->shuf;
    } else if (elem > 1) {
        for (k = 0; k < elem; k++) {
            unsigned char *d = p->shuf + k * ne;
            const unsigned char *s = raw + k;
            for (j = 0; j < ne; j++) d[j] = s[j * elem];
        }
        src = p->shuf;
    }
    if (deflateReset(z) != Z_OK) return 0;
    z->next_out = p->out;
    z->avail_out = (uInt)p->cap_out;
    for (k = 0; k < elem; k++) { /* the planes, ne bytes each (one for elem 1) */
        const unsigned char *b = src + k * ne;
        /* the entropy of the data's first quarter (all of a short plane):
         * every column of the rows it holds, at a quarter of the cost */
        const size_t probe = nf / 4 > 4096 ? nf / 4 : nf;
        const int level = cd_h5_byte_entropy(b, probe) < CD_PACK_H_STORE ? 1 : 0;
        if (put(p, b, nf, level) < 0 || put(p, b + nf, ne - nf, 1) < 0) return 0;
    }
    if (deflate(z, Z_FINISH) != Z_STREAM_END) return 0;
    return (size_t)(p->cap_out - z->avail_out);
}
