/* capdyn: contact dynamics of free-flying space robots (C99 core).
 * Include this header for the core library (libcapdyn.a). */
#ifndef CAPDYN_CAPDYN_H
#define CAPDYN_CAPDYN_H
#include "capdyn/model.h"
#include "capdyn/sim.h"
#include "capdyn/dynamics.h"
#endif
