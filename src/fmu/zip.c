/* A minimal ZIP writer: stored entries (zip.h). */
#define _POSIX_C_SOURCE 200809L
#include "zip.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

unsigned long cdz_crc32(unsigned long crc, const unsigned char *p, size_t n)
{
    size_t i;
    int k;
    crc = ~crc & 0xFFFFFFFFUL;
    for (i = 0; i < n; i++) {
        crc ^= p[i];
        for (k = 0; k < 8; k++) crc = (crc >> 1) ^ (0xEDB88320UL & (0UL - (crc & 1UL)));
    }
    return ~crc & 0xFFFFFFFFUL;
}

static void le16(unsigned char *b, unsigned long v)
{
    b[0] = (unsigned char)(v & 0xFF);
    b[1] = (unsigned char)((v >> 8) & 0xFF);
}
static void le32(unsigned char *b, unsigned long v)
{
    le16(b, v & 0xFFFF);
    le16(b + 2, (v >> 16) & 0xFFFF);
}

/* 1980-01-01 00:00 in MS-DOS format: a fixed time keeps the archive of the
 * same inputs byte-identical */
#define DOS_TIME 0UL
#define DOS_DATE ((0UL << 9) | (1UL << 5) | 1UL)

int cdz_write(const char *path, const cdz_entry *e, int n, char *msg, size_t len)
{
    char *tmp;
    FILE *f;
    unsigned long *crc, *off, pos = 0, cd_start, cd_size = 0;
    unsigned char h[46];
    int i, ok = 1;
    const unsigned long lim = 0xFFFFFFFFUL;
    if (len) msg[0] = 0;
    if (n < 0 || n > 0xFFFF) {
        snprintf(msg, len, "%s: %d entries: more than a ZIP without ZIP64 holds", path, n);
        return -1;
    }
    tmp = (char *)malloc(strlen(path) + 16);
    crc = (unsigned long *)calloc((size_t)n + 1, sizeof *crc);
    off = (unsigned long *)calloc((size_t)n + 1, sizeof *off);
    if (!tmp || !crc || !off) {
        free(tmp); free(crc); free(off);
        snprintf(msg, len, "%s: out of memory", path);
        return -1;
    }
    sprintf(tmp, "%s.tmp%ld", path, (long)getpid());
    f = fopen(tmp, "wb");
    if (!f) {
        snprintf(msg, len, "cannot write '%s': %s", path, strerror(errno));
        free(tmp); free(crc); free(off);
        return -1;
    }
    /* local headers and data */
    for (i = 0; ok && i < n; i++) {
        size_t nl = strlen(e[i].name);
        if (e[i].size >= lim || pos + 30 + nl + e[i].size >= lim || nl > 0xFFFF) {
            snprintf(msg, len, "%s: entry '%s' would take the archive over 4 GiB (no ZIP64)", path, e[i].name);
            ok = 0;
            break;
        }
        crc[i] = cdz_crc32(0, e[i].data, e[i].size);
        off[i] = pos;
        memset(h, 0, sizeof h);
        le32(h, 0x04034b50UL);
        le16(h + 4, 20);             /* version needed: 2.0 */
        le16(h + 6, 0);              /* flags */
        le16(h + 8, 0);              /* method: stored */
        le16(h + 10, DOS_TIME);
        le16(h + 12, DOS_DATE);
        le32(h + 14, crc[i]);
        le32(h + 18, (unsigned long)e[i].size);
        le32(h + 22, (unsigned long)e[i].size);
        le16(h + 26, (unsigned long)nl);
        le16(h + 28, 0);             /* extra field length */
        if (fwrite(h, 1, 30, f) != 30 || fwrite(e[i].name, 1, nl, f) != nl ||
            (e[i].size && fwrite(e[i].data, 1, e[i].size, f) != e[i].size)) ok = 0;
        pos += 30 + (unsigned long)nl + (unsigned long)e[i].size;
    }
    /* central directory */
    cd_start = pos;
    for (i = 0; ok && i < n; i++) {
        size_t nl = strlen(e[i].name);
        unsigned long mode = e[i].executable ? 0100755UL : 0100644UL;
        memset(h, 0, sizeof h);
        le32(h, 0x02014b50UL);
        le16(h + 4, (3UL << 8) | 20); /* made by: UNIX, 2.0 (the external attributes hold the mode) */
        le16(h + 6, 20);
        le16(h + 8, 0);
        le16(h + 10, 0);
        le16(h + 12, DOS_TIME);
        le16(h + 14, DOS_DATE);
        le32(h + 16, crc[i]);
        le32(h + 20, (unsigned long)e[i].size);
        le32(h + 24, (unsigned long)e[i].size);
        le16(h + 28, (unsigned long)nl);
        /* extra 30, comment 32, disk 34, internal attributes 36: 0 */
        le32(h + 38, mode << 16);
        le32(h + 42, off[i]);
        if (fwrite(h, 1, 46, f) != 46 || fwrite(e[i].name, 1, nl, f) != nl) ok = 0;
        cd_size += 46 + (unsigned long)nl;
        if (cd_start + cd_size >= lim) {
            snprintf(msg, len, "%s: the archive would be over 4 GiB (no ZIP64)", path);
            ok = 0;
        }
    }
    if (ok) { /* end of central directory */
        memset(h, 0, sizeof h);
        le32(h, 0x06054b50UL);
        le16(h + 8, (unsigned long)n);
        le16(h + 10, (unsigned long)n);
        le32(h + 12, cd_size);
        le32(h + 16, cd_start);
        if (fwrite(h, 1, 22, f) != 22) ok = 0;
    }
    if (fclose(f) != 0) ok = 0;
    if (ok && rename(tmp, path) != 0) {
        snprintf(msg, len, "cannot write '%s': %s", path, strerror(errno));
        remove(tmp);
        ok = 0;
        free(tmp); free(crc); free(off);
        return -1;
    }
    if (!ok) {
        if (len && !msg[0]) snprintf(msg, len, "cannot write '%s': %s", path, strerror(errno ? errno : EIO));
        remove(tmp);
    }
    free(tmp); free(crc); free(off);
    return ok ? 0 : -1;
}
