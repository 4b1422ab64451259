/* The run objects of a loaded scenario, made the way `capdyn run` makes
 * them (io.h, cd_scenario_setup): shared by the CLI and the FMU wrapper
 * (src/fmu/, docs/fmu.md) so that both simulate the same thing. */
#include "capdyn/io.h"

#include <stddef.h>

cd_status cd_scenario_setup(const cd_scenario *sc, cd_data **dp, cd_ctrl **ctlp, cd_error *err)
{
    cd_data *d;
    cd_ctrl *ctl = NULL;
    if (!sc || !dp || !ctlp) {
        cd_error_set(err, CD_EINVAL, "cd_scenario_setup: %s is NULL", !sc ? "the scenario" : !dp ? "dp" : "ctlp");
        return CD_EINVAL;
    }
    *dp = NULL;
    *ctlp = NULL;
    d = cd_data_create(sc->model, sc->event_capacity, err);
    if (!d) return err->status;
    /* the scenario's built-in controller ([control], docs/capture.md) */
    if (sc->control && !(ctl = cd_ctrl_create(sc->model, sc->control, err))) {
        cd_data_free(d);
        return err->status;
    }
    if (ctl) cd_ctrl_install(ctl, d);
    *dp = d;
    *ctlp = ctl;
    return CD_OK;
}
