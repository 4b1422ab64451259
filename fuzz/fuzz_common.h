/* Shared part of the libFuzzer targets (fuzz/fuzz.mk, docs/reliability.md
 * "## Input"). An input is a scenario file, optionally followed by a line
 * "#--set" and one override per line:
 *
 *     [simulation]
 *     duration = 1
 *     ...
 *     #--set
 *     simulation.duration=2
 *
 * The text before "#--set" is written to a per-process temporary file (the
 * loader reads files: includes are resolved next to it) and loaded with the
 * overrides, on a thread with a 256 KiB stack (an embedder's thread): a
 * stack overflow or any sanitizer report is a finding. */
#ifndef CAPDYN_FUZZ_COMMON_H
#define CAPDYN_FUZZ_COMMON_H

#include "capdyn/io.h"

#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#ifndef FUZZ_STACK
#define FUZZ_STACK (256u * 1024u)
#endif
#define FUZZ_MAX_SETS 16

typedef struct {
    char path[64];
    char *sets[FUZZ_MAX_SETS];
    int nsets;
    void (*work)(const char *path, const char *const *sets, int nsets);
} fuzz_job;

static void *fuzz_thread(void *p)
{
    fuzz_job *j = (fuzz_job *)p;
    j->work(j->path, (const char *const *)j->sets, j->nsets);
    return NULL;
}

/* Splits the input, writes the scenario file, runs work on a FUZZ_STACK
 * thread. */
static void fuzz_run(const uint8_t *data, size_t size,
                     void (*work)(const char *path, const char *const *sets, int nsets))
{
    static const char mark[] = "\n#--set\n";
    fuzz_job j;
    const char *text = (const char *)data, *end = text + size, *sep = NULL, *p;
    size_t tlen = size, i;
    FILE *f;
    pthread_attr_t a;
    pthread_t t;
    memset(&j, 0, sizeof j);
    j.work = work;
    for (i = 0; i + sizeof mark - 1 <= size; i++)
        if (memcmp(text + i, mark, sizeof mark - 1) == 0) { sep = text + i; break; }
    if (sep) {
        tlen = (size_t)(sep - text);
        for (p = sep + sizeof mark - 1; p < end && j.nsets < FUZZ_MAX_SETS;) {
            const char *nl = memchr(p, '\n', (size_t)(end - p));
            size_t n = (size_t)((nl ? nl : end) - p);
            char *s = malloc(n + 1);
            if (!s) break;
            memcpy(s, p, n);
            s[n] = 0;
            j.sets[j.nsets++] = s;
            p = nl ? nl + 1 : end;
        }
    }
    snprintf(j.path, sizeof j.path, "/tmp/capdyn_fuzz_%ld.toml", (long)getpid());
    f = fopen(j.path, "wb");
    if (f) {
        fwrite(text, 1, tlen, f);
        fclose(f);
        pthread_attr_init(&a);
        pthread_attr_setstacksize(&a, FUZZ_STACK);
        if (pthread_create(&t, &a, fuzz_thread, &j) == 0) pthread_join(t, NULL);
        pthread_attr_destroy(&a);
    }
    for (i = 0; i < (size_t)j.nsets; i++) free(j.sets[i]);
}

/* A failed load must say why, on one line, with a known status. */
static void fuzz_check_error(const cd_error *err)
{
    if (err->status == CD_OK || err->msg[0] == 0 || strchr(err->msg, '\n') || strchr(err->msg, '\033')) {
        fprintf(stderr, "bad error report: status %d, message '%s'\n", (int)err->status, err->msg);
        abort();
    }
}

#endif
