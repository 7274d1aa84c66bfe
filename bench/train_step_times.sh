#!/usr/bin/env bash
# Per-part time of a training step of the warm start (b) and the physics-aware stage (c):
#   bench/train_step_times.sh ARCH INPUT_SIZE DATASET [STEPS]
# e.g. bench/train_step_times.sh resnet18 128 data/tiny 20. Runs `weft train` with a config
# written here (batch 8 in stage b; 9 = 3 windows of 3 frames in stage c, the simulator of
# the dataset's dataset.yaml), no PoseNet stage (its weights do not change the cost), and prints
# the mean milliseconds per step of each part over the stage's steps after the first two
# (RUN/timing_<stage>.json covers all of them; docs/TRAINING.md). WEFT_BUILD_DIR picks the build.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
weft="${WEFT_BUILD_DIR:-$root/build}/apps/weft"
arch=${1:?arch: resnet18|resnet34|resnet50}; size=${2:?input size}; data=${3:?dataset folder}; steps=${4:-20}
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cat > "$work/bench.yaml" <<YAML
seed: 1
network: {backbone: $arch, input_size: $size}
stages:
  warmup:  {steps: $steps, batch_size: 8, lr: 1.0e-4, landmarks: 1, silhouette: 1, arap: 10, attachment: 10}
  physics: {steps: $steps, batch_size: 9, lr: 1.0e-4, landmarks: 1, silhouette: 1, simulation: 1, attachment: 10}
physics: {window_frames: 3, max_iterations: 60, tolerance: 1.0e-2}
silhouette_size: 128
loader_threads: 1
log_every: 1000
validate_every: 0
validation_samples: 1
checkpoint_every: 100000
keep_checkpoints: 1
YAML
"$weft" train --config "$work/bench.yaml" --data "$data" --out "$work/run" 2>&1 | grep -E "ms per step|failed and" | sed 's/^\[[^]]*\] \[info\] //'
