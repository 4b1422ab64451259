/* embed_run.c with one user switch reserved (the clutch snippet of
 * docs/embedding.md, whose cd_model_set_user_switches call, "before
 * cd_model_finalize", the harness makes in build()). */
#define HARNESS_NUSER 1
#include "embed_run.c"
