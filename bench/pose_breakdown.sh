#!/usr/bin/env bash
# Where a model's pose error on unseen motion comes from (issue 38, "find where the error
# comes from"): one model captured on the unseen clip CMU 01_03 from its input view under
# the paper's protocol (--gt-translation, the temporal filter), then `weft eval
# --training-data` against the set it trained on: PA-MPJPE, the depth / image-plane split,
# the per-joint table, the distance of each test pose to the nearest training pose, and the
# two baselines (the mean training pose, the 2D retrieval). docs/RESULTS.md has the figures.
#
#   bench/pose_breakdown.sh OUT
#
# Environment (each made when missing, resumable step by step):
#   TRAINING_DATA  the training set (default OUT/training_set, from
#                  configs/synth/training_set_random_poses.yaml: ~50 min on 2 cores)
#   UNSEEN         the test clip (default OUT/unseen, configs/synth/unseen_studio.yaml)
#   CONFIG         the training config (default configs/train/default.yaml)
#   RUN            a trained model folder (default OUT/run, trained with CONFIG: ~30 min)
#   VIEW           the input view (default cam03)
# Writes OUT/capture (weft infer) and OUT/report (weft eval: report.html, metrics.json).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
weft="${WEFT_BUILD_DIR:-$root/build}/apps/weft"
out=${1:?usage: bench/pose_breakdown.sh OUT}
view=${VIEW:-cam03}
data=${TRAINING_DATA:-$out/training_set}
unseen=${UNSEEN:-$out/unseen}
config=${CONFIG:-$root/configs/train/default.yaml}
run=${RUN:-$out/run}
mkdir -p "$out"
log() { echo "[$(date +%H:%M:%S)] $*" >&2; }
timed() { local t0=$SECONDS; "$@"; log "  took $((SECONDS - t0)) s"; }

if [ ! -f "$data/dataset.yaml" ]; then
  log "training set → $data"
  timed "$weft" synth --config "$root/configs/synth/training_set_random_poses.yaml" --out "$data"
fi
if [ ! -f "$unseen/dataset.yaml" ]; then
  log "unseen clip → $unseen"
  timed "$weft" synth --config "$root/configs/synth/unseen_studio.yaml" --out "$unseen"
fi
if [ ! -f "$run/model.safetensors" ]; then
  log "weft train $config → $run"
  resume=()
  [ -d "$run/checkpoints" ] && resume=(--resume)
  timed "$weft" train --config "$config" --data "$data" --out "$run" "${resume[@]}"
fi
log "weft infer → $out/capture"
timed "$weft" infer --model "$run" --input "$unseen/images/$view" --camera "$unseen/cameras.yaml" \
  --camera-name "$view" --keypoints "$unseen/keypoints/$view" --out "$out/capture"
log "weft eval --gt-translation --training-data → $out/report"
timed "$weft" eval --prediction "$out/capture" --data "$unseen" --out "$out/report" --gt-translation \
  --training-data "$data"
