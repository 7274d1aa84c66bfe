#!/usr/bin/env bash
# Builds weft and runs the demo: what exists so far, end to end.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/build.sh" >/dev/null
"${WEFT_BUILD_DIR:-$root/build}/apps/weft" demo "$@"
