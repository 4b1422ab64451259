/* capdyn sweep --merge: the shards of one sweep (--shard K/N, a Slurm job
 * array) joined into one summary (docs/sweep.md, "Past one machine"). The
 * sweep's definition is read from the first shard; every shard is checked
 * against it as --resume checks a summary (same scenario text, overrides,
 * keys, every variant's values), and each variant is taken from the shard
 * that ran it. The merged summary is the one a single process would have
 * written (root checksum equal; /timing aside). */
#define _DEFAULT_SOURCE /* MAP_ANONYMOUS */
#define _POSIX_C_SOURCE 200809L
#include "sweep.h"

#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

#define MG_BUF (64L << 20) /* bytes of the definition passed from the child */

typedef struct {
    const char *path;
    char *buf; /* shared: NUL-separated fields */
} mg_job;

/* appends a field; 0 or -1 (too long) */
static int put(char *buf, size_t *at, const char *v)
{
    size_t n = strlen(v) + 1;
    if (*at + n > (size_t)MG_BUF) return -1;
    memcpy(buf + *at, v, n);
    *at += n;
    return 0;
}

/* the child: the first shard's definition as fields: scenario, text,
 * overrides, length, until_verdict, lhs, seed, mc, nvary, nkey, then
 * nkey x "name=spec" */
static int def_child(void *arg)
{
    mg_job *j = arg;
    sw_summary s;
    char msg[2048], num[64];
    size_t at = 0;
    int k, rc = 0;
    if (sw_summary_load(j->path, &s, msg, sizeof msg) != 0) {
        cli_error("--merge: %s", msg);
        return CLI_FAIL;
    }
    rc |= put(j->buf, &at, s.scenario);
    rc |= put(j->buf, &at, s.scenario_text);
    rc |= put(j->buf, &at, s.overrides);
    snprintf(num, sizeof num, "%.17g", s.length);
    rc |= put(j->buf, &at, num);
    snprintf(num, sizeof num, "%lld", s.until_verdict);
    rc |= put(j->buf, &at, num);
    snprintf(num, sizeof num, "%lld", strcmp(s.design, "lhs") ? 0LL : s.lhs_samples);
    rc |= put(j->buf, &at, num);
    snprintf(num, sizeof num, "%lld", s.seed);
    rc |= put(j->buf, &at, num);
    snprintf(num, sizeof num, "%lld", s.mc);
    rc |= put(j->buf, &at, num);
    snprintf(num, sizeof num, "%lld", s.nvary);
    rc |= put(j->buf, &at, num);
    snprintf(num, sizeof num, "%d", s.nkey);
    rc |= put(j->buf, &at, num);
    for (k = 0; k < s.nkey && !rc; k++) {
        char *kv = malloc(strlen(s.names[k]) + strlen(s.specs[k]) + 2);
        if (!kv) rc = -1;
        else {
            sprintf(kv, "%s=%s", s.names[k], s.specs[k]);
            rc |= put(j->buf, &at, kv);
            free(kv);
        }
    }
    sw_summary_free(&s);
    if (rc) {
        cli_error("--merge: '%s': the sweep's definition is too large", j->path);
        return CLI_FAIL;
    }
    return CLI_OK;
}

static const char *next_field(const char **p)
{
    const char *v = *p;
    *p += strlen(v) + 1;
    return v;
}

int sw_merge(const sw_opts *o)
{
    mg_job j;
    const char *q, *vary[SW_MAX_KEYS + 1], *disp[SW_MAX_KEYS + 1];
    sw_meta meta;
    sw_plan p;
    sw_out out;
    sw_result *res = NULL, *tmp = NULL;
    long lhs, mc, nvary, nkey, i, seed, until;
    int f, k, rc = CLI_FAIL;
    char msg[2048];
    memset(&p, 0, sizeof p);
    memset(&out, 0, sizeof out);
    out.lock_fd = -1;
    for (f = 0; f < o->nmerge; f++)
        if (cli_regular_input(o->merge[f], "sweep summary", msg, sizeof msg) != 0) {
            cli_error("--merge: %s", msg);
            return CLI_FAIL;
        }
    j.path = o->merge[0];
    j.buf = mmap(NULL, (size_t)MG_BUF, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    if (j.buf == MAP_FAILED) {
        cli_error("--merge: out of memory");
        return CLI_FAIL;
    }
    if (cli_isolated(j.path, def_child, &j) != CLI_OK) goto done;
    q = j.buf;
    meta.scenario = next_field(&q);
    meta.scenario_text = next_field(&q);
    meta.overrides = next_field(&q);
    cli_number(next_field(&q), &meta.length);
    if (cli_count(next_field(&q), &until) || cli_count(next_field(&q), &lhs) || cli_count(next_field(&q), &seed) ||
        cli_count(next_field(&q), &mc) || cli_count(next_field(&q), &nvary) || cli_count(next_field(&q), &nkey) ||
        nkey < 1 || nkey > SW_MAX_KEYS || nvary > nkey || nvary > SW_MAX_VARY || nkey - nvary > SW_MAX_DISP) {
        cli_error("--merge: '%s': the sweep's definition is damaged", j.path);
        goto done;
    }
    meta.until_verdict = (int)until;
    for (k = 0; k < nkey; k++) {
        if (k < nvary) vary[k] = next_field(&q);
        else disp[k - nvary] = next_field(&q);
    }
    if (sw_plan_make_mc(&p, vary, (int)nvary, lhs, (unsigned long long)seed, disp, (int)(nkey - nvary), mc) != CLI_OK)
        goto done;
    res = malloc(sizeof *res * (size_t)(p.nvar + 1));
    tmp = malloc(sizeof *tmp * (size_t)(p.nvar + 1));
    if (!res || !tmp) {
        cli_error("out of memory");
        goto done;
    }
    for (i = 0; i < p.nvar; i++) sw_result_blank(&res[i], i);
    for (f = 0; f < o->nmerge; f++) {
        if (sw_summary_resume(o->merge[f], &meta, &p, tmp) != 0) goto done; /* the same sweep? */
        for (i = 0; i < p.nvar; i++) {
            if (tmp[i].status == SW_NOT_RUN) continue;
            if (res[i].status != SW_NOT_RUN) {
                cli_error("--merge: variant %ld is in two shards ('%s' and an earlier one): give each shard once", i,
                          o->merge[f]);
                goto done;
            }
            res[i] = tmp[i];
        }
    }
    if (sw_out_open(&out, o->output, o->merge, o->nmerge, msg, sizeof msg) != 0 ||
        sw_summary_write(&out, &meta, &p, res, 0, 0, msg, sizeof msg) != 0) {
        cli_error("--merge: %s", msg);
        goto done;
    }
    {
        long nrun = 0;
        for (i = 0; i < p.nvar; i++) nrun += res[i].status != SW_NOT_RUN;
        if (!o->quiet)
            printf("merged %d summaries: %ld of %ld variants run -> %s\n", o->nmerge, nrun, p.nvar, o->output);
    }
    rc = CLI_OK;
done:
    free(res);
    free(tmp);
    sw_out_close(&out);
    sw_plan_free(&p);
    munmap(j.buf, (size_t)MG_BUF);
    return rc;
}
