#!/usr/bin/env python3
"""The statistics of bench/physics_claim.sh: paired per-frame comparisons of its arms.

Reads OUT/arms/<arm>-<seed>/evaluation_test.json (weft train --evaluate: per_frame rows of
every prediction, frame x input view) and writes OUT/physics_claim.json. For each metric
and each arm against ARAP-only: the ratio of the means over every paired prediction of
every seed (physics / ARAP-only; IoU: the difference in percentage points), with a 95 %
bootstrap interval that resamples the test frames (a frame's views and seeds go
together: they share its pose and are not independent), and each seed's own ratio.
Standard library only.
"""
import argparse
import json
import math
import os
import random
import sys

# (metric, per_frame key, kind): "ratio" of means, or "points" difference of a fraction.
METRICS = [
    ("penetration_mean_all_mm", "penetration_mean_all_mm", "ratio"),
    ("penetrating_fraction", "penetrating_fraction", "ratio"),
    ("oob_force_mean_n", "oob_force_mean_n", "ratio"),
    ("oob_force_p95_n", "oob_force_p95_n", "ratio"),
    ("oob_force_max_n", "oob_force_max_n", "ratio"),
    ("oob_force_outside_mean_n", "oob_force_outside_mean_n", "ratio"),
    ("inertia_mean_n", "inertia_mean_n", "ratio"),
    ("elastic_mean_n", "elastic_mean_n", "ratio"),
    ("collision_mean_n", "collision_mean_n", "ratio"),
    ("friction_mean_n", "friction_mean_n", "ratio"),
    ("iou_points", "amv_iou", "points"),
    ("cloth_error_mm", "cloth_error_mean_mm", "ratio"),
    ("chamfer_mm", "cloth_chamfer_mm", "ratio"),
]


def load_rows(path):
    with open(path) as f:
        evaluation = json.load(f)
    return {(r["frame"], r["view"]): r for r in evaluation["per_frame"]}, evaluation


def statistic(pairs, kind):
    a = [p[0] for p in pairs]
    b = [p[1] for p in pairs]
    if not pairs:
        return float("nan")
    if kind == "points":
        return 100.0 * (sum(a) - sum(b)) / len(pairs)
    return (sum(a) / len(a)) / (sum(b) / len(b)) if sum(b) != 0 else float("nan")


def compare(arm_rows, base_rows, seeds, key, kind, resamples, rng):
    # pairs[frame] = [(arm value, base value), ...] over seeds and views, both measured.
    by_frame = {}
    per_seed = []
    for seed in seeds:
        seed_pairs = []
        for k, row in arm_rows[seed].items():
            other = base_rows[seed].get(k)
            if other is None or row[key] is None or other[key] is None:
                continue
            by_frame.setdefault(k[0], []).append((row[key], other[key]))
            seed_pairs.append((row[key], other[key]))
        per_seed.append(statistic(seed_pairs, kind))
    frames = sorted(by_frame)
    pairs = [p for f in frames for p in by_frame[f]]
    value = statistic(pairs, kind)
    boot = []
    for _ in range(resamples):
        drawn = [p for _ in frames for p in by_frame[frames[rng.randrange(len(frames))]]]
        s = statistic(drawn, kind)
        if math.isfinite(s):
            boot.append(s)
    boot.sort()
    lo = boot[int(0.025 * (len(boot) - 1))] if boot else float("nan")
    hi = boot[int(math.ceil(0.975 * (len(boot) - 1)))] if boot else float("nan")
    mean_arm = sum(p[0] for p in pairs) / len(pairs) if pairs else float("nan")
    mean_base = sum(p[1] for p in pairs) / len(pairs) if pairs else float("nan")
    return {
        "ratio" if kind == "ratio" else "difference_points": value,
        "ci_low": lo,
        "ci_high": hi,
        "arm_mean": mean_arm,
        "arap_only_mean": mean_base,
        "pairs": len(pairs),
        "frames": len(frames),
        "per_seed": per_seed,
    }


def finite_or_none(x):
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, dict):
        return {k: finite_or_none(v) for k, v in x.items()}
    if isinstance(x, list):
        return [finite_or_none(v) for v in x]
    return x


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", help="the OUT folder of bench/physics_claim.sh")
    ap.add_argument("--seeds", required=True, help="comma-separated seeds of the arms")
    ap.add_argument("--arms", default="physics,physics_no_cloth_arap", help="arms compared with arap_only")
    ap.add_argument("--wall-seconds", type=float, default=float("nan"))
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--resamples", type=int, default=2000)
    a = ap.parse_args()
    seeds = [int(s) for s in a.seeds.split(",")]
    rng = random.Random(0)

    def rows_of(arm):
        rows = {}
        for seed in seeds:
            path = os.path.join(a.out, "arms", f"{arm}-{seed}", "evaluation_test.json")
            if not os.path.exists(path):
                sys.exit(f"physics_claim: {path} is missing (the arm's evaluation did not run)")
            rows[seed] = load_rows(path)[0]
        return rows

    def summary_of(arm, seed):
        with open(os.path.join(a.out, "arms", f"{arm}-{seed}", "evaluation_test.json")) as f:
            return json.load(f)

    def pooled(arm):
        # The force's distribution pooled over every free vertex of every measured frame
        # (the evaluation's summary): each seed's ratio of its statistics, and their mean.
        out = {}
        for stat in ("mean", "p95", "p99", "max"):
            ratios = []
            for seed in seeds:
                x = summary_of(arm, seed)["oob_force_n"][stat]
                y = summary_of("arap_only", seed)["oob_force_n"][stat]
                ratios.append(x / y if x is not None and y else float("nan"))
            out[f"oob_force_pooled_{stat}"] = {"ratio": sum(ratios) / len(ratios), "per_seed": ratios}
        return out

    base = rows_of("arap_only")
    result = {"quick": a.quick, "seeds": seeds, "wall_seconds": a.wall_seconds, "baseline": "arap_only", "arms": {}}
    for arm in a.arms.split(","):
        rows = rows_of(arm)
        result["arms"][arm] = {
            name: compare(rows, base, seeds, key, kind, a.resamples, rng) for name, key, kind in METRICS
        }
        result["arms"][arm].update(pooled(arm))
    # The headline: the physics arm's figures, as the issue states them.
    if "physics" in result["arms"]:
        result.update(result["arms"]["physics"])
    out = os.path.join(a.out, "physics_claim.json")
    tmp = out + ".tmp"
    with open(tmp, "w") as f:
        json.dump(finite_or_none(result), f, indent=2)
        f.write("\n")
    os.replace(tmp, out)
    for arm, metrics in result["arms"].items():
        print(f"{arm} / arap_only over seeds {seeds}:")
        for name, m in metrics.items():
            v = m.get("ratio", m.get("difference_points"))
            unit = " points" if "difference_points" in m else "x"
            seeds_text = "per seed " + ", ".join(f"{s:.3f}" for s in m["per_seed"])
            if "ci_low" not in m:  # pooled: no interval over frames
                print(f"  {name:28s} {v:8.3f}{unit}  ({seeds_text})")
                continue
            print(f"  {name:28s} {v:8.3f}{unit}  95% CI [{m['ci_low']:.3f}, {m['ci_high']:.3f}]  "
                  f"(arm {m['arm_mean']:.4g}, arap_only {m['arap_only_mean']:.4g}; {seeds_text})")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
