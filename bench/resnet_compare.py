#!/usr/bin/env python3
"""Runs `weft bench resnet` and bench/resnet_torch_bench.py with the same settings, one
after the other (--rounds times, alternating, so both see the same machine load), and
prints each side's median figures and the ratios PyTorch / weft (> 1: weft is faster).

  bench/resnet_compare.py --weft build/apps/weft --arch resnet50 --batch 8 --size 128
"""
import argparse
import os
import re
import statistics
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
PATTERNS = {
    "train_ms": r"train step: ([\d.]+) ms",
    "infer_ms": r"inference:\s+([\d.]+) ms",
    "peak_mib": r"peak memory: ([\d.]+) MiB",
    "rss_first": r"first/last timed train step: ([\d.]+) /",
    "rss_last": r"first/last timed train step: [\d.]+ / ([\d.]+) MiB",
}


def run(cmd):
    out = subprocess.run(cmd, capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"failed ({out.returncode}): {' '.join(cmd)}\n{out.stdout}{out.stderr}")
    vals = {}
    for key, pat in PATTERNS.items():
        m = re.search(pat, out.stdout)
        if not m:
            sys.exit(f"no '{key}' in the output of {' '.join(cmd)}:\n{out.stdout}")
        vals[key] = float(m.group(1))
    return vals


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--weft", required=True)
    ap.add_argument("--python", default="/usr/bin/python3" if os.path.exists("/usr/bin/python3")
                    else sys.executable)
    ap.add_argument("--arch", default="resnet50")
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--steps", type=int, default=5)
    ap.add_argument("--warmup", type=int, default=2)
    ap.add_argument("--rounds", type=int, default=1)
    # Both sides get the same thread count. PyTorch's own default is the number of
    # physical cores, 1 on this 2-vCPU machine, and with 1 thread it also routes 1x1
    # convolutions at batch < 16 away from oneDNN to its BLAS path.
    ap.add_argument("--threads", type=int, default=os.cpu_count())
    args = ap.parse_args()
    common = ["--arch", args.arch, "--batch", str(args.batch), "--size", str(args.size),
              "--steps", str(args.steps), "--warmup", str(args.warmup)]
    weft, torch = [], []
    for r in range(args.rounds):
        weft.append(run([args.weft, "--threads", str(args.threads), "bench", "resnet"] + common))
        torch.append(run([args.python, os.path.join(HERE, "resnet_torch_bench.py"),
                          "--threads", str(args.threads)] + common))
        print(f"round {r + 1}: weft train {weft[-1]['train_ms']:.1f} ms, infer "
              f"{weft[-1]['infer_ms']:.1f} ms | torch train {torch[-1]['train_ms']:.1f} ms, "
              f"infer {torch[-1]['infer_ms']:.1f} ms", flush=True)
    med = lambda rows, k: statistics.median(row[k] for row in rows)
    print(f"\n{args.arch}, batch {args.batch}, {args.size}x{args.size}, {args.threads} threads, "
          f"median over "
          f"{args.rounds} round(s) of {args.steps}-step medians")
    print(f"{'':12s}{'weft':>12s}{'PyTorch':>12s}{'PyTorch/weft':>14s}")
    for key, label in (("train_ms", "train ms"), ("infer_ms", "infer ms"),
                       ("peak_mib", "peak MiB")):
        w, t = med(weft, key), med(torch, key)
        print(f"{label:12s}{w:12.1f}{t:12.1f}{t / w:14.2f}")
    print(f"weft resident after first/last timed train step: {med(weft, 'rss_first'):.0f} / "
          f"{med(weft, 'rss_last'):.0f} MiB")


if __name__ == "__main__":
    main()
