#!/usr/bin/env bash
# The main job: the whole method end to end on a small studio, in about 15 minutes on two
# cores after the build.
#  1. weft synth writes a multi-view studio dataset with ground-truth body and cloth: 3 s of
#     a walk on the spot, 8 views (configs/synth/demo.yaml), and the second of the walk
#     after it, filmed by a moving camera over a green screen (configs/synth/demo_wild.yaml);
#  2. weft train runs the method's three stages and the person detector on the studio data
#     (configs/train/demo.yaml);
#  3. weft detect finds the person in the clip from its pixels alone (OpenPose JSON and PNG
#     masks) and measures them against the clip's truth (detection_accuracy.json);
#  4. weft infer captures the clip from its pixels alone (the model's own keypoints and
#     masks; no --keypoints, no keying): both networks, the temporal filter, meshes, pose
#     files and overlays;
#  5. weft eval measures the capture against the clip's ground truth and writes report.html.
# Everything goes to $WEFT_DEMO_OUT (default /tmp/weft_demo). WEFT_DEMO_CONFIG=tiny runs the
# seconds-long configs of the tests instead (configs/*/tiny*.yaml: every stage at work,
# nothing learnt; no detector, so the capture reads the clip's keypoints and keys its green screen).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/build.sh" >/dev/null
weft="${WEFT_BUILD_DIR:-$root/build}/apps/weft"
out=${WEFT_DEMO_OUT:-/tmp/weft_demo}
mkdir -p "$out"
case ${WEFT_DEMO_CONFIG:-demo} in
  demo) studio=demo clip=demo_wild train=demo ;;
  tiny) studio=tiny clip=tiny_wild train=tiny ;;
  *) echo "demo.sh: WEFT_DEMO_CONFIG is demo or tiny, not '$WEFT_DEMO_CONFIG'" >&2; exit 2 ;;
esac
t0=$SECONDS
"$weft" synth --config "$root/configs/synth/$studio.yaml" --out "$out/studio"
"$weft" synth --config "$root/configs/synth/$clip.yaml" --out "$out/clip"
rm -rf "$out/run" "$out/detect" "$out/capture" "$out/report"
"$weft" train --config "$root/configs/train/$train.yaml" --data "$out/studio" --out "$out/run"
if [ "$train" = demo ]; then
  "$weft" detect --model "$out/run" --input "$out/clip/images/wild" --truth "$out/clip" --overlays --out "$out/detect"
  "$weft" infer --model "$out/run" --input "$out/clip/images/wild" --camera "$out/clip/cameras.yaml" --out "$out/capture"
else
  "$weft" infer --model "$out/run" --input "$out/clip/images/wild" --camera "$out/clip/cameras.yaml" \
    --keypoints "$out/clip/keypoints/wild" --out "$out/capture"
fi
"$weft" eval --prediction "$out/capture" --data "$out/clip" --out "$out/report"
echo "done in $((SECONDS - t0)) s after the build"
echo "studio dataset: $out/studio (docs/DATASET.md); every view of one frame: $out/studio/preview.png"
echo "model: $out/run (docs/TRAINING.md); loss curves: $out/run/losses.png"
if [ "$train" = demo ]; then
  echo "the person found in the clip: $out/detect/keypoints, masks, overlays (docs/CAPTURE.md); accuracy: $out/detect/detection_accuracy.json"
fi
echo "capture of the clip: $out/capture (docs/CAPTURE.md); overlays: $out/capture/overlay.mp4"
echo "report: $out/report/report.html"
