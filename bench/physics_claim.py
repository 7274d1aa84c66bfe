#!/usr/bin/env python3
"""The statistics of bench/physics_claim.sh: paired per-frame comparisons of its arms.

Reads OUT/arms/<arm>-<seed>/evaluation_test.json (weft train --evaluate: per_frame rows of
every prediction, frame x input view) and writes OUT/physics_claim.json. For each metric
and each arm against its ARAP-only arm (arap_only under the oracle pose; pose_noise_arap_only
for the --noise-arms, under the perturbed pose): the ratio of the means over every paired prediction of
every seed (physics / ARAP-only; IoU: the difference in percentage points), with a 95 %
bootstrap interval that resamples the test frames (a frame's views and seeds go
together: they share its pose and are not independent), and each seed's own ratio.
The top-level entries repeat the headline arm's figures: pose_noise_physics when it ran,
else physics; the oracle's physics arm is also under "oracle".
Standard library only.
"""
import argparse
import json
import math
import os
import random
import sys

# (metric, per_frame key, kind): "ratio" of means, "points" difference of a fraction's
# means, or "weighted:<key>" ratio of means weighted by another per-frame column (the
# depth over the vertices inside, weighted by the fraction inside, which is their count
# over the garment's fixed number of free vertices: the mean over every penetrating vertex
# of the pooled frames, the paper's Table 2).
METRICS = [
    ("penetration_mean_mm", "penetration_mean_mm", "weighted:penetrating_fraction"),
    ("penetration_mean_all_mm", "penetration_mean_all_mm", "ratio"),
    ("penetrating_fraction", "penetrating_fraction", "ratio"),
    ("contact_fraction", "contact_fraction", "ratio"),
    ("oob_force_mean_n", "oob_force_mean_n", "ratio"),
    ("oob_force_p95_n", "oob_force_p95_n", "ratio"),
    ("oob_force_max_n", "oob_force_max_n", "ratio"),
    ("oob_force_outside_mean_n", "oob_force_outside_mean_n", "ratio"),
    ("inertia_mean_n", "inertia_mean_n", "ratio"),
    ("elastic_mean_n", "elastic_mean_n", "ratio"),
    ("collision_mean_n", "collision_mean_n", "ratio"),
    ("friction_mean_n", "friction_mean_n", "ratio"),
    ("iou_points", "amv_iou", "points"),
    ("rv_iou_points", "rv_iou", "points"),
    ("sv_iou_points", "sv_iou", "points"),
    ("cloth_error_mm", "cloth_error_mean_mm", "ratio"),
    ("chamfer_mm", "cloth_chamfer_mm", "ratio"),
]


def load_rows(path):
    """{(frame, view): row} of a `weft train --evaluate` file (per_frame: a list of rows) or
    of a `weft eval` metrics.json (per_frame: columns, one input view)."""
    with open(path) as f:
        evaluation = json.load(f)
    per_frame = evaluation["per_frame"]
    if isinstance(per_frame, dict):
        ids = per_frame["id"]
        rows = [{k: v[i] for k, v in per_frame.items()} for i in range(len(ids))]
        return {(r["id"], 0): r for r in rows}, evaluation
    return {(r["frame"], r["view"]): r for r in per_frame}, evaluation


def term(row, key, kind):
    """A row's (numerator, denominator) of the metric; None when not measured."""
    v = row.get(key)
    if v is None:
        return None
    if kind.startswith("weighted:"):
        w = row.get(kind.split(":", 1)[1])
        return None if w is None else (v * w, w)
    return (v, 1.0)


def statistic(pairs, kind):
    if not pairs:
        return float("nan")
    na = sum(p[0][0] for p in pairs)
    da = sum(p[0][1] for p in pairs)
    nb = sum(p[1][0] for p in pairs)
    db = sum(p[1][1] for p in pairs)
    if da == 0 or db == 0:
        return float("nan")
    if kind == "points":
        return 100.0 * (na / da - nb / db)
    return (na / da) / (nb / db) if nb != 0 else float("nan")


def mean_of(pairs, side):
    d = sum(p[side][1] for p in pairs)
    return sum(p[side][0] for p in pairs) / d if d else float("nan")


def compare(arm_rows, base_rows, seeds, key, kind, resamples, rng):
    # pairs[frame] = [(arm term, base term), ...] over seeds and views, both measured.
    by_frame = {}
    per_seed = []
    for seed in seeds:
        seed_pairs = []
        for k, row in arm_rows[seed].items():
            other = base_rows[seed].get(k)
            if other is None:
                continue
            a, b = term(row, key, kind), term(other, key, kind)
            if a is None or b is None:
                continue
            by_frame.setdefault(k[0], []).append((a, b))
            seed_pairs.append((a, b))
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
    return {
        "difference_points" if kind == "points" else "ratio": value,
        "ci_low": lo,
        "ci_high": hi,
        "arm_mean": mean_of(pairs, 0),
        "arap_only_mean": mean_of(pairs, 1),
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
    ap.add_argument("--noise-arms", default="", help="arms under the perturbed pose, compared with pose_noise_arap_only")
    ap.add_argument("--wall-seconds", type=float, default=float("nan"))
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--pipeline", action="store_true",
                    help="the arms' captures of unseen motion: OUT/reports/<arm>-<seed>/metrics.json (weft eval)")
    ap.add_argument("--resamples", type=int, default=2000)
    a = ap.parse_args()
    seeds = [int(s) for s in a.seeds.split(",")]
    rng = random.Random(0)

    def evaluation_path(arm, seed):
        if a.pipeline:
            return os.path.join(a.out, "reports", f"{arm}-{seed}", "metrics.json")
        return os.path.join(a.out, "arms", f"{arm}-{seed}", "evaluation_test.json")

    def rows_of(arm):
        rows = {}
        for seed in seeds:
            path = evaluation_path(arm, seed)
            if not os.path.exists(path):
                sys.exit(f"physics_claim: {path} is missing (the arm's evaluation did not run)")
            rows[seed] = load_rows(path)[0]
        return rows

    def pooled_force(arm, seed):
        with open(evaluation_path(arm, seed)) as f:
            e = json.load(f)
        if a.pipeline:  # weft eval: summary.out_of_balance_force (mean_n, p95_n, p99_n, max_n)
            force = e["summary"]["out_of_balance_force"]
            return {stat: force.get(f"{stat}_n") for stat in ("mean", "p95", "p99", "max")}
        return e["oob_force_n"]

    def pooled(arm, baseline):
        # The force's distribution pooled over every free vertex of every measured frame
        # (the evaluation's summary): each seed's ratio of its statistics, and their mean.
        out = {}
        for stat in ("mean", "p95", "p99", "max"):
            ratios = []
            for seed in seeds:
                x = pooled_force(arm, seed)[stat]
                y = pooled_force(baseline, seed)[stat]
                ratios.append(x / y if x is not None and y else float("nan"))
            out[f"oob_force_pooled_{stat}"] = {"ratio": sum(ratios) / len(ratios), "per_seed": ratios}
        return out

    result = {"quick": a.quick, "pipeline": a.pipeline, "seeds": seeds, "wall_seconds": a.wall_seconds, "baseline": "arap_only",
              "baselines": {}, "arms": {}}
    groups = [("arap_only", [x for x in a.arms.split(",") if x])]
    if a.noise_arms:
        groups.append(("pose_noise_arap_only", [x for x in a.noise_arms.split(",") if x]))
    for baseline, arms in groups:
        if not arms:
            continue
        base = rows_of(baseline)
        for arm in arms:
            rows = rows_of(arm)
            result["baselines"][arm] = baseline
            result["arms"][arm] = {
                name: compare(rows, base, seeds, key, kind, a.resamples, rng) for name, key, kind in METRICS
            }
            result["arms"][arm].update(pooled(arm, baseline))
    # The headline (top-level entries): physics against ARAP-only under the perturbed pose
    # when it was run (a predicted pose's situation), else under the oracle pose. The
    # oracle's physics arm stays under "oracle" either way.
    if "physics" in result["arms"]:
        result["oracle"] = result["arms"]["physics"]
    headline = "pose_noise_physics" if "pose_noise_physics" in result["arms"] else "physics"
    if headline in result["arms"]:
        result["headline"] = headline
        result.update(result["arms"][headline])
    out = os.path.join(a.out, "physics_claim.json")
    tmp = out + ".tmp"
    with open(tmp, "w") as f:
        json.dump(finite_or_none(result), f, indent=2)
        f.write("\n")
    os.replace(tmp, out)
    for arm, metrics in result["arms"].items():
        print(f"{arm} / {result['baselines'][arm]} over seeds {seeds}:")
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
