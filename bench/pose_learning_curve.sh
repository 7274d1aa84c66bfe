#!/usr/bin/env bash
# PoseNet's learning curve on unseen motion (issue 38, "pose diversity where it is cheap"):
# every checkpoint of each given run, captured on the unseen clip (CMU 01_03) from its
# input view with the detector-model keypoints, under the paper's protocol
# (--gt-translation, the temporal filter), then `weft eval`. One row per (run, step) in
# OUT/curve.csv: root-relative MPJPE, PA-MPJPE, heading (median, fraction above 45°),
# trunk direction and pelvis tilt medians. Runs are compared at the same steps; give
# their folders in pairs of arms and seeds as you like. Resumable: a (run, step) with a
# report is not redone.
#
#   bench/pose_learning_curve.sh OUT RUN [RUN ...]
#
# Environment: UNSEEN the test clip (default OUT/unseen, made from
# configs/synth/unseen_studio.yaml when missing), VIEW the input view (default cam03),
# KEEP_MESHES=1 to keep each checkpoint's captured meshes (deleted after its evaluation).
# Runs keep their checkpoints with checkpoint_every / keep_checkpoints in their config
# (e.g. 500 and 4 for a 2,000-step pose stage). docs/RESULTS.md has the figures.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
weft="${WEFT_BUILD_DIR:-$root/build}/apps/weft"
out=${1:?usage: bench/pose_learning_curve.sh OUT RUN [RUN ...]}
shift
[ $# -ge 1 ] || { echo "usage: bench/pose_learning_curve.sh OUT RUN [RUN ...]" >&2; exit 2; }
view=${VIEW:-cam03}
unseen=${UNSEEN:-$out/unseen}
mkdir -p "$out"
log() { echo "[$(date +%H:%M:%S)] $*" >&2; }

if [ ! -f "$unseen/dataset.yaml" ]; then
  log "unseen clip → $unseen"
  "$weft" synth --config "$root/configs/synth/unseen_studio.yaml" --out "$unseen"
fi
for run in "$@"; do
  [ -d "$run/checkpoints" ] || { echo "$run: no checkpoints/ (a run folder of weft train?)" >&2; exit 1; }
  name=$(basename "$run")
  for ckpt in "$run"/checkpoints/step_*.safetensors; do
    step=$(basename "$ckpt" .safetensors); step=$((10#${step#step_}))
    dir="$out/$name/step_$step"
    [ -f "$dir/report/metrics.json" ] && continue
    log "$name step $step"
    rm -rf "$dir" && mkdir -p "$dir"
    "$weft" infer --model "$run" --weights "$ckpt" --input "$unseen/images/$view" --camera "$unseen/cameras.yaml" \
      --camera-name "$view" --keypoints "$unseen/keypoints/$view" --out "$dir/capture" > "$dir/infer.log" 2>&1
    "$weft" eval --prediction "$dir/capture" --data "$unseen" --out "$dir/report" --gt-translation > "$dir/eval.log" 2>&1
    # Measured: the meshes (~100 MB per checkpoint) are not kept; capture.json, pose.bvh and
    # the report are. KEEP_MESHES=1 keeps them.
    [ "${KEEP_MESHES:-0}" = 1 ] || rm -rf "$dir/capture/meshes"
  done
done
python3 - "$out" "$@" <<'EOF'
import csv, glob, json, os, sys
out, runs = sys.argv[1], sys.argv[2:]
rows = []
for run in runs:
    name = os.path.basename(run.rstrip('/'))
    for path in sorted(glob.glob(os.path.join(out, name, 'step_*', 'report', 'metrics.json'))):
        step = int(path.split(os.sep)[-3][len('step_'):])
        s = json.load(open(path))['summary']
        rows.append([name, step, round(s['mpjpe_root_relative_mm'], 1), round(s['pa_mpjpe_mm'], 1),
                     round(s['root_heading_deg']['median'], 1), round(s['root_heading_deg']['fraction_above_45'], 3),
                     round(s['trunk_direction_deg']['median'], 1), round(s['root_tilt_deg']['median'], 1)])
rows.sort(key=lambda r: (r[0], r[1]))
tmp = os.path.join(out, 'curve.csv.tmp')
with open(tmp, 'w', newline='') as f:
    w = csv.writer(f)
    w.writerow(['run', 'step', 'mpjpe_root_relative_mm', 'pa_mpjpe_mm', 'heading_median_deg', 'heading_above_45',
                'trunk_median_deg', 'tilt_median_deg'])
    w.writerows(rows)
os.replace(tmp, os.path.join(out, 'curve.csv'))
for r in rows: print(*r, sep='\t')
EOF
