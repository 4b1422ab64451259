/* embed_run.c with two user switches reserved (the cd_ctrl snippet of
 * docs/embedding.md: the controller's grasp trigger and hold; its
 * cd_model_set_user_switches call, "before cd_model_finalize", the harness
 * makes in build()). The chaser is the hand (system 0, a free base), the
 * palm its base body, the fixture the wall's body. */
#define HARNESS_NUSER 2
#include "embed_run.c"
