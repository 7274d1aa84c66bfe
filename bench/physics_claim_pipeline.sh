#!/usr/bin/env bash
# The physics claim in the full pipeline, as the paper measures it (its section 3.3.2:
# PoseNet fixed while L_sim trains PADefNet), on unseen motion:
#
#   bench/physics_claim.sh --pipeline OUT      (or this script directly, OUT as argument)
#
# 1. PoseNet: the default config's pose stage (configs/train/default.yaml) → OUT/pose, or
#    POSE_RUN (an existing run whose model.safetensors holds the networks to start from).
# 2. One warm start of PADefNet from it: default.yaml's warmup stage → OUT/warmup.
# 3. From that one model, per seed (1, 2, 3) the default physics stage in two arms with the
#    same steps on the same batches (the seed):
#      physics    default.yaml's physics stage (L_sim as Eq. 8 + ARAP)
#      arap_only  the same with the simulation weight 0
# 4. Each arm captures the unseen sequence (configs/synth/unseen_studio.yaml: CMU 01_03)
#    from the input view VIEW (default cam03) with weft infer (keypoints: the sequence's
#    detections, the detector error model of the synth config; masks keyed; the temporal
#    filter on) and weft eval measures it on every view under the paper's protocol
#    (--gt-translation).
# 5. bench/physics_claim.py --pipeline: per metric the physics / ARAP-only ratio of means
#    over the paired frames of all seeds, 95 % bootstrap intervals over frames, each
#    seed's ratio → OUT/physics_claim.json (penetration over the free vertices: the mean
#    depth over those inside, the paper's Table 2, and over all; fraction inside; contact
#    fraction; force mean / per-frame p95 / max, Table 1; AMV/RV/SV IoU, Table 3; cloth
#    error and Chamfer).
# Every step is skipped when its output exists, so an interrupted run continues.
# Environment: TRAINING_DATA (default: weft synth configs/synth/training_set_random_poses.yaml →
# OUT/training_set), UNSEEN (default: weft synth configs/synth/unseen_studio.yaml →
# OUT/unseen), POSE_RUN, VIEW, SEEDS (default "1 2 3"). Needs a build (scripts/build.sh).
set -euo pipefail
out=${1:?usage: bench/physics_claim.sh --pipeline OUT}
root=$(cd "$(dirname "$0")/.." && pwd)
weft=${WEFT_BUILD_DIR:-$root/build}/apps/weft
[ -x "$weft" ] || { echo "physics_claim: $weft is not built (run scripts/build.sh)" >&2; exit 2; }
mkdir -p "$out/configs" "$out/arms" "$out/captures" "$out/reports"
out=$(cd "$out" && pwd)
view=${VIEW:-cam03}
read -r -a seeds <<<"${SEEDS:-1 2 3}"
start=$(date +%s)
log() { echo "physics_claim --pipeline [$(($(date +%s) - start)) s]: $*"; }
default="$root/configs/train/default.yaml"

data=${TRAINING_DATA:-$out/training_set}
if [ ! -f "$data/dataset.yaml" ]; then
  log "synth: configs/synth/training_set_random_poses.yaml (the default's training set) → $data"
  "$weft" synth --config "$root/configs/synth/training_set_random_poses.yaml" --out "$data" >"$out/training_set.log" 2>&1
fi
unseen=${UNSEEN:-$out/unseen}
if [ ! -f "$unseen/dataset.yaml" ]; then
  log "synth: configs/synth/unseen_studio.yaml → $unseen"
  "$weft" synth --config "$root/configs/synth/unseen_studio.yaml" --out "$unseen" >"$out/unseen.log" 2>&1
fi

# stage_config NAME SEED KEEP [SED...]: default.yaml with the seed set, every stage but KEEP
# at 0 steps, then the extra sed expressions.
stage_config() {
  local name=$1 seed=$2 keep=$3
  shift 3
  # default.yaml's paths are relative to configs/train; the written config lives elsewhere.
  local args=(-e "s/^seed: .*/seed: $seed/" -e "s|\.\./motions/|$root/configs/motions/|" -e "s|\.\./retarget/|$root/configs/retarget/|")
  for stage in pose warmup physics; do
    [ "$stage" = "$keep" ] || args+=(-e "/^  $stage:/s/steps: [0-9]*/steps: 0/")
  done
  for e in "$@"; do args+=(-e "$e"); done
  sed "${args[@]}" "$default" >"$out/configs/$name.yaml"
  echo "# Written by bench/physics_claim_pipeline.sh from configs/train/default.yaml" >>"$out/configs/$name.yaml"
}

# train NAME CONFIG INIT: one run → OUT/NAME (resumed when its checkpoints exist).
train() {
  local run="$out/$1" resume=() init=()
  [ -f "$run/model.safetensors" ] && return 0
  [ -d "$run/checkpoints" ] && resume=(--resume)
  [ -n "$3" ] && init=(--init "$3")
  log "train $1"
  "$weft" train --config "$2" --data "$data" --out "$run" "${init[@]}" "${resume[@]}" >"$run.log" 2>&1
}

pose_model=${POSE_RUN:+$POSE_RUN/model.safetensors}
if [ -z "$pose_model" ]; then
  stage_config pose 1 pose
  train pose "$out/configs/pose.yaml" ""
  pose_model="$out/pose/model.safetensors"
fi
[ -f "$pose_model" ] || { echo "physics_claim: $pose_model does not exist" >&2; exit 2; }
stage_config warmup 1 warmup
train warmup "$out/configs/warmup.yaml" "$pose_model"

for seed in "${seeds[@]}"; do
  for arm in physics arap_only; do
    name="$arm-$seed"
    if [ "$arm" = physics ]; then
      stage_config "$name" "$seed" physics
    else
      stage_config "$name" "$seed" physics "/^  physics:/s/simulation: [0-9.e-]*/simulation: 0/"
    fi
    train "arms/$name" "$out/configs/$name.yaml" "$out/warmup/model.safetensors"
    capture="$out/captures/$name"
    if [ ! -f "$capture/capture.json" ]; then
      log "capture $name on $view"
      "$weft" infer --model "$out/arms/$name" --input "$unseen/images/$view" --camera "$unseen/cameras.yaml" \
        --camera-name "$view" --keypoints "$unseen/keypoints/$view" --out "$capture" >"$capture.log" 2>&1
    fi
    if [ ! -f "$out/reports/$name/metrics.json" ]; then
      log "evaluate $name (--gt-translation)"
      "$weft" eval --prediction "$capture" --data "$unseen" --out "$out/reports/$name" --gt-translation \
        >"$out/reports/$name.log" 2>&1
    fi
  done
done

log "statistics"
python3 "$root/bench/physics_claim.py" "$out" --pipeline --seeds "$(IFS=,; echo "${seeds[*]}")" \
  --arms physics --wall-seconds "$(($(date +%s) - start))"
