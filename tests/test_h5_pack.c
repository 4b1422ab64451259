/* The results writer's chunk filter (src/io/h5_pack.c): its output must be
 * the zlib stream of HDF5's shuffle of the chunk, whatever each byte plane
 * got (deflate or a stored copy), and the choice must follow the planes'
 * entropy. (That files written with it read back the same values through
 * HDF5's own filters: cli::uncompressed_results_hold_the_same_samples.) */
#include <criterion/criterion.h>
#include "../src/io/h5_pack.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static uint64_t lcg(uint64_t *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return *s >> 11;
}

/* inflates p's output (len bytes) and undoes the shuffle; the result must be
 * raw (n bytes of elements of elem bytes) */
static void expect_round_trip(const cd_h5_packer *p, size_t len, const unsigned char *raw, size_t n, size_t elem)
{
    unsigned char *flat = malloc(n + 16), *back = malloc(n);
    uLongf got = (uLongf)(n + 16);
    size_t ne = n / elem, k, j;
    cr_assert(flat && back);
    cr_assert_eq(uncompress(flat, &got, p->out, (uLong)len), Z_OK, "a valid zlib stream");
    cr_assert_eq((size_t)got, n, "inflates to the chunk's %zu bytes, got %zu", n, (size_t)got);
    for (k = 0; k < elem; k++)
        for (j = 0; j < ne; j++) back[j * elem + k] = elem > 1 ? flat[k * ne + j] : flat[j];
    cr_expect_eq(memcmp(back, raw, n), 0, "the same bytes after unshuffling");
    free(flat);
    free(back);
}

Test(h5_pack, entropy_of_known_histograms)
{
    unsigned char b[512];
    int i;
    for (i = 0; i < 512; i++) b[i] = (unsigned char)(i % 256);
    cr_expect_float_eq(cd_h5_byte_entropy(b, 512), 8.0, 1e-12, "256 equally frequent values: 8 bits");
    memset(b, 7, sizeof b);
    cr_expect_float_eq(cd_h5_byte_entropy(b, 512), 0.0, 1e-12, "one value: 0 bits");
    for (i = 0; i < 512; i++) b[i] = (unsigned char)(i & 1);
    cr_expect_float_eq(cd_h5_byte_entropy(b, 512), 1.0, 1e-12, "two equally frequent values: 1 bit");
}

Test(h5_pack, noisy_doubles_store_their_low_planes_and_round_trip)
{
    /* 1 MiB of doubles (several 64 KiB stored blocks per plane): a smooth
     * signal plus noise of relative size 1e-6. The exponent and leading
     * mantissa bytes are regular (deflated), the low mantissa bytes are
     * noise (entropy ~8 bits: stored) */
    const size_t ne = 131072, n = ne * sizeof(double);
    double *x = malloc(n);
    cd_h5_packer p;
    uint64_t s = 42;
    size_t i, len;
    cr_assert(x);
    for (i = 0; i < ne; i++) x[i] = 1.0 + 0.5 * sin(1e-4 * (double)i) + 1e-6 * (double)(lcg(&s) % 1000000) / 1e6;
    cr_assert_eq(cd_h5_packer_init(&p, n), 0);
    len = cd_h5_pack(&p, (const unsigned char *)x, n, n, sizeof(double));
    cr_assert_gt(len, 0);
    expect_round_trip(&p, len, (const unsigned char *)x, n, sizeof(double));
    cr_expect_geq(p.n_stored, 4.0 * (double)ne, "at least the 4 lowest planes stored: %.0f bytes", p.n_stored);
    cr_expect_geq(p.n_deflated, 2.0 * (double)ne, "at least the sign/exponent planes deflated: %.0f", p.n_deflated);
    cr_expect_lt(len, n, "smaller than the raw chunk: %zu of %zu", len, n);
    cd_h5_packer_free(&p);
    free(x);
}

Test(h5_pack, regular_and_random_bytes)
{
    /* elem 1 (int8 modes, no shuffle): a chunk of one value deflates to
     * almost nothing; uniformly random bytes are stored, at most the stored
     * blocks' headers and the zlib wrapper above the raw size */
    const size_t n = 200000;
    unsigned char *b = malloc(n);
    cd_h5_packer p;
    uint64_t s = 7;
    size_t i, len;
    cr_assert(b);
    cr_assert_eq(cd_h5_packer_init(&p, n), 0);
    memset(b, 2, n);
    len = cd_h5_pack(&p, b, n, n, 1);
    cr_assert_gt(len, 0);
    expect_round_trip(&p, len, b, n, 1);
    cr_expect_lt(len, n / 100, "a constant chunk: %zu bytes", len);
    for (i = 0; i < n; i++) b[i] = (unsigned char)(lcg(&s) & 0xff);
    p.n_stored = p.n_deflated = 0;
    len = cd_h5_pack(&p, b, n, n, 1);
    cr_assert_gt(len, 0);
    expect_round_trip(&p, len, b, n, 1);
    cr_expect_eq(p.n_stored, (double)n, "random bytes are stored");
    cr_expect_leq(len, n + 5 * (n / 65535 + 1) + 6 + 16, "stored: %zu bytes for %zu", len, n);
    cd_h5_packer_free(&p);
    free(b);
}

Test(h5_pack, refuses_what_it_cannot_pack)
{
    /* a chunk larger than the buffers, or not a whole number of elements:
     * 0, and the writer then goes through HDF5's own filters */
    unsigned char b[64] = {0};
    cd_h5_packer p;
    cr_assert_eq(cd_h5_packer_init(&p, 32), 0);
    cr_expect_eq(cd_h5_pack(&p, b, 64, 64, 8), 0);
    cr_expect_eq(cd_h5_pack(&p, b, 30, 30, 8), 0);
    cr_expect_eq(cd_h5_pack(&p, b, 32, 40, 8), 0);
    cr_expect_gt(cd_h5_pack(&p, b, 32, 32, 8), 0);
    cd_h5_packer_free(&p);
}

Test(h5_pack, a_partly_filled_chunk_stores_only_its_rows)
{
    /* a chunk of 8192 doubles of which the first 1000 hold noise and the
     * rest are the zeros of rows not yet written: the noisy planes are
     * stored for the 1000 elements only, the zero tails deflated, so the
     * stream is far below the chunk's 64 KiB (it was the whole chunk when the
     * choice covered the tail too, and every rewrite of a growing chunk left
     * a dead copy that large in the file); and it inflates to the chunk */
    const size_t ne = 8192, nd = 1000, n = ne * sizeof(double);
    double *x = calloc(ne, sizeof(double));
    cd_h5_packer p;
    uint64_t s = 3;
    size_t i, len;
    cr_assert(x);
    for (i = 0; i < nd; i++) x[i] = (double)(lcg(&s) % 1000003) * 1e-3 + 1.0;
    cr_assert_eq(cd_h5_packer_init(&p, n), 0);
    len = cd_h5_pack(&p, (const unsigned char *)x, n, nd * sizeof(double), sizeof(double));
    cr_assert_gt(len, 0);
    expect_round_trip(&p, len, (const unsigned char *)x, n, sizeof(double));
    cr_expect_gt(p.n_stored, 0.0, "noisy planes stored");
    cr_expect_leq(p.n_stored, 8.0 * (double)nd, "only the data's bytes stored: %.0f", p.n_stored);
    cr_expect_lt(len, 8 * nd + 1024, "%zu bytes for %zu of data", len, 8 * nd);
    cd_h5_packer_free(&p);
    free(x);
}
