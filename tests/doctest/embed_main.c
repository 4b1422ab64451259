/* Harness for a C snippet of docs/embedding.md that is the body of a main
 * function (tests/doctest/run.sh: <!-- doctest c embed_main -->): it builds
 * its own model and data; it must return 0 or fall off the end. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <capdyn/capdyn.h>
#include SNIP_DEFS
int main(void)
{
#include SNIP_BODY
    return 0;
}
