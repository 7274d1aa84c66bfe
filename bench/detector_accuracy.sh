#!/usr/bin/env bash
# The person detector on the demo's clip (issue 39): how well weft finds the person's BODY_25
# keypoints and mask from the pixels alone, and what capturing from them costs against the
# capture from the clip's own keypoints and masks. docs/CAPTURE.md, "From pixels alone:
# measured", has the figures.
#
#   bench/detector_accuracy.sh OUT
#
# Environment (each made when missing):
#   STUDIO  the demo's studio (default OUT/studio, configs/synth/demo.yaml)
#   CLIP    the demo's clip (default OUT/clip, configs/synth/demo_wild.yaml)
#   RUN     a model trained by configs/train/demo.yaml (default OUT/run); with
#           DETECTOR_ONLY=1, RUN's detector is trained alone (the demo config with the
#           other stages at 0 steps: the same detector, seeds and batches) and POSE_RUN
#           (a demo model, possibly without a detector) captures from its detections.
# Writes OUT/detect (weft detect: keypoints/, masks/, detection_accuracy.json),
# OUT/labels_accuracy (the clip's own detections against the truth: the labels' noise),
# OUT/capture_truth, OUT/capture_pixels (weft infer from the clip's keypoints and masks,
# and from the detector's) and their reports.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
weft="${WEFT_BUILD_DIR:-$root/build}/apps/weft"
out=${1:?usage: bench/detector_accuracy.sh OUT}
studio=${STUDIO:-$out/studio}
clip=${CLIP:-$out/clip}
run=${RUN:-$out/run}
mkdir -p "$out"
log() { echo "[$(date +%H:%M:%S)] $*" >&2; }
timed() { local t0=$SECONDS; "$@"; log "  took $((SECONDS - t0)) s"; }
[ -f "$studio/dataset.yaml" ] || timed "$weft" synth --config "$root/configs/synth/demo.yaml" --out "$studio"
[ -f "$clip/dataset.yaml" ] || timed "$weft" synth --config "$root/configs/synth/demo_wild.yaml" --out "$clip"
config="$root/configs/train/demo.yaml"
if [ "${DETECTOR_ONLY:-0}" = 1 ]; then
  config="$out/demo_detector_only.yaml"
  sed -e 's/^  pose:    {steps: [0-9]*,/  pose:    {steps: 0,/' -e 's/^  warmup:  {steps: [0-9]*,/  warmup:  {steps: 0,/' \
      -e 's/^  physics: {steps: [0-9]*,/  physics: {steps: 0,/' "$root/configs/train/demo.yaml" > "$config"
fi
[ -f "$run/model.safetensors" ] || timed "$weft" train --config "$config" --data "$studio" --out "$run"
pose_run=${POSE_RUN:-$run}

log "the detector on the clip"
timed "$weft" detect --model "$run" --input "$clip/images/wild" --truth "$clip" --out "$out/detect"
mkdir -p "$out/labels"
ln -sfn "$(cd "$clip" && pwd)/keypoints/wild" "$out/labels/keypoints"
ln -sfn "$(cd "$clip" && pwd)/masks/wild" "$out/labels/masks"
"$weft" detect --measure "$out/labels" --truth "$clip" --out "$out/labels_accuracy"

log "captures: from the clip's keypoints and masks, and from the detector's"
timed "$weft" infer --model "$pose_run" --input "$clip/images/wild" --camera "$clip/cameras.yaml" \
  --keypoints "$clip/keypoints/wild" --masks "$clip/masks/wild" --out "$out/capture_truth"
if [ "$pose_run" = "$run" ]; then  # the model's own detector inside weft infer
  timed "$weft" infer --model "$run" --input "$clip/images/wild" --camera "$clip/cameras.yaml" --out "$out/capture_pixels"
else
  timed "$weft" infer --model "$pose_run" --input "$clip/images/wild" --camera "$clip/cameras.yaml" \
    --keypoints "$out/detect/keypoints" --masks "$out/detect/masks" --out "$out/capture_pixels"
fi
for c in truth pixels; do
  "$weft" eval --prediction "$out/capture_$c" --data "$clip" --out "$out/report_$c" > /dev/null
done
python3 - "$out" <<'PY'
import json, sys
out = sys.argv[1]
d = json.load(open(f"{out}/detect/detection_accuracy.json"))
l = json.load(open(f"{out}/labels_accuracy/detection_accuracy.json"))
print(f"detector: mask IoU median {d['mask_iou']['median']:.4f} (min {d['mask_iou']['min']:.4f}); keypoints vs truth "
      f"median {d['against_truth']['median_px']:.2f} px, PCK@5% {100 * d['against_truth']['pck']:.1f} %; "
      f"vs the clip's detections median {d['against_labels']['median_px']:.2f} px")
print(f"the clip's own detections vs truth: median {l['against_truth']['median_px']:.2f} px, "
      f"PCK@5% {100 * l['against_truth']['pck']:.1f} %")
for c in ("truth", "pixels"):
    s = json.load(open(f"{out}/report_{c}/metrics.json"))["summary"]
    print(f"capture from {c}: SVIoU {s['iou']['sv']:.4f}, body error {s['body_error_mm']['mean']:.1f} mm, "
          f"MPJPE {s['mpjpe_mm']:.1f} mm")
PY
