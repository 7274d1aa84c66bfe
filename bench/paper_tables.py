#!/usr/bin/env python3
"""The paper's tables from two `weft eval` reports (metrics.json): the physics-aware model
against the ARAP-only (DeepCap-like) one, with the paper's own ratios beside ours.

  bench/paper_tables.py --physics OUT/physics_report/metrics.json \
      --arap OUT/arap_only_report/metrics.json [--title "..."] > tables.md
"""
import argparse
import json
import math

# Li et al. 2021, Tables 1-3 (DeepCap row, ours row).
PAPER = {
    "force_mean": (2.119, 1.017),
    "force_max": (29.84, 7.063),
    "penetration_cm": (23.83, 4.165),
    "amv_iou": (82.53, 80.83),
}


def fmt(x, digits=3):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    return f"{x:.{digits}g}"


def ratio(a, b):
    return a / b if a is not None and b not in (None, 0) else None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--physics", required=True)
    ap.add_argument("--arap", required=True)
    ap.add_argument("--title", default="Unseen motion")
    a = ap.parse_args()
    p = json.load(open(a.physics))["summary"]
    d = json.load(open(a.arap))["summary"]

    def get(s, *keys):
        for k in keys:
            if s is None or k not in s or s[k] is None:
                return None
            s = s[k]
        return s

    rows = [
        ("Out-of-balance force, mean (N)", ("out_of_balance_force", "mean_n"), "force_mean"),
        ("Out-of-balance force, max (N)", ("out_of_balance_force", "max_n"), "force_max"),
        ("Out-of-balance force, mean (× m g)", ("out_of_balance_force", "mean_rel"), None),
        ("Penetration depth, mean over penetrating vertices (cm)", ("penetration", "mean_cm"), "penetration_cm"),
        ("Penetration depth, max (mm)", ("penetration", "max_mm"), None),
        ("Cloth vertices inside the body (%)", ("penetration", "fraction_inside"), None),
        ("AMVIoU (%)", ("iou", "amv"), "amv_iou"),
        ("RVIoU (%)", ("iou", "rv"), None),
        ("SVIoU (%)", ("iou", "sv"), None),
        ("Cloth vertex error, mean (mm)", ("cloth_error_mm", "mean"), None),
        ("Cloth vertex error, 95th percentile (mm)", ("cloth_error_mm", "p95"), None),
        ("Cloth Chamfer distance (mm)", ("cloth_chamfer_mm",), None),
        ("Body vertex error, mean (mm)", ("body_error_mm", "mean"), None),
        ("MPJPE (mm)", ("mpjpe_mm",), None),
        ("MPJPE, root-relative (mm)", ("mpjpe_root_relative_mm",), None),
        ("Root rotation error, median (°)", ("root_rotation_deg", "median"), None),
        ("Frames with the root rotation off by more than 45° (%)", ("root_rotation_deg", "fraction_above_45"), None),
    ]
    print(f"### {a.title}\n")
    print("| metric | ARAP-only (DeepCap-like) | physics-aware | ratio physics / ARAP | paper's ratio |")
    print("|---|---|---|---|---|")
    for label, keys, paper in rows:
        pv, dv = get(p, *keys), get(d, *keys)
        scale = 100.0 if keys[0] in ("iou",) or keys[-1] in ("fraction_inside", "fraction_above_45") else 1.0
        pv = pv * scale if pv is not None else None
        dv = dv * scale if dv is not None else None
        if keys[0] == "iou":
            r = f"{pv - dv:+.2f} points" if pv is not None and dv is not None else "–"
            pr = f"{PAPER[paper][1] - PAPER[paper][0]:+.2f} points" if paper else ""
        else:
            rr = ratio(pv, dv)
            r = f"{rr:.2f}×" if rr is not None else "–"
            pr = f"{PAPER[paper][1] / PAPER[paper][0]:.2f}×" if paper else ""
        print(f"| {label} | {fmt(dv)} | {fmt(pv)} | {r} | {pr} |")
    gt = get(p, "out_of_balance_force", "ground_truth")
    if gt:
        print(f"\nGround truth (the simulator's own frames): out-of-balance force {fmt(gt.get('mean_n'))} N mean, "
              f"{fmt(gt.get('max_n'))} N max; penetration {fmt(get(p, 'penetration', 'ground_truth', 'mean_cm'))} cm.")
    print(f"Frames: {get(p, 'frames')} captured, {get(p, 'iou', 'frames')} with IoU, "
          f"{get(p, 'out_of_balance_force', 'frames')} with the force (three consecutive frames).")


if __name__ == "__main__":
    main()
