#!/usr/bin/env python3
"""An oracle_pose_noise file (capture/training/pose_noise.h) from a PoseNet's measured errors.

    bench/pose_noise_config.py RUN/evaluation_val.json --source "what was measured" > configs/noise/NAME.yaml

Reads `weft train --evaluate` output (dof_errors: each regressed dof's mean error and its
spread about the mean; dof_error_correlation_frames: the correlation time of the error
about its mean) and writes the mapping oracle_pose_noise reads: seed 1, scale 1,
correlation_frames, spread (dof: std), bias (dof: mean). Dofs not measured are left out.
Standard library only.
"""
import argparse
import json
import math
import sys


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("evaluation", help="RUN/evaluation_<split>.json of weft train --evaluate")
    ap.add_argument("--source", required=True, help="a line saying which model, data and command measured it")
    a = ap.parse_args()
    with open(a.evaluation) as f:
        e = json.load(f)
    dofs = e.get("dof_errors") or {}
    if not dofs:
        sys.exit(f"pose_noise_config: {a.evaluation} has no dof_errors (evaluated under oracle_pose, "
                 "or by a weft without them)")
    tau = e.get("dof_error_correlation_frames")
    if tau is None or not math.isfinite(tau) or tau <= 0:
        sys.exit(f"pose_noise_config: {a.evaluation}: dof_error_correlation_frames is {tau}, expected > 0")
    print("# PoseNet's error per regressed dof, for oracle_pose_noise (capture/training/pose_noise.h).")
    print(f"# {a.source}")
    print(f"# Written by bench/pose_noise_config.py from {a.evaluation}: split '{e.get('split')}', "
          f"{e.get('predictions')} predictions; root-relative joint error "
          f"{e.get('joint_error_root_relative_mm'):.1f} mm;")
    print(f"# lag-1 autocorrelation of the error about its mean {e.get('dof_error_lag1'):.3f}.")
    print("seed: 1")
    print("scale: 1.0")
    print(f"correlation_frames: {tau:.3g}")
    print("spread:   # standard deviation of predicted - true about its mean (radians)")
    for name, d in dofs.items():
        if d.get("std") is not None:
            print(f"  {name}: {d['std']:.4g}")
    print("bias:     # mean of predicted - true (radians)")
    for name, d in dofs.items():
        if d.get("mean") is not None:
            print(f"  {name}: {d['mean']:.4g}")


if __name__ == "__main__":
    main()
