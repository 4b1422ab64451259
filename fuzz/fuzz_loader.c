/* libFuzzer target: the scenario loader with overrides (fuzz/fuzz_common.h).
 * Findings: any crash, sanitizer report, stack overflow at 256 KiB, leak,
 * or a failed load without a one-line message. */
#include "fuzz_common.h"

static void load(const char *path, const char *const *sets, int nsets)
{
    cd_error err;
    cd_scenario *sc = cd_scenario_load(path, sets, nsets, &err);
    if (!sc) {
        fuzz_check_error(&err);
        return;
    }
    if (!sc->model || !sc->model->finalized || !(sc->duration > 0) || !(sc->output_dt > 0)) {
        fprintf(stderr, "loaded scenario breaks its contract\n");
        abort();
    }
    cd_scenario_free(sc);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_run(data, size, load);
    return 0;
}
