#!/usr/bin/env bash
# Capture speed of `weft infer`, end to end on this machine (read, segment, crop, both
# networks, filter, deformation layer, placement, write), at ResNet-18/128² and
# ResNet-50/256², and the two networks' inference beside PyTorch's in the same run
# (bench/resnet_compare.py, alternating rounds).
#
#   bench/infer_speed.sh [FRAMES=120] [ROUNDS=3]
#
# The clip: configs/synth/tiny_wild.yaml with FRAMES frames (256², one moving camera,
# green screen, OpenPose keypoints). The models: one training step of configs/train/tiny.yaml
# at each architecture (speed does not depend on the weights). Two output settings: the
# defaults (PLY + OBJ meshes, overlay PNGs, overlay.mp4) and meshes only (PLY).
# Prints per round the frames per second and the time per part (ms per frame), then the
# medians. Work files go to $WEFT_BENCH_DIR (default /tmp/weft_infer_bench).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
weft="${WEFT_BUILD_DIR:-$root/build}/apps/weft"
work=${WEFT_BENCH_DIR:-/tmp/weft_infer_bench}
frames=${1:-120}
rounds=${2:-3}
mkdir -p "$work"
[ -f "$work/tiny/dataset.yaml" ] || "$weft" synth --config "$root/configs/synth/tiny.yaml" --out "$work/tiny" >/dev/null
[ -f "$work/clip_$frames/dataset.yaml" ] ||
  "$weft" synth --config "$root/configs/synth/tiny_wild.yaml" --frames "$frames" --out "$work/clip_$frames" >/dev/null
echo "output: {meshes: [ply], overlays: false, video: false}" > "$work/meshes_only.yaml"
summary=""
for spec in "resnet18 128" "resnet50 256"; do
  set -- $spec
  arch=$1 size=$2
  model="$work/model_${arch}_$size"
  if [ ! -f "$model/model.yaml" ]; then
    sed -e "s/^network: .*/network: {backbone: $arch, input_size: $size}/" \
        "$root/configs/train/tiny.yaml" > "$work/train_${arch}_$size.yaml"
    "$weft" train --config "$work/train_${arch}_$size.yaml" --data "$work/tiny" --out "$model" --stop-after 1 >/dev/null
  fi
  for setting in defaults meshes_only; do
    config=()
    [ "$setting" = meshes_only ] && config=(--config "$work/meshes_only.yaml")
    fps_list=""
    for r in $(seq "$rounds"); do
      rm -rf "$work/capture"
      "$weft" infer --model "$model" --input "$work/clip_$frames/images/wild" --camera "$work/clip_$frames/cameras.yaml" \
        --keypoints "$work/clip_$frames/keypoints/wild" "${config[@]}" --out "$work/capture" >/dev/null 2>&1
      line=$(/usr/bin/python3 - "$work/capture/capture.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
t = j["timing"]; n = len(j["frames"])
parts = ", ".join(f"{k} {1000 * v / n:.1f}" for k, v in sorted(t["parts"].items()) if k != "load")
# Frames per second without the one-off model load (reported apart).
steady = t["seconds"] - t["parts"].get("load", 0)
print(f"{n / steady:.1f} fps ({n / t['seconds']:.1f} with the {1000 * t['parts'].get('load', 0):.0f} ms model load); ms per frame: {parts}")
PY
)
      echo "$arch/$size² $setting round $r: $line"
      fps_list="$fps_list ${line%% fps*}"
    done
    median=$(printf '%s\n' $fps_list | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}')
    summary="$summary$arch/$size² $setting: median $median frames/s over $rounds rounds\n"
  done
  if /usr/bin/python3 -c "import torch, torchvision" 2>/dev/null; then
    echo "$arch/$size² networks, batch 8, against PyTorch (ratio > 1: weft faster):"
    /usr/bin/python3 "$root/bench/resnet_compare.py" --weft "$weft" --arch "$arch" --batch 8 --size "$size" \
      --rounds "$rounds" --threads "$(nproc)" | grep -E '^round|infer ms|PyTorch/weft' || true
  else
    echo "PyTorch not installed (apt-get install python3-torch python3-torchvision): no peer figure"
  fi
done
printf "%b" "$summary"
