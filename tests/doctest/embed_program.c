/* Harness for a C snippet of docs/embedding.md that is a whole program or a
 * file-scope fragment (tests/doctest/run.sh: <!-- doctest c embed_program -->):
 * its definitions and its remaining lines both at file scope, then (unless
 * the snippet has its own main) an empty main. */
#include <capdyn/capdyn.h>
#include SNIP_DEFS
#include SNIP_BODY
#ifndef SNIP_HAS_MAIN
int main(void)
{
    return 0;
}
#endif
