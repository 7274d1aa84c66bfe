#!/usr/bin/env python3
"""The distribution of weft's per-tensor float32 error ratios over several seeds.

Runs bench/resnet_torch_parity.py --verbose once per seed and prints, over every
output, gradient and running statistic of all runs, the median, 90th percentile and
maximum of weft's relative L2 error (against PyTorch float64) divided by PyTorch
float32's (+1e-7), and the share above 1. Tensors moved by a ReLU/max-pool tie that
flipped in one of the float32 runs (error above 1e-4 in either) are left out; a flip
that moves a tensor by less than that stays in, and shows as an outlier (the parity
script reports the near-ties of each run).

  /usr/bin/python3 bench/resnet_parity_seeds.py --weft build/apps/weft --arch resnet18 --train --seeds 0-4
"""
import argparse
import os
import re
import statistics
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
TIE_MOVED = 1e-4


def seeds(text):
    lo, _, hi = text.partition("-")
    return list(range(int(lo), int(hi or lo) + 1))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--weft", required=True)
    ap.add_argument("--arch", default="resnet18", choices=["resnet18", "resnet34", "resnet50"])
    ap.add_argument("--train", action="store_true")
    ap.add_argument("--batch", type=int, default=2)
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--seeds", type=seeds, default=seeds("0-4"), help="a range, e.g. 0-4")
    args = ap.parse_args()
    ratios, left_out = [], 0
    for s in args.seeds:
        cmd = [sys.executable, os.path.join(HERE, "resnet_torch_parity.py"), "--weft", args.weft,
               "--arch", args.arch, "--batch", str(args.batch), "--size", str(args.size),
               "--verbose", "--seed", str(s), "--tolerance", "1000"] + (["--train"] if args.train else [])
        run = subprocess.run(cmd, capture_output=True, text=True)
        if run.returncode == 77:
            print(run.stdout.strip())
            return 77
        if run.returncode != 0:
            sys.exit(f"failed ({run.returncode}): {' '.join(cmd)}\n{run.stdout}{run.stderr}")
        for m in re.finditer(r"^\s+(\S+)\s+weft (\S+)\s+torch32 (\S+)", run.stdout, re.M):
            ew, et = float(m.group(2)), float(m.group(3))
            if ew > TIE_MOVED or et > TIE_MOVED:
                left_out += 1
                continue
            ratios.append((ew / (et + 1e-7), s, m.group(1)))
    if not ratios:
        sys.exit("no tensors compared")
    r = sorted(x[0] for x in ratios)
    p90 = r[min(len(r) - 1, int(0.9 * len(r)))]
    above = 100.0 * sum(x > 1 for x in r) / len(r)
    mode = "train" if args.train else "eval"
    print(f"{args.arch} {mode}, seeds {args.seeds[0]}-{args.seeds[-1]}, {len(r)} tensors: "
          f"median {statistics.median(r):.2f}, 90th percentile {p90:.2f}, max {r[-1]:.2f}, "
          f"above 1: {above:.0f}% ({left_out} tensors moved by a flipped tie left out)")
    for ratio, s, name in sorted(ratios)[-3:]:
        print(f"  {ratio:.2f}  seed {s}  {name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
