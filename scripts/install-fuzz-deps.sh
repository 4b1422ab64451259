#!/usr/bin/env bash
# Installs what `make fuzz` needs: the build dependencies plus clang and
# libFuzzer's runtime (scripts/install-deps.sh --fuzz: Debian's clang and
# libclang-rt-dev), then checks that clang links a libFuzzer target with
# ASan and UBSan. Only `make fuzz` (and .ci/run through it) calls this. It
# fails loudly when they cannot be installed or do not work: the fuzzing
# step of CI must not be skipped silently.
# Usage: scripts/install-fuzz-deps.sh     (CAPDYN_NO_INSTALL=1 to only check)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh --fuzz

d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT
printf '#include <stdint.h>\n#include <stddef.h>\nint LLVMFuzzerTestOneInput(const uint8_t *d, size_t n);\nint LLVMFuzzerTestOneInput(const uint8_t *d, size_t n) { (void)d; (void)n; return 0; }\n' > "$d/t.c"
if ! clang -fsanitize=fuzzer,address,undefined "$d/t.c" -o "$d/t" 2> "$d/err"; then
  echo "install-fuzz-deps: clang cannot link a libFuzzer target:" >&2
  cat "$d/err" >&2
  exit 1
fi
