/* capdyn: contact dynamics of free-flying space robots (C99 core).
 * Include this header for the core library (libcapdyn.a): the model builder
 * (model.h), the simulation data and its state (data.h), kinematics, dynamics
 * and the integrator (sim.h), the builders of hands and targets (build.h). See docs/embedding.md. */
#ifndef CAPDYN_CAPDYN_H
#define CAPDYN_CAPDYN_H
#include "capdyn/model.h"
#include "capdyn/data.h"
#include "capdyn/sim.h"
#include "capdyn/dynamics.h"
#include "capdyn/control.h"
#include "capdyn/build.h"
#endif
