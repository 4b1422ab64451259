#!/usr/bin/env bash
# Installs what `make MPI=1` (capdyn sweep under mpirun/srun, docs/sweep.md)
# needs on top of scripts/install-deps.sh: Open MPI's C library, headers and
# launcher from Debian (libopenmpi-dev, openmpi-bin). Never needed by the
# default build or `make test`. Idempotent; root or sudo.
# CAPDYN_NO_INSTALL=1 only checks.
set -euo pipefail
CAPDYN_EXTRA_PKGS="libopenmpi-dev openmpi-bin" exec bash "$(dirname "$0")/install-deps.sh"
