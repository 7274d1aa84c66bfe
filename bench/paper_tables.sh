#!/usr/bin/env bash
# The paper's tables on unseen motion (docs/RESULTS.md): the physics-aware model against the
# ARAP-only (DeepCap-like) one, trained for the same number of steps on the same data,
# each adapted to the test sequence, captured from one view and evaluated.
#
#   bench/paper_tables.sh [OUT=/tmp/weft_paper]
#
# Steps (each skipped when its output exists, so an interrupted run continues; measured
# durations on 2 cores in docs/RESULTS.md):
#  1. weft synth configs/synth/training_set_random_poses.yaml (the default's training set) → OUT/training_set
#  2. weft train configs/train/default.yaml                 → OUT/physics
#     weft train configs/train/default_arap_only.yaml       → OUT/arap_only
#  3. weft synth configs/synth/unseen_studio.yaml (CMU 01_03, unseen) → OUT/unseen
#  4. per model: weft adapt on the input view (ITERATIONS, default 300; 0 skips it),
#     weft infer on that view (keypoints from the sequence's OpenPose files, masks keyed,
#     the temporal filter on), weft eval against the sequence's ground truth (every view
#     for the IoUs) twice: with --gt-translation (the paper's protocol: every method gets
#     the true global translation) → OUT/<model>_report_gt, and without → OUT/<model>_report
#  5. bench/paper_tables.py → OUT/tables.md
# Environment: VIEW (default cam03), ITERATIONS, PHYSICS_RUN / ARAP_RUN (existing model
# folders to use instead of training), TRAINING_DATA (an existing training set).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
weft="${WEFT_BUILD_DIR:-$root/build}/apps/weft"
out=${1:-/tmp/weft_paper}
view=${VIEW:-cam03}
iterations=${ITERATIONS:-300}
mkdir -p "$out"
log() { echo "[$(date +%H:%M:%S)] $*" >&2; }
timed() { local t0=$SECONDS; "$@"; log "  took $((SECONDS - t0)) s"; }

data=${TRAINING_DATA:-$out/training_set}
if [ ! -f "$data/dataset.yaml" ]; then
  log "1. training set → $data"
  timed "$weft" synth --config "$root/configs/synth/training_set_random_poses.yaml" --out "$data"
fi
train() {  # name config
  local run=${!3:-$out/$1}
  if [ ! -f "$run/model.safetensors" ]; then
    log "2. weft train $2 → $run"
    local resume=()
    [ -d "$run/checkpoints" ] && resume=(--resume)
    timed "$weft" train --config "$root/$2" --data "$data" --out "$run" "${resume[@]}" >&2
  elif [ ! -f "$run/model.yaml" ]; then
    "$weft" train --config "$root/$2" --data "$data" --out "$run" --resume >&2  # writes the model folder
  fi
  echo "$run"
}
physics_run=$(train physics configs/train/default.yaml PHYSICS_RUN | tail -1)
arap_run=$(train arap_only configs/train/default_arap_only.yaml ARAP_RUN | tail -1)
if [ ! -f "$out/unseen/dataset.yaml" ]; then
  log "3. unseen test sequence → $out/unseen"
  timed "$weft" synth --config "$root/configs/synth/unseen_studio.yaml" --out "$out/unseen"
fi
input=(--input "$out/unseen/images/$view" --camera "$out/unseen/cameras.yaml" --camera-name "$view"
       --keypoints "$out/unseen/keypoints/$view")
for name in physics arap_only; do
  run=$physics_run
  [ "$name" = arap_only ] && run=$arap_run
  model=$run
  if [ "$iterations" -gt 0 ]; then
    model="$out/${name}_adapted"
    if [ ! -f "$model/model.safetensors" ]; then
      log "4. weft adapt $name ($iterations iterations per network) → $model"
      resume=()
      [ -d "$model/checkpoints" ] && resume=(--resume)
      timed "$weft" adapt --model "$run" "${input[@]}" --iterations "$iterations" --out "$model" "${resume[@]}"
    fi
  fi
  if [ ! -f "$out/${name}_capture/capture.json" ]; then
    log "4. weft infer $name → $out/${name}_capture"
    timed "$weft" infer --model "$model" "${input[@]}" --out "$out/${name}_capture"
  fi
  # The paper's protocol (the ground-truth global translation, after the temporal filter
  # weft infer applies by default), and the capture as it is.
  log "4. weft eval $name --gt-translation → $out/${name}_report_gt"
  timed "$weft" eval --prediction "$out/${name}_capture" --data "$out/unseen" --out "$out/${name}_report_gt" \
    --gt-translation
  log "4. weft eval $name → $out/${name}_report"
  timed "$weft" eval --prediction "$out/${name}_capture" --data "$out/unseen" --out "$out/${name}_report"
done
{
  /usr/bin/python3 "$root/bench/paper_tables.py" --physics "$out/physics_report_gt/metrics.json" \
    --arap "$out/arap_only_report_gt/metrics.json" \
    --title "Unseen motion (CMU 01_03), input view $view, the paper's protocol (ground-truth global translation)"
  echo
  /usr/bin/python3 "$root/bench/paper_tables.py" --physics "$out/physics_report/metrics.json" \
    --arap "$out/arap_only_report/metrics.json" \
    --title "Unseen motion (CMU 01_03), input view $view, the predicted global translation"
} | tee "$out/tables.md"
log "tables: $out/tables.md; reports: $out/{physics,arap_only}_report{,_gt}/report.html"
