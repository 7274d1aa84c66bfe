#!/usr/bin/env bash
# Builds weft and runs the whole test suite with ctest. Extra arguments go to ctest,
# e.g. scripts/test.sh -L gradcheck. WEFT_SANITIZE=1 builds into build-sanitize/ with
# AddressSanitizer and UndefinedBehaviorSanitizer.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
if [ "${WEFT_SANITIZE:-0}" = 1 ]; then
  export WEFT_BUILD_DIR=${WEFT_BUILD_DIR:-$root/build-sanitize}
  WEFT_BUILD_DIR=$WEFT_BUILD_DIR "$root/scripts/build.sh" -DWEFT_SANITIZE=ON -DWEFT_BUILD_BENCH=OFF
else
  "$root/scripts/build.sh"
fi
build=${WEFT_BUILD_DIR:-$root/build}
cd "$build"
ctest --output-on-failure --timeout 600 -j"$(nproc)" "$@"
