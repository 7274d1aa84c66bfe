#!/usr/bin/env bash
# The look experiment: does the painted character (docs/CHARACTER.md, "Appearance") cure
# PoseNet's front/back confusion? The same random-pose dataset rendered twice, the
# character painted and flat-coloured (the same motion, cameras, seed and lights), and
# PoseNet trained alone on each for the same steps from the same seeds, then measured on
# each dataset's test split (a held-out stretch from the middle of the motion).
#
#   bench/look_experiment.sh [--quick] OUT
#
#  1. weft synth configs/synth/pose_look.yaml → OUT/painted, and with the character's
#     appearance off → OUT/flat
#  2. per seed (SEEDS, default "1 2") and arm: weft train configs/train/pose_look.yaml
#     with that seed → OUT/<arm>_s<seed>, then --evaluate test
#  3. bench/look_experiment.py → OUT/look_experiment.json and a table on stdout
# --quick: 300 frames and 300 steps (the direction, in minutes). Steps are skipped when
# their output exists, so an interrupted run continues.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
weft="${WEFT_BUILD_DIR:-$root/build}/apps/weft"
quick=0
if [ "${1:-}" = --quick ]; then quick=1; shift; fi
out=${1:?usage: bench/look_experiment.sh [--quick] OUT}
seeds=${SEEDS:-1 2}
mkdir -p "$out"
log() { echo "[$(date +%H:%M:%S)] $*" >&2; }
t_start=$SECONDS

# Configs with absolute paths, one per arm (and per seed for training).
abs() { sed -e "s|\.\./characters/|$root/configs/characters/|; s|\.\./motions/|$root/configs/motions/|" \
            -e "s|\.\./retarget/|$root/configs/retarget/|; s|\.\./synth/|$root/configs/synth/|"; }
sed -e 's/^  textured: true/  textured: false/' "$root/configs/characters/makehuman_skirt_coarse.yaml" \
  > "$out/character_flat.yaml"
grep -q "textured: false" "$out/character_flat.yaml" || { echo "could not switch the appearance off" >&2; exit 1; }
abs < "$root/configs/synth/pose_look.yaml" > "$out/synth_painted.yaml"
sed -e "s|^character: .*|character: $out/character_flat.yaml|" "$out/synth_painted.yaml" > "$out/synth_flat.yaml"
frames=""
if [ $quick = 1 ]; then frames="--frames 300"; fi
for arm in painted flat; do
  if [ ! -f "$out/$arm/dataset.yaml" ]; then
    log "1. weft synth ($arm) → $out/$arm"
    # shellcheck disable=SC2086
    "$weft" synth --config "$out/synth_$arm.yaml" --out "$out/$arm" $frames >&2
  fi
done
for seed in $seeds; do
  for arm in painted flat; do
    run="$out/${arm}_s$seed"
    cfg="$out/train_s$seed.yaml"
    abs < "$root/configs/train/pose_look.yaml" | sed -e "s/^seed: .*/seed: $seed/" > "$cfg"
    if [ $quick = 1 ]; then sed -i -e 's/pose:    {steps: 1200/pose:    {steps: 300/' "$cfg"; fi
    if [ ! -f "$run/model.safetensors" ]; then
      log "2. weft train ($arm, seed $seed) → $run"
      resume=()
      [ -d "$run/checkpoints" ] && resume=(--resume)
      "$weft" train --config "$cfg" --data "$out/$arm" --out "$run" "${resume[@]}" >&2
    fi
    if [ ! -f "$run/evaluation_test.json" ]; then
      log "2. weft train --evaluate test ($arm, seed $seed)"
      "$weft" train --config "$cfg" --data "$out/$arm" --out "$run" --evaluate test >&2
    fi
  done
done
# shellcheck disable=SC2086
/usr/bin/python3 "$root/bench/look_experiment.py" --out "$out" --seeds $seeds --seconds $((SECONDS - t_start))
