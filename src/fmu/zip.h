/* A minimal ZIP writer for the FMU archive (docs/fmu.md): stored
 * (uncompressed) entries with their CRC-32, the format of PKWARE's
 * APPNOTE.TXT sections 4.3-4.4 without compression, ZIP64, encryption or
 * data descriptors. FMI 2.0 accepts stored entries. */
#ifndef CD_FMU_ZIP_H
#define CD_FMU_ZIP_H

#include <stddef.h>

typedef struct {
    const char *name;          /* path inside the archive, '/'-separated */
    const unsigned char *data;
    size_t size;
    int executable;            /* 1: unix mode 0755, else 0644 */
} cdz_entry;

/* CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320) of n bytes,
 * continuing from crc (0 to start). */
unsigned long cdz_crc32(unsigned long crc, const unsigned char *p, size_t n);

/* Writes the n entries to path (created or replaced; written under a
 * temporary name in its directory and renamed onto it, so that a failure
 * leaves no partial archive at path). Returns 0, or -1 with msg (len bytes)
 * naming the file and what failed (an entry or the archive over 4 GiB, more
 * than 65535 entries, a write error). */
int cdz_write(const char *path, const cdz_entry *e, int n, char *msg, size_t len);

#endif
