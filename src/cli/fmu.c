/* capdyn fmu: a scenario as an FMI 2.0 co-simulation FMU (docs/fmu.md).
 *
 * Loads the scenario (with the --param values as overrides, so that a bad
 * key fails here with the loader's message), checks that the scenario file
 * loads on its own from another directory (an FMU carries that one file),
 * lists its variables (src/fmu/vars.c, the list the FMU binary builds too),
 * writes modelDescription.xml and zips it with the prebuilt binary
 * directory (make fmu: build/fmu/linux64/, or CAPDYN_FMU_DIR) and the
 * scenario into one archive of stored entries (src/fmu/zip.c). */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "../fmu/vars.h"
#include "../fmu/zip.h"

#include <dirent.h>
#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#ifndef CAPDYN_FMU_DIR
#define CAPDYN_FMU_DIR "build/fmu/linux64"
#endif
#define FMU_MODEL_ID "capdyn_fmu"

static const char *fmu_help =
    "usage: capdyn fmu SCENARIO.toml -o FILE.fmu [--input NAME ...] [--output NAME ...]\n"
    "                  [--param KEY=VALUE ...] [--set KEY=VALUE ...] [--list]\n"
    "\n"
    "Writes an FMI 2.0 co-simulation FMU of the scenario (docs/fmu.md): its\n"
    "modelDescription.xml, the linux64 binary (built by make fmu) and the scenario\n"
    "in resources/. Every fmi2DoStep advances with the adaptive integrator to the\n"
    "end of the communication step, locating every event inside it.\n"
    "\n"
    "options:\n"
    "  -o, --output-file FILE  the FMU to write (required unless --list); written\n"
    "                      under a temporary name and renamed onto FILE\n"
    "  --input NAME        offer only the named inputs (repeatable; default: all)\n"
    "  --output NAME       offer only the named outputs (repeatable; default: all)\n"
    "  --param KEY=VALUE   a scenario key (the --set syntax, a number) as an FMU\n"
    "                      parameter, VALUE its start value; settable before\n"
    "                      initialisation (repeatable)\n"
    "  --set KEY=VALUE     fixes a scenario value inside the FMU (TOML syntax)\n"
    "  --list              print the variables (causality, type, name, description)\n"
    "  -h, --help          this text\n"
    "\n"
    "The binary is looked up in CAPDYN_FMU_DIR if set, else in the build tree\n"
    "(" CAPDYN_FMU_DIR ").\n";

/* a growing text buffer */
typedef struct {
    char *s;
    size_t n, cap;
    int oom;
} sbuf;

static void sb_printf(sbuf *b, const char *fmt, ...)
{
    va_list ap;
    int k;
    if (b->oom) return;
    for (;;) {
        size_t room = b->cap - b->n;
        va_start(ap, fmt);
        k = vsnprintf(b->s ? b->s + b->n : NULL, b->s ? room : 0, fmt, ap);
        va_end(ap);
        if (k < 0) { b->oom = 1; return; }
        if (b->s && (size_t)k < room) { b->n += (size_t)k; return; }
        {
            size_t cap = b->cap ? 2 * b->cap : 4096;
            char *ns;
            while (cap < b->n + (size_t)k + 1) cap *= 2;
            ns = (char *)realloc(b->s, cap);
            if (!ns) { b->oom = 1; return; }
            b->s = ns;
            b->cap = cap;
        }
    }
}

/* s with &, <, >, " escaped for an XML attribute */
static void sb_xml(sbuf *b, const char *s)
{
    for (; *s; s++) {
        switch (*s) {
        case '&': sb_printf(b, "&amp;"); break;
        case '<': sb_printf(b, "&lt;"); break;
        case '>': sb_printf(b, "&gt;"); break;
        case '"': sb_printf(b, "&quot;"); break;
        default:
            if ((unsigned char)*s < 0x20) sb_printf(b, " ");
            else sb_printf(b, "%c", *s);
        }
    }
}

static unsigned char *read_all(const char *path, size_t *n, char *msg, size_t len)
{
    FILE *f = fopen(path, "rb");
    unsigned char *buf = NULL;
    size_t cap = 0, got = 0, k;
    if (!f) {
        snprintf(msg, len, "cannot read '%s': %s", path, strerror(errno));
        return NULL;
    }
    for (;;) {
        if (got == cap) {
            unsigned char *nb = (unsigned char *)realloc(buf, cap ? 2 * cap : 65536);
            if (!nb) { free(buf); fclose(f); snprintf(msg, len, "%s: out of memory", path); return NULL; }
            buf = nb;
            cap = cap ? 2 * cap : 65536;
        }
        k = fread(buf + got, 1, cap - got, f);
        got += k;
        if (k == 0) break;
    }
    if (ferror(f)) {
        snprintf(msg, len, "cannot read '%s': %s", path, strerror(errno));
        free(buf);
        fclose(f);
        return NULL;
    }
    fclose(f);
    *n = got;
    return buf;
}

/* FNV-1a, 64 bits, continuing from h */
static unsigned long long fnv(unsigned long long h, const void *p, size_t n)
{
    const unsigned char *c = (const unsigned char *)p;
    size_t i;
    for (i = 0; i < n; i++) {
        h ^= c[i];
        h *= 1099511628211ULL;
    }
    return h;
}

/* The scenario file loads on its own (what the FMU carries): copied into a
 * fresh directory and loaded there with the same overrides. */
static int loads_alone(const unsigned char *text, size_t n, const char *const *ov, int nov, char *msg, size_t len)
{
    const char *tmpdir = getenv("TMPDIR");
    char dir[1024], path[1100];
    FILE *f;
    cd_scenario *sc;
    cd_error err;
    int ok;
    snprintf(dir, sizeof dir, "%s/capdyn-fmu-XXXXXX", tmpdir && *tmpdir ? tmpdir : "/tmp");
    if (!mkdtemp(dir)) {
        snprintf(msg, len, "cannot make a temporary directory in '%s': %s", tmpdir && *tmpdir ? tmpdir : "/tmp", strerror(errno));
        return -1;
    }
    snprintf(path, sizeof path, "%s/scenario.toml", dir);
    f = fopen(path, "wb");
    ok = f && fwrite(text, 1, n, f) == n;
    if (f && fclose(f) != 0) ok = 0;
    if (!ok) {
        snprintf(msg, len, "cannot write '%s': %s", path, strerror(errno));
        remove(path);
        rmdir(dir);
        return -1;
    }
    sc = cd_scenario_load(path, ov, nov, &err);
    remove(path);
    rmdir(dir);
    if (!sc) {
        snprintf(msg, len, "the scenario does not load on its own, as resources/scenario.toml inside the FMU (an FMU carries "
                 "the scenario file only: no include or other file it names): %s", err.msg);
        return -1;
    }
    cd_scenario_free(sc);
    return 0;
}

static int name_in(const char *name, char **list, int n)
{
    int i;
    for (i = 0; i < n; i++)
        if (!strcmp(list[i], name)) return 1;
    return 0;
}

int cmd_fmu(int argc, char **argv)
{
    const char *scenario = NULL, *out = NULL, *bindir;
    char **inputs, **outputs, **params, **sets, **ov;
    int nin = 0, nout = 0, nparam = 0, nset = 0, list = 0, i, j, rc = CLI_FAIL, nvar = 0, nent = 0;
    cd_scenario *sc = NULL;
    cd_data *d = NULL;
    cd_ctrl *ctl = NULL;
    cdf_var *vars = NULL;
    cd_error err;
    char msg[1536];
    unsigned char *text = NULL;
    size_t ntext = 0;
    sbuf x = {NULL, 0, 0, 0}, pt = {NULL, 0, 0, 0};
    cdz_entry *ent = NULL;
    unsigned char **bins = NULL;
    char **binnames = NULL;
    int nbin = 0, *sel = NULL;
    DIR *dh = NULL;
    unsigned long long h1, h2;

    inputs = (char **)calloc((size_t)argc + 1, sizeof(char *));
    outputs = (char **)calloc((size_t)argc + 1, sizeof(char *));
    params = (char **)calloc((size_t)argc + 1, sizeof(char *));
    sets = (char **)calloc((size_t)argc + 1, sizeof(char *));
    ov = (char **)calloc((size_t)argc + 1, sizeof(char *));
    if (!inputs || !outputs || !params || !sets || !ov) {
        cli_error("out of memory");
        goto done;
    }
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            fputs(fmu_help, stdout);
            rc = CLI_OK;
            goto done;
        }
        if (!strcmp(a, "--list")) { list = 1; continue; }
        if (!strcmp(a, "-o") || !strcmp(a, "--output-file") || !strcmp(a, "--input") || !strcmp(a, "--output") ||
            !strcmp(a, "--param") || !strcmp(a, "--set")) {
            if (!v || !*v) { rc = cli_usage("fmu", "%s needs a value", a); goto done; }
            i++;
            if (!strcmp(a, "-o") || !strcmp(a, "--output-file")) out = v;
            else if (!strcmp(a, "--input")) inputs[nin++] = (char *)v;
            else if (!strcmp(a, "--output")) outputs[nout++] = (char *)v;
            else {
                const char *eq = strchr(v, '=');
                double num;
                if (!eq || eq == v) { rc = cli_usage("fmu", "%s expects KEY=VALUE, got '%s'", a, v); goto done; }
                if (!strcmp(a, "--param")) {
                    if (cli_number(eq + 1, &num) != 0) {
                        rc = cli_usage("fmu", "--param %s: the start value '%s' is not a finite number (FMU parameters are Real)", v, eq + 1);
                        goto done;
                    }
                    for (j = 0; j < nparam; j++)
                        if (!strncmp(params[j], v, (size_t)(eq - v) + 1)) {
                            rc = cli_usage("fmu", "--param %.*s given twice", (int)(eq - v), v);
                            goto done;
                        }
                    params[nparam++] = (char *)v;
                } else
                    sets[nset++] = (char *)v;
            }
            continue;
        }
        if (a[0] == '-' && a[1]) { rc = cli_usage("fmu", "unknown option '%s'", a); goto done; }
        if (scenario) { rc = cli_usage("fmu", "unexpected argument '%s' (one scenario file per FMU)", a); goto done; }
        scenario = a;
    }
    if (!scenario) { rc = cli_usage("fmu", "missing the scenario file"); goto done; }
    if (!out && !list) { rc = cli_usage("fmu", "missing -o FILE.fmu"); goto done; }

    /* the scenario as the FMU will load it: --set values fixed into the
     * text, then the parameters' start values as overrides */
    for (i = 0; i < nset; i++) ov[i] = sets[i];
    for (i = 0; i < nparam; i++) ov[nset + i] = params[i];
    sc = cd_scenario_load(scenario, (const char *const *)ov, nset + nparam, &err);
    if (!sc) { cli_error("%s", err.msg); goto done; }
    if (cd_scenario_setup(sc, &d, &ctl, &err) != CD_OK) { cli_error("%s: %s", scenario, err.msg); goto done; }
    cd_ctrl_free(ctl); /* only the data's layout is needed here */
    ctl = NULL;
    if (cdf_vars_build(sc, d, &vars, &nvar, &err) != CD_OK) { cli_error("%s", err.msg); goto done; }
    sel = (int *)calloc((size_t)nvar + 1, sizeof *sel);
    if (!sel) { cli_error("out of memory"); goto done; }
    for (i = 0; i < nin; i++) {
        for (j = 0; j < nvar; j++) if (vars[j].causality == CDF_INPUT && !strcmp(vars[j].name, inputs[i])) break;
        if (j == nvar) { rc = cli_usage("fmu", "--input '%s': no such input of %s (capdyn fmu %s --list)", inputs[i], scenario, scenario); goto done; }
    }
    for (i = 0; i < nout; i++) {
        for (j = 0; j < nvar; j++) if (vars[j].causality == CDF_OUTPUT && !strcmp(vars[j].name, outputs[i])) break;
        if (j == nvar) { rc = cli_usage("fmu", "--output '%s': no such output of %s (capdyn fmu %s --list)", outputs[i], scenario, scenario); goto done; }
    }
    for (j = 0; j < nvar; j++) {
        if (vars[j].causality == CDF_INPUT) sel[j] = !nin || name_in(vars[j].name, inputs, nin);
        else sel[j] = !nout || name_in(vars[j].name, outputs, nout);
    }
    if (list) {
        for (j = 0; j < nvar; j++)
            if (sel[j])
                printf("%-9s %-7s %-40s %s\n", vars[j].causality == CDF_INPUT ? "input" : "output",
                       vars[j].type == CDF_REAL ? "Real" : "Integer", vars[j].name, vars[j].desc);
        for (i = 0; i < nparam; i++)
            printf("%-9s %-7s %-40.*s scenario key, start %s\n", "parameter", "Real", (int)(strchr(params[i], '=') - params[i]),
                   params[i], strchr(params[i], '=') + 1);
        rc = CLI_OK;
        goto done;
    }

    /* the scenario file as it is; the --set values and the parameters go
     * into resources/params.txt, which the binary applies as overrides */
    if (!(text = read_all(scenario, &ntext, msg, sizeof msg))) { cli_error("%s", msg); goto done; }
    if (loads_alone(text, ntext, (const char *const *)ov, nset + nparam, msg, sizeof msg) != 0) {
        cli_error("%s: %s", scenario, msg);
        goto done;
    }

    /* the binary directory */
    bindir = getenv("CAPDYN_FMU_DIR");
    if (!bindir || !*bindir) bindir = CAPDYN_FMU_DIR;
    {
        char p[2048];
        struct stat stb;
        snprintf(p, sizeof p, "%s/%s.so", bindir, FMU_MODEL_ID);
        if (stat(p, &stb) != 0) {
            cli_error("no FMU binary '%s' (%s): run 'make fmu' (it needs fmpy's FMI 2.0 headers: make python-test "
                      "installs them) or set CAPDYN_FMU_DIR", p, strerror(errno));
            goto done;
        }
    }
    dh = opendir(bindir);
    if (!dh) { cli_error("cannot read the FMU binary directory '%s': %s", bindir, strerror(errno)); goto done; }
    {
        struct dirent *de;
        while ((de = readdir(dh))) {
            char p[2048];
            struct stat stb;
            size_t nb;
            unsigned char **b2;
            char **n2;
            if (de->d_name[0] == '.') continue;
            snprintf(p, sizeof p, "%s/%s", bindir, de->d_name);
            if (stat(p, &stb) != 0 || !S_ISREG(stb.st_mode)) continue;
            b2 = (unsigned char **)realloc(bins, (size_t)(nbin + 1) * sizeof *b2);
            if (b2) bins = b2;
            n2 = (char **)realloc(binnames, (size_t)(nbin + 1) * sizeof *n2);
            if (n2) binnames = n2;
            if (!b2 || !n2 || !(binnames[nbin] = (char *)malloc(strlen(de->d_name) + 32))) { cli_error("out of memory"); goto done; }
            snprintf(binnames[nbin], strlen(de->d_name) + 32, "binaries/linux64/%s", de->d_name);
            bins[nbin] = NULL;
            nbin++;
            if (!(bins[nbin - 1] = read_all(p, &nb, msg, sizeof msg))) { cli_error("%s", msg); goto done; }
            {
                cdz_entry *e2 = (cdz_entry *)realloc(ent, (size_t)(nbin + 3) * sizeof *e2);
                if (!e2) { cli_error("out of memory"); goto done; }
                ent = e2;
            }
            ent[nbin - 1].name = binnames[nbin - 1];
            ent[nbin - 1].data = bins[nbin - 1];
            ent[nbin - 1].size = nb;
            ent[nbin - 1].executable = !strcmp(de->d_name, FMU_MODEL_ID ".so");
        }
    }

    /* the parameters and --set values the binary applies at instantiation */
    for (i = 0; i < nset; i++) sb_printf(&pt, "set %s\n", sets[i]);
    for (i = 0; i < nparam; i++) sb_printf(&pt, "param %s\n", params[i]);
    if (pt.oom) { cli_error("out of memory"); goto done; }

    /* guid: a hash of the scenario, the overrides and the variables */
    h1 = fnv(14695981039346656037ULL, text, ntext);
    h1 = fnv(h1, pt.s ? pt.s : "", pt.n);
    h2 = fnv(h1 ^ 0x9e3779b97f4a7c15ULL, vars, (size_t)nvar * sizeof *vars);
    h2 = fnv(h2, sel, (size_t)nvar * sizeof *sel);

    /* modelDescription.xml */
    sb_printf(&x, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<fmiModelDescription fmiVersion=\"2.0\" modelName=\"");
    sb_xml(&x, sc->title && *sc->title ? sc->title : scenario);
    sb_printf(&x, "\" guid=\"{%08llx-%04llx-%04llx-%04llx-%012llx}\" description=\"capdyn scenario ", h1 >> 32,
              (h1 >> 16) & 0xFFFF, h1 & 0xFFFF, h2 >> 48, h2 & 0xFFFFFFFFFFFFULL);
    sb_xml(&x, strrchr(scenario, '/') ? strrchr(scenario, '/') + 1 : scenario);
    sb_printf(&x, " (docs/fmu.md)\" generationTool=\"capdyn %s\" variableNamingConvention=\"flat\" "
                  "numberOfEventIndicators=\"0\">\n", cd_version());
    sb_printf(&x, "  <CoSimulation modelIdentifier=\"%s\" canHandleVariableCommunicationStepSize=\"true\" "
                  "canInterpolateInputs=\"false\" maxOutputDerivativeOrder=\"0\" canRunAsynchronuously=\"false\" "
                  "canBeInstantiatedOnlyOncePerProcess=\"false\" canNotUseMemoryManagementFunctions=\"true\" "
                  "canGetAndSetFMUstate=\"true\" canSerializeFMUstate=\"true\" "
                  "providesDirectionalDerivative=\"false\"/>\n", FMU_MODEL_ID);
    sb_printf(&x, "  <LogCategories>\n    <Category name=\"logStatusError\" description=\"errors\"/>\n"
                  "    <Category name=\"logAll\" description=\"everything\"/>\n  </LogCategories>\n");
    {
        char a[CLI_NUM], b[CLI_NUM];
        sb_printf(&x, "  <DefaultExperiment startTime=\"0\" stopTime=\"%s\" stepSize=\"%s\"/>\n",
                  cli_fmt_num(a, sc->duration), cli_fmt_num(b, sc->output_dt));
    }
    sb_printf(&x, "  <ModelVariables>\n");
    for (j = 0; j < nvar; j++) {
        const cdf_var *v = &vars[j];
        if (!sel[j]) continue;
        sb_printf(&x, "    <ScalarVariable name=\"");
        sb_xml(&x, v->name);
        sb_printf(&x, "\" valueReference=\"%d\" description=\"", j);
        sb_xml(&x, v->desc);
        if (v->causality == CDF_INPUT)
            sb_printf(&x, "\" causality=\"input\" variability=\"continuous\">\n      <Real start=\"0\"/>\n");
        else
            sb_printf(&x, "\" causality=\"output\" variability=\"%s\" initial=\"calculated\">\n      <%s/>\n",
                      v->type == CDF_REAL ? "continuous" : "discrete", v->type == CDF_REAL ? "Real" : "Integer");
        sb_printf(&x, "    </ScalarVariable>\n");
    }
    for (i = 0; i < nparam; i++) {
        const char *eq = strchr(params[i], '=');
        char num[CLI_NUM];
        double val;
        (void)cli_number(eq + 1, &val);
        sb_printf(&x, "    <ScalarVariable name=\"");
        sb_printf(&x, "%.*s", (int)(eq - params[i]), params[i]);
        sb_printf(&x, "\" valueReference=\"%d\" description=\"scenario key (docs/scenario-format.md)\" "
                      "causality=\"parameter\" variability=\"fixed\" initial=\"exact\">\n      <Real start=\"%s\"/>\n"
                      "    </ScalarVariable>\n", nvar + i, cli_fmt_num(num, val));
    }
    sb_printf(&x, "  </ModelVariables>\n  <ModelStructure>\n");
    {
        int idx = 0, nouts = 0;
        for (j = 0; j < nvar; j++) if (sel[j] && vars[j].causality == CDF_OUTPUT) nouts++;
        if (nouts) {
            sb_printf(&x, "    <Outputs>\n");
            for (j = 0, idx = 0; j < nvar; j++) {
                if (!sel[j]) continue;
                idx++;
                if (vars[j].causality == CDF_OUTPUT) sb_printf(&x, "      <Unknown index=\"%d\"/>\n", idx);
            }
            sb_printf(&x, "    </Outputs>\n    <InitialUnknowns>\n");
            for (j = 0, idx = 0; j < nvar; j++) {
                if (!sel[j]) continue;
                idx++;
                if (vars[j].causality == CDF_OUTPUT) sb_printf(&x, "      <Unknown index=\"%d\"/>\n", idx);
            }
            sb_printf(&x, "    </InitialUnknowns>\n");
        }
    }
    sb_printf(&x, "  </ModelStructure>\n</fmiModelDescription>\n");
    if (x.oom) { cli_error("out of memory"); goto done; }

    {
        cdz_entry *e2 = (cdz_entry *)realloc(ent, (size_t)(nbin + 3) * sizeof *e2);
        if (!e2) { cli_error("out of memory"); goto done; }
        ent = e2;
    }
    /* modelDescription.xml first, then the binaries, then the resources */
    memmove(ent + 1, ent, (size_t)nbin * sizeof *ent);
    ent[0].name = "modelDescription.xml";
    ent[0].data = (const unsigned char *)x.s;
    ent[0].size = x.n;
    ent[0].executable = 0;
    nent = nbin + 1;
    ent[nent].name = "resources/scenario.toml";
    ent[nent].data = text;
    ent[nent].size = ntext;
    ent[nent].executable = 0;
    nent++;
    ent[nent].name = "resources/params.txt";
    ent[nent].data = (const unsigned char *)(pt.s ? pt.s : "");
    ent[nent].size = pt.n;
    ent[nent].executable = 0;
    nent++;
    if (cdz_write(out, ent, nent, msg, sizeof msg) != 0) { cli_error("%s", msg); goto done; }
    {
        int ni = 0, no = 0;
        for (j = 0; j < nvar; j++) if (sel[j]) { if (vars[j].causality == CDF_INPUT) ni++; else no++; }
        printf("%s: FMI 2.0 co-simulation FMU of '%s': %d input%s, %d output%s, %d parameter%s\n", out,
               sc->title ? sc->title : scenario, ni, ni == 1 ? "" : "s", no, no == 1 ? "" : "s", nparam,
               nparam == 1 ? "" : "s");
    }
    rc = CLI_OK;
done:
    if (dh) closedir(dh);
    for (i = 0; i < nbin; i++) { free(bins[i]); free(binnames[i]); }
    free(bins);
    free(binnames);
    free(ent);
    free(x.s);
    free(pt.s);
    free(text);
    free(sel);
    free(vars);
    cd_data_free(d);
    cd_scenario_free(sc);
    free(inputs);
    free(outputs);
    free(params);
    free(sets);
    free(ov);
    return rc;
}
