#!/usr/bin/env bash
# The main job: the whole method on tiny data, end to end, in minutes on two cores.
#  1. weft synth writes a tiny multi-view studio dataset with ground-truth body and cloth
#     (configs/synth/tiny.yaml) and a short single-camera clip of motion it has not seen,
#     filmed by a moving camera over a green screen (configs/synth/tiny_wild.yaml);
#  2. weft train runs the method's three stages on the studio data (configs/train/tiny.yaml:
#     far too short to learn much; it shows every stage at work);
#  3. weft infer captures the clip: green-screen keying, both networks, the temporal
#     filter, meshes, pose files and overlays;
#  4. weft eval measures the capture against the clip's ground truth and writes report.html.
# Everything goes to $WEFT_DEMO_OUT (default /tmp/weft_demo).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/build.sh" >/dev/null
weft="${WEFT_BUILD_DIR:-$root/build}/apps/weft"
out=${WEFT_DEMO_OUT:-/tmp/weft_demo}
mkdir -p "$out"
"$weft" synth --config "$root/configs/synth/tiny.yaml" --out "$out/tiny"
"$weft" synth --config "$root/configs/synth/tiny_wild.yaml" --out "$out/clip"
rm -rf "$out/run" "$out/capture" "$out/report"
"$weft" train --config "$root/configs/train/tiny.yaml" --data "$out/tiny" --out "$out/run"
"$weft" infer --model "$out/run" --input "$out/clip/images/wild" --camera "$out/clip/cameras.yaml" \
  --keypoints "$out/clip/keypoints/wild" --out "$out/capture"
"$weft" eval --prediction "$out/capture" --data "$out/clip" --out "$out/report"
echo "studio dataset: $out/tiny (docs/DATASET.md); every view of one frame: $out/tiny/preview.png"
echo "model: $out/run (docs/TRAINING.md); loss curves: $out/run/losses.png"
echo "capture of the clip: $out/capture (docs/CAPTURE.md); overlays: $out/capture/overlay.mp4"
echo "report: $out/report/report.html"
