#!/usr/bin/env bash
# Builds weft and runs the demo: what exists so far, end to end. The engine trains a small
# network (weft demo), then the synthetic studio writes a tiny multi-view dataset with
# ground-truth body and cloth (weft synth, configs/synth/tiny.yaml) into
# $WEFT_DEMO_OUT (default /tmp/weft_demo); look at its preview.png.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/build.sh" >/dev/null
weft="${WEFT_BUILD_DIR:-$root/build}/apps/weft"
out=${WEFT_DEMO_OUT:-/tmp/weft_demo}
"$weft" demo "$@"
"$weft" synth --config "$root/configs/synth/tiny.yaml" --out "$out/tiny"
echo "dataset: $out/tiny (docs/DATASET.md); every view of one frame: $out/tiny/preview.png"
