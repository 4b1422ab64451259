/* The FMI 2.0 co-simulation wrapper of a capdyn scenario (docs/fmu.md).
 *
 * Built into build/fmu/linux64/capdyn_fmu.so (Makefile, "FMU") against
 * libcapdyn_io.a and libcapdyn.a, GSL linked in statically; `capdyn fmu`
 * zips it with a generated modelDescription.xml and the scenario. The
 * FMI headers come from the installed fmpy package at build time.
 *
 * fmi2Instantiate loads resources/scenario.toml (with resources/params.txt:
 * one KEY=VALUE per --param, the parameters' start values) through
 * cd_scenario_load and cd_scenario_setup (io.h), the code path of
 * `capdyn run`; parameters set before fmi2ExitInitializationMode reload it
 * with their values as overrides. fmi2DoStep advances with cd_sim_advance
 * to the end of the communication step (adaptive steps, every event located
 * inside), then lets the capture monitor look at the state, as capdyn run
 * does at every output sample. Nothing prints or exits: errors go to the
 * importer's logger with fmi2Error (fmi2Fatal only when the instance cannot
 * be trusted any more). GSL's error handler is turned off at instantiation:
 * GSL is linked statically with hidden symbols, so that handler is this
 * library's own copy, not the importer's. */
#define _POSIX_C_SOURCE 200809L
#include "fmi2Functions.h"
#include "vars.h"

#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef enum { ST_INSTANTIATED, ST_INIT, ST_STEPPING, ST_ERROR, ST_TERMINATED } inst_state;

typedef struct {
    fmi2CallbackFunctions cb;
    char *name;
    char *scenario;        /* path of resources/scenario.toml */
    int loggingOn;
    inst_state state;
    /* parameters: --param keys and their values (start and current) */
    int nset;
    char **sets;           /* the --set values of capdyn fmu (KEY=VALUE), fixed */
    int nparam;
    char **pkey;
    double *pstart, *pval;
    int pdirty;
    /* the run */
    cd_scenario *sc;
    cd_data *d;
    cd_ctrl *ctl;
    cd_monitor mon;
    int have_mon;
    cdf_var *vars;
    int nvar;
    double *in;            /* (nvar) input values (0 for other variables) */
    size_t ns, nc;         /* cd_state_size, cd_ctrl_state_size */
} inst;

/* an FMU state: the data's and the controller's state, the monitor, the inputs */
typedef struct {
    double *buf;           /* ns + nc + nvar */
    cd_monitor mon;
    inst_state state;
} fmu_state;

static void logmsg(inst *c, fmi2Status st, const char *fmt, ...)
{
    char msg[1200], esc[2400];
    size_t i, k = 0;
    va_list ap;
    if (!c->cb.logger) return;
    if (st == fmi2OK && !c->loggingOn) return;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    /* the message is the logger's format string, with no arguments: every
     * '%' doubled (an importer's logger without varargs, e.g. through
     * ctypes, then still shows the text as it is) */
    for (i = 0; msg[i] && k + 2 < sizeof esc; i++) {
        if (msg[i] == '%') esc[k++] = '%';
        esc[k++] = msg[i];
    }
    esc[k] = 0;
    c->cb.logger(c->cb.componentEnvironment, c->name ? c->name : "capdyn", st,
                 st == fmi2OK ? "logAll" : "logStatusError", esc);
}

static fmi2Status fail(inst *c, fmi2Status st, const char *fmt, ...)
{
    char msg[1200];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    logmsg(c, st, "%s", msg);
    if (st == fmi2Fatal || st == fmi2Error) c->state = ST_ERROR;
    return st;
}

static char *dupstr(const char *s)
{
    size_t n = strlen(s) + 1;
    char *r = (char *)malloc(n);
    if (r) memcpy(r, s, n);
    return r;
}

static void free_run(inst *c)
{
    cd_data_free(c->d);
    cd_ctrl_free(c->ctl);
    cd_scenario_free(c->sc);
    free(c->vars);
    free(c->in);
    c->d = NULL;
    c->ctl = NULL;
    c->sc = NULL;
    c->vars = NULL;
    c->in = NULL;
    c->nvar = 0;
}

/* Loads the scenario with the current parameter values and sets up the run
 * as capdyn run does. 0, or -1 after logging why (the previous run kept). */
static int load_run(inst *c)
{
    char **ov = NULL;
    cd_error err;
    cd_scenario *sc;
    cd_data *d = NULL;
    cd_ctrl *ctl = NULL;
    cdf_var *vars = NULL;
    double *in;
    int i, nvar = 0;
    if (c->nset + c->nparam) {
        ov = (char **)calloc((size_t)(c->nset + c->nparam), sizeof *ov);
        if (!ov) { fail(c, fmi2Error, "out of memory"); return -1; }
        for (i = 0; i < c->nset; i++)
            if (!(ov[i] = dupstr(c->sets[i]))) break;
        for (; i >= c->nset && i < c->nset + c->nparam; i++) {
            size_t n = strlen(c->pkey[i - c->nset]) + 40;
            ov[i] = (char *)malloc(n);
            if (!ov[i]) break;
            snprintf(ov[i], n, "%s=%.17g", c->pkey[i - c->nset], c->pval[i - c->nset]);
        }
        if (i < c->nset + c->nparam) {
            while (i-- > 0) free(ov[i]);
            free(ov);
            fail(c, fmi2Error, "out of memory");
            return -1;
        }
    }
    sc = cd_scenario_load(c->scenario, (const char *const *)ov, c->nset + c->nparam, &err);
    for (i = 0; i < c->nset + c->nparam; i++) free(ov[i]);
    free(ov);
    if (!sc) { fail(c, fmi2Error, "%s", err.msg); return -1; }
    if (cd_scenario_setup(sc, &d, &ctl, &err) != CD_OK) {
        cd_scenario_free(sc);
        fail(c, fmi2Error, "%s", err.msg);
        return -1;
    }
    if (cdf_vars_build(sc, d, &vars, &nvar, &err) != CD_OK || !(in = (double *)calloc((size_t)nvar + 1, sizeof *in))) {
        free(vars);
        cd_data_free(d);
        cd_ctrl_free(ctl);
        cd_scenario_free(sc);
        fail(c, fmi2Error, "out of memory");
        return -1;
    }
    free_run(c);
    c->sc = sc;
    c->d = d;
    c->ctl = ctl;
    c->vars = vars;
    c->nvar = nvar;
    c->in = in;
    c->ns = cd_state_size(sc->model);
    c->nc = ctl ? cd_ctrl_state_size(ctl) : 0;
    /* the capture monitor, as capdyn run: at the initial state */
    c->have_mon = 0;
    if (sc->capture_hand >= 0 && sc->capture_object >= 0) {
        cd_monitor_opts mop = cd_scenario_monitor_opts(sc);
        if (cd_monitor_init(&c->mon, sc->model, d, &mop, &err) != CD_OK)
            logmsg(c, fmi2Warning, "no capture verdict: %s", err.msg);
        else {
            cd_monitor_update(&c->mon, sc->model, d);
            c->have_mon = 1;
        }
    }
    c->pdirty = 0;
    return 0;
}

/* resources/params.txt (written by capdyn fmu): "set KEY=VALUE" lines (the
 * --set values, fixed) and "param KEY=VALUE" lines (the parameters and
 * their start values), in that order; 0 or -1 (logged) */
static int read_params(inst *c, const char *path)
{
    FILE *f = fopen(path, "r");
    char line[2048];
    if (!f) return fail(c, fmi2Error, "cannot read '%s' (resources/params.txt of the FMU)", path), -1;
    while (fgets(line, sizeof line, f)) {
        char *eq, *end, *kv;
        size_t l = strlen(line);
        int is_set;
        double v = 0;
        while (l && (line[l - 1] == '\n' || line[l - 1] == '\r')) line[--l] = 0;
        if (!l) continue;
        is_set = !strncmp(line, "set ", 4);
        kv = is_set ? line + 4 : !strncmp(line, "param ", 6) ? line + 6 : NULL;
        eq = kv ? strchr(kv, '=') : NULL;
        if (!eq) { fclose(f); fail(c, fmi2Error, "%s: line '%s': expected 'set KEY=VALUE' or 'param KEY=VALUE'", path, line); return -1; }
        if (!is_set) {
            v = strtod(eq + 1, &end);
            if (end == eq + 1 || *end || !isfinite(v)) { fclose(f); fail(c, fmi2Error, "%s: parameter '%s': not a finite number", path, kv); return -1; }
        }
        if (is_set) {
            char **s2 = (char **)realloc(c->sets, (size_t)(c->nset + 1) * sizeof *s2);
            if (s2) c->sets = s2;
            if (!s2 || !(c->sets[c->nset] = dupstr(kv))) { fclose(f); fail(c, fmi2Error, "out of memory"); return -1; }
            c->nset++;
        } else {
            int n = c->nparam;
            char **k2 = (char **)realloc(c->pkey, (size_t)(n + 1) * sizeof *k2);
            double *s2, *v2;
            if (k2) c->pkey = k2;
            s2 = (double *)realloc(c->pstart, (size_t)(n + 1) * sizeof *s2);
            if (s2) c->pstart = s2;
            v2 = (double *)realloc(c->pval, (size_t)(n + 1) * sizeof *v2);
            if (v2) c->pval = v2;
            *eq = 0;
            if (!k2 || !s2 || !v2 || !(c->pkey[n] = dupstr(kv))) { fclose(f); fail(c, fmi2Error, "out of memory"); return -1; }
            c->pstart[n] = c->pval[n] = v;
            c->nparam = n + 1;
        }
    }
    fclose(f);
    return 0;
}

/* file:///a/b or file:/a/b (RFC 8089, as importers write it) -> /a/b, %XX decoded */
static char *uri_to_path(const char *uri)
{
    const char *p = uri;
    char *out, *o;
    if (!strncmp(p, "file://", 7)) {
        p += 7;
        if (strncmp(p, "localhost/", 10) == 0) p += 9;
    } else if (!strncmp(p, "file:", 5))
        p += 5;
    out = o = (char *)malloc(strlen(p) + 1);
    if (!out) return NULL;
    for (; *p; p++) {
        if (*p == '%' && p[1] && p[2]) {
            char hex[3] = {p[1], p[2], 0};
            *o++ = (char)strtol(hex, NULL, 16);
            p += 2;
        } else
            *o++ = *p;
    }
    *o = 0;
    return out;
}

static void free_inst(inst *c)
{
    int i;
    if (!c) return;
    free_run(c);
    for (i = 0; i < c->nparam; i++) free(c->pkey[i]);
    free(c->pkey);
    for (i = 0; i < c->nset; i++) free(c->sets[i]);
    free(c->sets);
    free(c->pstart);
    free(c->pval);
    free(c->scenario);
    free(c->name);
    free(c);
}

/* ---- FMI 2.0 API ------------------------------------------------------- */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn)
{
    inst *c;
    char *dir, *path;
    size_t n;
    (void)fmuGUID;
    (void)visible;
    if (!functions) return NULL;
    c = (inst *)calloc(1, sizeof *c);
    if (!c) return NULL;
    c->cb = *functions;
    c->loggingOn = loggingOn;
    c->name = dupstr(instanceName ? instanceName : "capdyn");
    /* GSL's default handler aborts; this library's own copy is turned off */
    gsl_set_error_handler_off();
    if (fmuType != fmi2CoSimulation) {
        fail(c, fmi2Error, "capdyn FMUs are co-simulation FMUs only (fmi2CoSimulation)");
        free_inst(c);
        return NULL;
    }
    if (!fmuResourceLocation || !(dir = uri_to_path(fmuResourceLocation))) {
        fail(c, fmi2Error, "no fmuResourceLocation: the scenario is in the FMU's resources/");
        free_inst(c);
        return NULL;
    }
    n = strlen(dir) + 32;
    path = (char *)malloc(n);
    c->scenario = (char *)malloc(n);
    if (!path || !c->scenario) {
        free(dir);
        free(path);
        fail(c, fmi2Error, "out of memory");
        free_inst(c);
        return NULL;
    }
    snprintf(c->scenario, n, "%s%sscenario.toml", dir, dir[0] && dir[strlen(dir) - 1] == '/' ? "" : "/");
    snprintf(path, n, "%s%sparams.txt", dir, dir[0] && dir[strlen(dir) - 1] == '/' ? "" : "/");
    free(dir);
    if (read_params(c, path) != 0 || load_run(c) != 0) {
        free(path);
        free_inst(c);
        return NULL;
    }
    free(path);
    c->state = ST_INSTANTIATED;
    return c;
}

void fmi2FreeInstance(fmi2Component comp) { free_inst((inst *)comp); }

fmi2Status fmi2SetDebugLogging(fmi2Component comp, fmi2Boolean loggingOn, size_t n, const fmi2String cat[])
{
    inst *c = (inst *)comp;
    (void)n;
    (void)cat;
    if (!c) return fmi2Error;
    c->loggingOn = loggingOn;
    return fmi2OK;
}

fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    inst *c = (inst *)comp;
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (!c) return fmi2Error;
    if (c->state != ST_INSTANTIATED) return fail(c, fmi2Error, "fmi2SetupExperiment: only after fmi2Instantiate");
    /* the scenario's tolerances (simulation.rtol, atol) are the model's: an
     * importer's tolerance is not applied (docs/fmu.md, "Limits") */
    if (startTime != 0.0) return fail(c, fmi2Error, "fmi2SetupExperiment: startTime %g: a scenario starts at t = 0", startTime);
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component comp)
{
    inst *c = (inst *)comp;
    if (!c) return fmi2Error;
    if (c->state != ST_INSTANTIATED) return fail(c, fmi2Error, "fmi2EnterInitializationMode: not after fmi2Instantiate");
    c->state = ST_INIT;
    return fmi2OK;
}

/* writes the inputs into the data (only there: the integrator restarts at
 * a call boundary where an input changed) */
static void apply_inputs(inst *c)
{
    int i;
    for (i = 0; i < c->nvar; i++) {
        const cdf_var *v = &c->vars[i];
        if (v->causality != CDF_INPUT) continue;
        if (v->what == CDF_IN_QFRC) c->d->qfrc_applied[v->a] = c->in[i];
        else if (v->what == CDF_IN_XFRC) c->d->xfrc_applied[v->a] = c->in[i];
        else if (v->what == CDF_IN_CTRL) c->d->ctrl[v->a] = c->in[i];
    }
}

fmi2Status fmi2ExitInitializationMode(fmi2Component comp)
{
    inst *c = (inst *)comp;
    double *keep;
    if (!c) return fmi2Error;
    if (c->state != ST_INIT) return fail(c, fmi2Error, "fmi2ExitInitializationMode: not in initialization mode");
    if (c->pdirty) { /* parameters changed: the scenario with their values, inputs kept */
        int nvar = c->nvar;
        keep = (double *)malloc(((size_t)nvar + 1) * sizeof *keep);
        if (!keep) return fail(c, fmi2Error, "out of memory");
        memcpy(keep, c->in, (size_t)nvar * sizeof *keep);
        if (load_run(c) != 0) {
            free(keep);
            return fmi2Error;
        }
        if (c->nvar == nvar) memcpy(c->in, keep, (size_t)nvar * sizeof *keep);
        free(keep);
    }
    apply_inputs(c);
    c->state = ST_STEPPING;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component comp)
{
    inst *c = (inst *)comp;
    if (!c) return fmi2Error;
    c->state = ST_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component comp)
{
    inst *c = (inst *)comp;
    if (!c) return fmi2Error;
    /* as after fmi2Instantiate: the parameters' start values, the initial state */
    if (c->nparam) memcpy(c->pval, c->pstart, (size_t)c->nparam * sizeof *c->pval);
    if (load_run(c) != 0) return fmi2Error;
    c->state = ST_INSTANTIATED;
    return fmi2OK;
}

static int check_vr(inst *c, const char *fn, fmi2ValueReference vr)
{
    if (vr < (fmi2ValueReference)(c->nvar + c->nparam)) return 0;
    fail(c, fmi2Error, "%s: unknown value reference %u", fn, (unsigned)vr);
    return -1;
}

static double obj_fn(const inst *c, int obj, int *nstick, int *nslip)
{
    const cd_model *m = c->sc->model;
    double s = 0;
    int k;
    *nstick = *nslip = 0;
    for (k = 0; k < m->nslot; k++) {
        int ba = m->cp_body[m->slot_cp[k]], bb = m->shape_body[m->slot_shape[k]];
        if (m->body_sys[ba] != obj && m->body_sys[bb] != obj) continue;
        s += c->d->slot_fn[k];
        if (c->d->slot_mode[k] == CD_MODE_STICK) (*nstick)++;
        else if (c->d->slot_mode[k] == CD_MODE_SLIP) (*nslip)++;
    }
    return s;
}

fmi2Status fmi2GetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[])
{
    inst *c = (inst *)comp;
    size_t i;
    int ns, nl;
    if (!c) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        const cdf_var *v;
        if (check_vr(c, "fmi2GetReal", vr[i])) return fmi2Error;
        if ((int)vr[i] >= c->nvar) { value[i] = c->pval[vr[i] - (fmi2ValueReference)c->nvar]; continue; }
        v = &c->vars[vr[i]];
        if (v->type != CDF_REAL) return fail(c, fmi2Error, "fmi2GetReal: '%s' is an Integer", v->name);
        switch (v->what) {
        case CDF_Y: value[i] = c->d->y[v->a]; break;
        case CDF_FN_OBJECT: value[i] = obj_fn(c, v->a, &ns, &nl); break;
        case CDF_VERDICT_T:
            value[i] = !c->have_mon ? -1.0 : c->mon.verdict == CD_VERDICT_CAPTURED ? c->mon.t_capture
                     : c->mon.verdict == CD_VERDICT_ESCAPED ? c->mon.t_escape
                     : c->mon.verdict == CD_VERDICT_CAGED ? c->mon.t_cage : -1.0;
            break;
        default: value[i] = c->in[vr[i]]; break; /* an input */
        }
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[])
{
    inst *c = (inst *)comp;
    size_t i;
    int ns, nl;
    if (!c) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        const cdf_var *v;
        if (check_vr(c, "fmi2GetInteger", vr[i])) return fmi2Error;
        if ((int)vr[i] >= c->nvar || c->vars[vr[i]].type != CDF_INTEGER)
            return fail(c, fmi2Error, "fmi2GetInteger: value reference %u is not an Integer", (unsigned)vr[i]);
        v = &c->vars[vr[i]];
        if (v->what == CDF_VERDICT) value[i] = c->have_mon ? (fmi2Integer)c->mon.verdict : 0;
        else {
            (void)obj_fn(c, v->a, &ns, &nl);
            value[i] = v->what == CDF_N_STICK ? ns : nl;
        }
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[])
{
    inst *c = (inst *)comp;
    size_t i;
    if (!c) return fmi2Error;
    if (c->state == ST_ERROR || c->state == ST_TERMINATED) return fail(c, fmi2Error, "fmi2SetReal: the instance is not running");
    for (i = 0; i < nvr; i++) if (check_vr(c, "fmi2SetReal", vr[i])) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        if (!isfinite(value[i]))
            return fail(c, fmi2Error, "fmi2SetReal: value reference %u: %g is not finite", (unsigned)vr[i], value[i]);
        if ((int)vr[i] >= c->nvar) {
            int p = (int)vr[i] - c->nvar;
            if (c->state != ST_INSTANTIATED && c->state != ST_INIT)
                return fail(c, fmi2Error, "fmi2SetReal: parameter '%s' is fixed: set it before fmi2ExitInitializationMode", c->pkey[p]);
            continue;
        }
        if (c->vars[vr[i]].causality != CDF_INPUT)
            return fail(c, fmi2Error, "fmi2SetReal: '%s' is not an input", c->vars[vr[i]].name);
    }
    for (i = 0; i < nvr; i++) {
        if ((int)vr[i] >= c->nvar) {
            int p = (int)vr[i] - c->nvar;
            if (c->pval[p] != value[i]) c->pdirty = 1;
            c->pval[p] = value[i];
        } else
            c->in[vr[i]] = value[i];
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[])
{
    inst *c = (inst *)comp;
    (void)value;
    if (!c) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    return fail(c, fmi2Error, "fmi2SetInteger: value reference %u: a capdyn FMU has no Integer input or parameter", (unsigned)vr[0]);
}

fmi2Status fmi2GetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[])
{
    inst *c = (inst *)comp;
    (void)value;
    if (!c) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    return fail(c, fmi2Error, "fmi2GetBoolean: value reference %u: a capdyn FMU has no Boolean variable", (unsigned)vr[0]);
}
fmi2Status fmi2SetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[])
{
    (void)value;
    return fmi2GetBoolean(comp, vr, nvr, NULL);
}
fmi2Status fmi2GetString(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, fmi2String value[])
{
    inst *c = (inst *)comp;
    (void)value;
    if (!c) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    return fail(c, fmi2Error, "fmi2GetString: value reference %u: a capdyn FMU has no String variable", (unsigned)vr[0]);
}
fmi2Status fmi2SetString(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[])
{
    (void)value;
    return fmi2GetString(comp, vr, nvr, NULL);
}

/* ---- the step ---------------------------------------------------------- */

fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real t0, fmi2Real h, fmi2Boolean noSetPrior)
{
    inst *c = (inst *)comp;
    cd_error err;
    cd_status st;
    double t1;
    (void)noSetPrior;
    if (!c) return fmi2Error;
    if (c->state != ST_STEPPING) return fail(c, fmi2Error, "fmi2DoStep: not in step mode (after fmi2ExitInitializationMode)");
    if (!(h >= 0) || !isfinite(h)) return fail(c, fmi2Error, "fmi2DoStep: communication step size %g: must be >= 0 and finite", h);
    /* the importer's clock must be the FMU's: no rollback but fmi2SetFMUstate */
    if (fabs(t0 - c->d->t) > 1e-9 * (1.0 + fabs(t0)))
        return fail(c, fmi2Error, "fmi2DoStep: currentCommunicationPoint %.17g is not the FMU's time %.17g", t0, c->d->t);
    t1 = t0 + h;
    apply_inputs(c);
    st = cd_sim_advance(c->sc->model, c->d, t1, NULL, NULL, &err);
    if (st != CD_OK) return fail(c, fmi2Error, "fmi2DoStep from t = %.9g s: %s: %s", t0, cd_status_string(st), err.msg);
    if (c->have_mon) cd_monitor_update(&c->mon, c->sc->model, c->d);
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component comp)
{
    inst *c = (inst *)comp;
    if (!c) return fmi2Error;
    return fail(c, fmi2Error, "fmi2CancelStep: fmi2DoStep always returns when done (no asynchronous steps)");
}

static fmi2Status no_status(fmi2Component comp, const char *fn)
{
    inst *c = (inst *)comp;
    if (!c) return fmi2Error;
    return fail(c, fmi2Discard, "%s: no asynchronous steps, no status to report", fn);
}
fmi2Status fmi2GetStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Status *value)
{
    (void)s;
    (void)value;
    return no_status(comp, "fmi2GetStatus");
}
fmi2Status fmi2GetRealStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Real *value)
{
    inst *c = (inst *)comp;
    if (c && s == fmi2LastSuccessfulTime) {
        *value = c->d->t;
        return fmi2OK;
    }
    return no_status(comp, "fmi2GetRealStatus");
}
fmi2Status fmi2GetIntegerStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)s;
    (void)value;
    return no_status(comp, "fmi2GetIntegerStatus");
}
fmi2Status fmi2GetBooleanStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Boolean *value)
{
    (void)s;
    (void)value;
    return no_status(comp, "fmi2GetBooleanStatus");
}
fmi2Status fmi2GetStringStatus(fmi2Component comp, const fmi2StatusKind s, fmi2String *value)
{
    (void)s;
    (void)value;
    return no_status(comp, "fmi2GetStringStatus");
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    inst *c = (inst *)comp;
    (void)vr; (void)nvr; (void)order; (void)value;
    if (!c) return fmi2Error;
    return fail(c, fmi2Error, "fmi2SetRealInputDerivatives: inputs are held constant over a step (canInterpolateInputs false)");
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[])
{
    inst *c = (inst *)comp;
    (void)vr; (void)nvr; (void)order; (void)value;
    if (!c) return fmi2Error;
    return fail(c, fmi2Error, "fmi2GetRealOutputDerivatives: not provided (maxOutputDerivativeOrder 0)");
}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component comp, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference z[], size_t nz, const fmi2Real dv[], fmi2Real dz[])
{
    inst *c = (inst *)comp;
    (void)u; (void)nu; (void)z; (void)nz; (void)dv; (void)dz;
    if (!c) return fmi2Error;
    return fail(c, fmi2Error, "fmi2GetDirectionalDerivative: not provided");
}

/* ---- FMU state: cd_state_get/set and cd_ctrl_state_get/set --------------- */

fmi2Status fmi2GetFMUstate(fmi2Component comp, fmi2FMUstate *FMUstate)
{
    inst *c = (inst *)comp;
    fmu_state *s;
    if (!c || !FMUstate) return fmi2Error;
    if (c->state == ST_ERROR) return fail(c, fmi2Error, "fmi2GetFMUstate: the instance is in an error state");
    s = (fmu_state *)*FMUstate;
    if (!s) {
        s = (fmu_state *)calloc(1, sizeof *s);
        if (s) s->buf = (double *)malloc((c->ns + c->nc + (size_t)c->nvar + 1) * sizeof(double));
        if (!s || !s->buf) {
            if (s) free(s);
            return fail(c, fmi2Error, "fmi2GetFMUstate: out of memory");
        }
    }
    cd_state_get(c->sc->model, c->d, s->buf);
    if (c->ctl) cd_ctrl_state_get(c->ctl, s->buf + c->ns);
    memcpy(s->buf + c->ns + c->nc, c->in, (size_t)c->nvar * sizeof(double));
    s->mon = c->mon;
    s->state = c->state;
    *FMUstate = s;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component comp, fmi2FMUstate FMUstate)
{
    inst *c = (inst *)comp;
    fmu_state *s = (fmu_state *)FMUstate;
    cd_error err;
    double *undo;
    if (!c) return fmi2Error;
    if (!s) return fail(c, fmi2Error, "fmi2SetFMUstate: no state");
    /* the controller's memory is checked first: on failure nothing changed */
    undo = c->ctl ? (double *)malloc((c->nc + 1) * sizeof(double)) : NULL;
    if (c->ctl && !undo) return fail(c, fmi2Error, "fmi2SetFMUstate: out of memory");
    if (c->ctl) {
        cd_ctrl_state_get(c->ctl, undo);
        if (cd_ctrl_state_set(c->ctl, s->buf + c->ns, &err) != CD_OK) {
            free(undo);
            return fail(c, fmi2Error, "fmi2SetFMUstate: %s", err.msg);
        }
    }
    if (cd_state_set(c->sc->model, c->d, s->buf, &err) != CD_OK) {
        if (c->ctl) (void)cd_ctrl_state_set(c->ctl, undo, NULL);
        free(undo);
        return fail(c, fmi2Error, "fmi2SetFMUstate: %s", err.msg);
    }
    free(undo);
    memcpy(c->in, s->buf + c->ns + c->nc, (size_t)c->nvar * sizeof(double));
    c->mon = s->mon;
    c->state = s->state;
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component comp, fmi2FMUstate *FMUstate)
{
    fmu_state *s;
    (void)comp;
    if (!FMUstate) return fmi2OK;
    s = (fmu_state *)*FMUstate;
    if (s) {
        free(s->buf);
        free(s);
    }
    *FMUstate = NULL;
    return fmi2OK;
}

/* Serialized: a header of 8 doubles (magic, version, ns, nc, nvar, state,
 * sizeof(cd_monitor), 0), the state doubles, then the monitor's bytes.
 * Valid in builds of the same capdyn version and platform only. */
#define SER_MAGIC 4.0710e9 /* "capdyn FMU state" */
#define SER_HEAD 8

static size_t ser_size(const inst *c)
{
    return (SER_HEAD + c->ns + c->nc + (size_t)c->nvar) * sizeof(double) + sizeof(cd_monitor);
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component comp, fmi2FMUstate FMUstate, size_t *size)
{
    inst *c = (inst *)comp;
    (void)FMUstate;
    if (!c || !size) return fmi2Error;
    *size = ser_size(c);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component comp, fmi2FMUstate FMUstate, fmi2Byte bytes[], size_t size)
{
    inst *c = (inst *)comp;
    fmu_state *s = (fmu_state *)FMUstate;
    double head[SER_HEAD] = {0};
    size_t nd;
    if (!c) return fmi2Error;
    if (!s || !bytes) return fail(c, fmi2Error, "fmi2SerializeFMUstate: no state or no buffer");
    if (size < ser_size(c)) return fail(c, fmi2Error, "fmi2SerializeFMUstate: buffer of %lu bytes, %lu needed",
                                        (unsigned long)size, (unsigned long)ser_size(c));
    nd = c->ns + c->nc + (size_t)c->nvar;
    head[0] = SER_MAGIC;
    head[1] = 1;
    head[2] = (double)c->ns;
    head[3] = (double)c->nc;
    head[4] = (double)c->nvar;
    head[5] = (double)s->state;
    head[6] = (double)sizeof(cd_monitor);
    memcpy(bytes, head, sizeof head);
    memcpy(bytes + sizeof head, s->buf, nd * sizeof(double));
    memcpy(bytes + sizeof head + nd * sizeof(double), &s->mon, sizeof s->mon);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component comp, const fmi2Byte bytes[], size_t size, fmi2FMUstate *FMUstate)
{
    inst *c = (inst *)comp;
    double head[SER_HEAD];
    fmu_state *s;
    size_t nd;
    if (!c || !FMUstate) return fmi2Error;
    if (!bytes || size != ser_size(c)) return fail(c, fmi2Error, "fmi2DeSerializeFMUstate: %lu bytes, a state of this FMU has %lu",
                                                  (unsigned long)size, (unsigned long)ser_size(c));
    memcpy(head, bytes, sizeof head);
    if (head[0] != SER_MAGIC || head[1] != 1 || head[2] != (double)c->ns || head[3] != (double)c->nc ||
        head[4] != (double)c->nvar || head[6] != (double)sizeof(cd_monitor) || !(head[5] >= 0 && head[5] <= ST_TERMINATED))
        return fail(c, fmi2Error, "fmi2DeSerializeFMUstate: not a serialized state of this FMU (header)");
    nd = c->ns + c->nc + (size_t)c->nvar;
    s = (fmu_state *)calloc(1, sizeof *s);
    if (s) s->buf = (double *)malloc((nd + 1) * sizeof(double));
    if (!s || !s->buf) {
        if (s) free(s);
        return fail(c, fmi2Error, "fmi2DeSerializeFMUstate: out of memory");
    }
    memcpy(s->buf, bytes + sizeof head, nd * sizeof(double));
    memcpy(&s->mon, bytes + sizeof head + nd * sizeof(double), sizeof s->mon);
    s->state = (inst_state)(int)head[5];
    if (*FMUstate) fmi2FreeFMUstate(comp, FMUstate);
    *FMUstate = s;
    return fmi2OK;
}
