#!/usr/bin/env python3
"""The look experiment's figures (bench/look_experiment.sh): PoseNet's root rotation error on
each arm's test split, painted against flat, per seed and over seeds, with paired
differences and bootstrap 95 % intervals over test frames.

  bench/look_experiment.py --out OUT --seeds 1 2 [--seconds S]

Writes OUT/look_experiment.json and prints a Markdown table.
"""
import argparse
import json
import math
import os
import random
import statistics


def load(path):
    with open(path) as f:
        return json.load(f)


def per_prediction(evaluation, key):
    """{(frame, view): value} of one metric, values that were measured."""
    out = {}
    for row in evaluation["per_frame"]:
        v = row.get(key)
        if v is not None and not (isinstance(v, float) and math.isnan(v)):
            out[(row["frame"], row["view"])] = v
    return out


def summary(values):
    v = sorted(values)
    if not v:
        return {"median": None, "p95": None, "mean": None, "above_45": None, "count": 0}
    def q(p):
        x = p * (len(v) - 1)
        lo = math.floor(x)
        hi = min(lo + 1, len(v) - 1)
        return v[lo] + (v[hi] - v[lo]) * (x - lo)
    return {"median": q(0.5), "p95": q(0.95), "mean": statistics.fmean(v),
            "above_45": sum(1 for x in v if x > 45) / len(v), "count": len(v)}


def bootstrap(frames, stat, rounds=2000, seed=7):
    """95 % interval of stat(resampled frames), resampling whole test frames."""
    rng = random.Random(seed)
    values = []
    for _ in range(rounds):
        sample = [frames[rng.randrange(len(frames))] for _ in frames]
        values.append(stat(sample))
    values.sort()
    return values[int(0.025 * rounds)], values[int(0.975 * rounds) - 1]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--seeds", nargs="+", type=int, required=True)
    ap.add_argument("--seconds", type=float, default=None)
    a = ap.parse_args()
    arms = ("painted", "flat")
    per = {arm: {} for arm in arms}  # arm → {(seed, frame, view): error}
    joint = {arm: {} for arm in arms}
    seeds = {}
    for s in a.seeds:
        seeds[s] = {}
        for arm in arms:
            e = load(os.path.join(a.out, f"{arm}_s{s}", "evaluation_test.json"))
            rot = per_prediction(e, "root_rotation_error_deg")
            jnt = per_prediction(e, "mpjpe_mm")
            for k, v in rot.items():
                per[arm][(s,) + k] = v
            for k, v in jnt.items():
                joint[arm][(s,) + k] = v
            seeds[s][arm] = {"root_rotation_deg": summary(list(rot.values())),
                             "joint_error_root_relative_mm": e.get("joint_error_root_relative_mm"),
                             "joint_error_mm": e.get("joint_error_mm"),
                             "keypoint_error_px": e.get("keypoint_error_px")}
    keys = sorted(set(per["painted"]) & set(per["flat"]))
    if not keys:
        raise SystemExit("no paired predictions: are both arms' test splits the same frames?")
    frames = sorted({k[1] for k in keys})
    by_frame = {f: [k for k in keys if k[1] == f] for f in frames}

    def stats(sample_frames):
        ks = [k for f in sample_frames for k in by_frame[f]]
        p = summary([per["painted"][k] for k in ks])
        d = summary([per["flat"][k] for k in ks])
        return p, d

    def diff(metric):
        def f(sample):
            p, d = stats(sample)
            return p[metric] - d[metric]
        return f

    p_all, d_all = stats(frames)
    result = {"seeds": a.seeds, "predictions_paired": len(keys), "test_frames": len(frames),
              "painted": p_all, "flat": d_all, "per_seed": seeds, "seconds": a.seconds, "painted_minus_flat": {}}
    for metric in ("median", "mean", "p95", "above_45"):
        lo, hi = bootstrap(frames, diff(metric))
        result["painted_minus_flat"][metric] = {"value": p_all[metric] - d_all[metric], "ci_low": lo, "ci_high": hi}
    jk = sorted(set(joint["painted"]) & set(joint["flat"]))
    if jk:
        jp = statistics.fmean(joint["painted"][k] for k in jk)
        jd = statistics.fmean(joint["flat"][k] for k in jk)
        result["joint_error_mm"] = {"painted": jp, "flat": jd, "ratio": jp / jd if jd else None}
    tmp = os.path.join(a.out, "look_experiment.json.tmp")
    with open(tmp, "w") as f:
        json.dump(result, f, indent=1)
    os.replace(tmp, os.path.join(a.out, "look_experiment.json"))

    def fmt(x, d=1):
        return "–" if x is None else f"{x:.{d}f}"
    print(f"### Root rotation error on the test split, {len(frames)} frames × views × {len(a.seeds)} seeds "
          f"({len(keys)} paired predictions)\n")
    print("| | painted | flat | painted − flat | 95 % CI |")
    print("|---|---|---|---|---|")
    for metric, label, scale in (("median", "median (°)", 1), ("mean", "mean (°)", 1), ("p95", "p95 (°)", 1),
                                 ("above_45", "predictions above 45° (%)", 100)):
        dd = result["painted_minus_flat"][metric]
        print(f"| {label} | {fmt(p_all[metric] * scale)} | {fmt(d_all[metric] * scale)} | "
              f"{fmt(dd['value'] * scale)} | {fmt(dd['ci_low'] * scale)} – {fmt(dd['ci_high'] * scale)} |")
    if jk:
        print(f"| 3D joint error (mm) | {fmt(jp)} | {fmt(jd)} | ratio {jp / jd:.2f}× | |")
    print("\nPer seed (median °, above 45° %): " + "; ".join(
        f"seed {s}: painted {fmt(seeds[s]['painted']['root_rotation_deg']['median'])}, "
        f"{fmt(100 * (seeds[s]['painted']['root_rotation_deg']['above_45'] or 0))} %; flat "
        f"{fmt(seeds[s]['flat']['root_rotation_deg']['median'])}, "
        f"{fmt(100 * (seeds[s]['flat']['root_rotation_deg']['above_45'] or 0))} %" for s in a.seeds))
    if a.seconds is not None:
        print(f"\nWall time: {a.seconds:.0f} s")


if __name__ == "__main__":
    main()
