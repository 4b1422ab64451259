/* tests/bad_inputs/: one scenario file per kind of mistake (issue 12). For
 * each NN_name.toml, `capdyn check NN_name.toml [args of NN_name.args, one
 * per line]` is run in that directory and must exit with status 1, write
 * nothing on stdout, and write on stderr exactly the one line of
 * NN_name.expected: "capdyn: error: FILE:LINE:COL: key 'PATH': expected ...,
 * got ..." (or the --set text in place of the file for an override).
 * tests/bad_inputs/generate.py writes the inputs; the expected lines were
 * checked by hand. At least 40 cases must be there. */
#include "loader_util.h"

#include <dirent.h>

static int is_case(const char *n)
{
    size_t l = strlen(n);
    size_t k = n[0] >= '0' && n[0] <= '9' && n[1] >= '0' && n[1] <= '9' && n[2] >= '0' && n[2] <= '9' ? 3 : 2; /* NN_ or NNN_ */
    return l > 8 && n[0] >= '0' && n[0] <= '9' && n[1] >= '0' && n[1] <= '9' && n[k] == '_' &&
           strcmp(n + l - 5, ".toml") == 0;
}

static int cmp_str(const void *a, const void *b) { return strcmp(*(const char *const *)a, *(const char *const *)b); }

/* runs one case; returns 1 when it behaves as expected (failures logged) */
static int run_case(const char *dir, const char *file)
{
    char base[256], path[1400], *want, *args_text = NULL, *out = NULL, *err = NULL;
    const char *argv[40];
    int n = 0, rc, ok;
    snprintf(base, sizeof base, "%.*s", (int)(strlen(file) - 5), file);
    snprintf(path, sizeof path, "%s/%s.expected", dir, base);
    want = slurp(path);
    if (!want) {
        cr_log_error("%s: no %s.expected", file, base);
        return 0;
    }
    argv[n++] = "check";
    argv[n++] = file;
    snprintf(path, sizeof path, "%s/%s.args", dir, base);
    args_text = slurp(path);
    if (args_text) {
        char *save = NULL, *tok;
        for (tok = strtok_r(args_text, "\n", &save); tok && n < 38; tok = strtok_r(NULL, "\n", &save)) argv[n++] = tok;
    }
    argv[n] = NULL;
    rc = lu_capdyn(dir, &out, &err, argv);
    ok = rc == 1 && out && out[0] == 0 && err && strcmp(err, want) == 0 && strchr(err, '\n') == err + strlen(err) - 1;
    if (!ok)
        cr_log_error("%s: exit %d (want 1), stdout '%s'\n  stderr   %s  expected %s", file, rc, out ? out : "?",
                     err ? err : "?\n", want);
    free(want);
    free(args_text);
    free(out);
    free(err);
    return ok;
}

Test(bad_inputs, each_file_gives_its_one_line_message_and_exit_1, .timeout = 120)
{
    char dir[1024];
    DIR *d;
    struct dirent *e;
    char *names[256];
    int n = 0, i, good = 0;
    snprintf(dir, sizeof dir, "%s/tests/bad_inputs", lu_root());
    d = opendir(dir);
    cr_assert_not_null(d, "%s", dir);
    while ((e = readdir(d)) != NULL && n < 256)
        if (is_case(e->d_name)) names[n++] = strdup(e->d_name);
    closedir(d);
    qsort(names, (size_t)n, sizeof *names, cmp_str);
    cr_expect(n >= 40, "%d cases, at least 40 wanted", n);
    for (i = 0; i < n; i++) {
        good += run_case(dir, names[i]);
        free(names[i]);
    }
    cr_expect_eq(good, n, "%d of %d cases as expected", good, n);
}
