#!/usr/bin/env bash
# The experiment behind the paper's physics claim, with the pose taken out of it:
#
#   bench/physics_claim.sh [--quick] [--reevaluate] OUT
#   bench/physics_claim.sh --pipeline OUT      (the full pipeline on unseen motion:
#                                               bench/physics_claim_pipeline.sh)
#
# 1. A dataset with 3D ground truth (configs/synth/physics_claim.yaml: 72 frames, the
#    coarse skirt, 4 views; the test split is the motion's last 18 frames).
# 2. One warm start of PADefNet under the oracle pose (training config key oracle_pose:
#    the skeleton posed by gt/pose.motion, so pose error does not enter; no PoseNet).
# 3. From that one model (weft train --init), the physics stage in three arms, each with
#    the same seeds, hence the same steps on the same window batches:
#      physics               L_sil + L_lm + L_att + L_sim + ARAP (body and garment)
#      arap_only             the same with the simulation weight 0
#      physics_no_cloth_arap L_sim with the body's ARAP only
# 4. The same under the oracle pose perturbed as PoseNet errs (training config key
#    oracle_pose_noise, configs/noise/posenet_dof_error.yaml: the default run's PoseNet's
#    error per dof on its validation split), so the garment the silhouettes ask for meets a
#    body in the wrong place, as under a predicted pose: its own warm start, then
#      pose_noise_physics    the physics arm's losses
#      pose_noise_arap_only  the same with the simulation weight 0
# 5. Every arm evaluated on the test split under its pose (weft train --evaluate test), and
#    bench/physics_claim.py: per metric the arm / ARAP-only ratio of means over the paired
#    predictions (IoU: difference in points) with a 95 % bootstrap interval over test
#    frames, and each seed's ratio, in OUT/physics_claim.json. Its top-level entries are
#    pose_noise_physics / pose_noise_arap_only; the oracle's under "oracle" and "arms".
# --quick: 3 seeds, short stages (about 20 minutes on 2 cores); without it 3 seeds and
# stages 4x longer. Reuses OUT/data and the warm starts when present, and skips an arm whose
# evaluation exists. --reevaluate: trains nothing; evaluates the warm starts and every arm of
# OUT again with this build's evaluator (after a change to a metric), then the statistics
# (whose wall time is then the re-evaluation's).
# Needs a build (scripts/build.sh).
set -euo pipefail
if [ "${1:-}" = --pipeline ]; then
  shift
  exec "$(dirname "$0")/physics_claim_pipeline.sh" "$@"
fi
quick=0
reevaluate=0
out=""
for a in "$@"; do
  case "$a" in
    --quick) quick=1 ;;
    --reevaluate) reevaluate=1 ;;
    --pipeline) echo "physics_claim: --pipeline comes first: bench/physics_claim.sh --pipeline OUT" >&2; exit 2 ;;
    -h|--help) sed -n '2,33p' "$0"; exit 0 ;;
    -*) echo "physics_claim: unknown option $a (expected --quick, --reevaluate or --pipeline)" >&2; exit 2 ;;
    *) out=$a ;;
  esac
done
[ -n "$out" ] || { echo "usage: bench/physics_claim.sh [--quick] [--reevaluate] OUT" >&2; exit 2; }
root=$(cd "$(dirname "$0")/.." && pwd)
weft=${WEFT_BUILD_DIR:-$root/build}/apps/weft
[ -x "$weft" ] || { echo "physics_claim: $weft is not built (run scripts/build.sh)" >&2; exit 2; }
if ((reevaluate)) && ! { [ -f "$out/data/dataset.yaml" ] && [ -f "$out/warmup/model.safetensors" ]; }; then
  echo "physics_claim: --reevaluate needs a finished experiment in $out (no data/dataset.yaml or warmup/model.safetensors)" >&2
  exit 2
fi
mkdir -p "$out/configs" "$out/arms"
out=$(cd "$out" && pwd)
seeds=(1 2 3)
if ((quick)); then warm_steps=300; physics_steps=60; else warm_steps=1200; physics_steps=240; fi
start=$(date +%s)
log() { echo "physics_claim [$(($(date +%s) - start)) s]: $*"; }

# evaluate NAME RUN: RUN's model on the test split, into RUN/evaluation_test.json (and NAME's log).
evaluate() {
  "$weft" train --config "$out/configs/$1.yaml" --data "$out/data" --out "$2" --evaluate test >>"$2.log" 2>&1
}

noise_file="$root/configs/noise/posenet_dof_error.yaml"
oracle_arms=(physics arap_only physics_no_cloth_arap)
noise_arms=(pose_noise_physics pose_noise_arap_only)

if ((reevaluate)); then
  for warm in warmup warmup_pose_noise; do
    [ -f "$out/$warm/model.safetensors" ] || continue
    log "re-evaluating the warm start $warm"
    evaluate "$warm" "$out/$warm"
  done
  for seed in "${seeds[@]}"; do
    for arm in "${oracle_arms[@]}" "${noise_arms[@]}"; do
      run="$out/arms/$arm-$seed"
      [ -f "$run/model.safetensors" ] || { echo "physics_claim: $run has no model.safetensors: run without --reevaluate" >&2; exit 2; }
      log "re-evaluating $arm, seed $seed"
      evaluate "$arm-$seed" "$run"
    done
  done
fi

if [ ! -f "$out/data/dataset.yaml" ]; then
  log "synth: configs/synth/physics_claim.yaml"
  "$weft" synth --config "$root/configs/synth/physics_claim.yaml" --out "$out/data" >"$out/synth.log" 2>&1
fi

# config NAME SEED STAGES: a training config under the oracle pose (perturbed when NAME
# starts with pose_noise or is warmup_pose_noise).
config() {
  local noise=""
  case $1 in pose_noise*|warmup_pose_noise) noise="oracle_pose_noise: $noise_file" ;; esac
  cat >"$out/configs/$1.yaml" <<EOF
# Written by bench/physics_claim.sh.
seed: $2
oracle_pose: true
$noise
network: {backbone: resnet18, input_size: 64}
stages:
$3
physics: {window_frames: 4, max_iterations: 60, tolerance: 1.0e-2}
silhouette_size: 64
loader_threads: 1
log_every: 20
validate_every: 0
validation_samples: 16
checkpoint_every: 100
keep_checkpoints: 1
EOF
}

for warm in warmup warmup_pose_noise; do
  [ -f "$out/$warm/model.safetensors" ] && continue
  config "$warm" 0 "  warmup: {steps: $warm_steps, batch_size: 8, lr: 1.0e-3, final_lr_fraction: 0.1, landmarks: 1, silhouette: 1, arap: 10, attachment: 10}"
  log "warm start $warm: $warm_steps steps"
  rm -rf "$out/$warm"
  "$weft" train --config "$out/configs/$warm.yaml" --data "$out/data" --out "$out/$warm" >"$out/$warm.log" 2>&1
  evaluate "$warm" "$out/$warm"
done

stage="batch_size: 8, lr: 2.0e-4, final_lr_fraction: 1, landmarks: 1, silhouette: 1, attachment: 10"
for seed in "${seeds[@]}"; do
  for arm in "${oracle_arms[@]}" "${noise_arms[@]}"; do
    case $arm in
      physics|pose_noise_physics) weights="simulation: 1, arap: 10" ;;
      arap_only|pose_noise_arap_only) weights="simulation: 0, arap: 10" ;;
      physics_no_cloth_arap) weights="simulation: 1, arap: 10, cloth_arap: 0" ;;
    esac
    case $arm in pose_noise*) warm=warmup_pose_noise ;; *) warm=warmup ;; esac
    run="$out/arms/$arm-$seed"
    [ -f "$run/evaluation_test.json" ] && continue
    config "$arm-$seed" "$seed" "  physics: {steps: $physics_steps, $stage, $weights}"
    log "$arm, seed $seed: $physics_steps physics steps from $warm"
    rm -rf "$run"
    "$weft" train --config "$out/configs/$arm-$seed.yaml" --data "$out/data" --out "$run" \
      --init "$out/$warm/model.safetensors" >"$run.log" 2>&1
    evaluate "$arm-$seed" "$run"
  done
done

log "statistics"
quick_flag=()
((quick)) && quick_flag=(--quick)
python3 "$root/bench/physics_claim.py" "$out" --seeds "$(IFS=,; echo "${seeds[*]}")" \
  --noise-arms pose_noise_physics --wall-seconds "$(($(date +%s) - start))" "${quick_flag[@]}"
