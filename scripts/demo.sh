#!/usr/bin/env bash
# Builds weft and runs the demo: what exists so far, end to end. The engine trains a small
# network (weft demo), the synthetic studio writes a tiny multi-view dataset with
# ground-truth body and cloth (weft synth, configs/synth/tiny.yaml) into
# $WEFT_DEMO_OUT (default /tmp/weft_demo), and weft train runs the method's three stages
# on it (configs/train/tiny.yaml) and measures the result on its test frame.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/build.sh" >/dev/null
weft="${WEFT_BUILD_DIR:-$root/build}/apps/weft"
out=${WEFT_DEMO_OUT:-/tmp/weft_demo}
"$weft" demo "$@"
"$weft" synth --config "$root/configs/synth/tiny.yaml" --out "$out/tiny"
rm -rf "$out/run"
"$weft" train --config "$root/configs/train/tiny.yaml" --data "$out/tiny" --out "$out/run"
"$weft" train --config "$root/configs/train/tiny.yaml" --data "$out/tiny" --out "$out/run" --evaluate test
echo "dataset: $out/tiny (docs/DATASET.md); every view of one frame: $out/tiny/preview.png"
echo "training run: $out/run (docs/TRAINING.md); loss curves: $out/run/losses.png; metrics: $out/run/evaluation_test.json"
