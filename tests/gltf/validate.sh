#!/usr/bin/env bash
# The glTF export against the Khronos glTF validator (npm gltf-validator):
# exports the user scenario of the plot tests (sphere, capsule, check points,
# links) and two shipped scenarios cut short (a convex-hull object; a plane)
# and fails if the validator reports any error. Run by `make gltf-test`
# (part of `make test`).
#
# The validator is installed into $BUILD/npm (npm install --prefix), once.
# Without node/npm it tries scripts/install-deps.sh with
# CAPDYN_EXTRA_PKGS="nodejs npm"; if they are still missing it says so and
# skips (exit 0): the pygltflib read-back test (python/tests/test_gltf.py)
# still checks the file.
set -euo pipefail
cd "$(dirname "$0")/../.."
BUILD=${BUILD:-build}
CAPDYN=${CAPDYN:-$BUILD/capdyn}
VALIDATOR_VERSION=2.0.0-dev.3.10
if ! command -v node > /dev/null || ! command -v npm > /dev/null; then
    echo "gltf-test: node/npm missing: installing them (scripts/install-deps.sh, CAPDYN_EXTRA_PKGS=\"nodejs npm\")"
    CAPDYN_EXTRA_PKGS="nodejs npm" bash scripts/install-deps.sh || true
fi
if ! command -v node > /dev/null || ! command -v npm > /dev/null; then
    echo "gltf-test: SKIPPED: node and npm are not available (the Khronos validator needs them)"
    exit 0
fi
V="$BUILD/npm/node_modules/gltf-validator"
if [ ! -f "$V/package.json" ] || ! grep -q "\"version\": \"$VALIDATOR_VERSION\"" "$V/package.json"; then
    echo "gltf-test: npm install --prefix $BUILD/npm gltf-validator@$VALIDATOR_VERSION"
    mkdir -p "$BUILD/npm"
    npm install --silent --no-audit --no-fund --prefix "$BUILD/npm" "gltf-validator@$VALIDATOR_VERSION" > /dev/null
fi
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
"$CAPDYN" run tests/plots/user_grasp.toml -q -o "$T/user.h5"
"$CAPDYN" run scenarios/space_gripper_irregular.toml --set simulation.duration=0.05 -q -o "$T/convex.h5"
"$CAPDYN" run scenarios/block_on_slope.toml --set simulation.duration=0.05 -q -o "$T/plane.h5"
for n in user convex plane; do "$CAPDYN" export "$T/$n.h5" gltf > "$T/$n.glb"; done
"$CAPDYN" export "$T/user.h5" gltf --frames 7 > "$T/user_frames.glb"
GLTF_VALIDATOR="$(cd "$V" && pwd)" node tests/gltf/validate.js "$T"/*.glb
