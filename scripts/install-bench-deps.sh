#!/usr/bin/env bash
# Installs what `make bench` needs on top of scripts/install-deps.sh: MuJoCo's
# C library and headers from Debian (libmujoco-dev, 2.2.2 on bookworm), for
# the side-by-side benchmark only (never needed by the library or the tests).
# Idempotent; root or sudo. CAPDYN_NO_INSTALL=1 only checks.
set -euo pipefail
CAPDYN_EXTRA_PKGS="libmujoco-dev" exec bash "$(dirname "$0")/install-deps.sh"
