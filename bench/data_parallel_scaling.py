#!/usr/bin/env python3
"""Data-parallel `weft train` on this machine: 1 rank vs N ranks (mpirun), T threads each.

    bench/data_parallel_scaling.py CONFIG DATA [--steps P W C] [--ranks 1 2] [--threads 1] [--repeats 3]

Runs CONFIG (e.g. configs/train/tiny.yaml) cut to P pose, W warm-start and C physics steps,
without checkpoints, validation or plots in between, once per repeat and rank count, and
prints per stage the median over the repeats of: samples per second (the stage's global
batch over its mean step time without the bookkeeping), the milliseconds per step spent in
the gradient all-reduce, and in waiting for the other ranks (the small all-reduce of the loss
terms: it absorbs the ranks' imbalance). The figures come from rank 0's RUN/timing_<stage>.json
(capture/training/trainer.cpp). `shards` stays 0 (one per rank), so 1 and N ranks differ in
batch-norm statistics as DDP does; the cost is what is measured. WEFT_BUILD_DIR picks the build.
"""
import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile

import yaml

ROOT = pathlib.Path(__file__).resolve().parent.parent


def bench_config(src: pathlib.Path, steps, out: pathlib.Path) -> dict:
    cfg = yaml.safe_load(src.read_text())
    for stage, n in zip(("pose", "warmup", "physics"), steps):
        cfg["stages"][stage]["steps"] = n
    cfg.update(log_every=1000, validate_every=0, validation_samples=1, checkpoint_every=100000, keep_checkpoints=1)
    cfg.pop("shards", None)
    out.write_text(yaml.safe_dump(cfg))
    return cfg


def run(weft, config, data, ranks, threads, work):
    out = work / f"run_{ranks}"
    subprocess.run(["rm", "-rf", str(out)], check=True)
    cmd = [str(weft), "train", "--threads", str(threads), "--config", str(config), "--data", str(data), "--out", str(out)]
    if ranks > 1:
        env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
        # --bind-to none: OpenMPI binds each rank to one core when np <= 2, which would
        # put a rank's T threads on one core.
        cmd = ["mpirun", "-np", str(ranks), "--oversubscribe", "--bind-to", "none"] + cmd
    else:
        env = dict(os.environ)
    subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return {p.stem[len("timing_"):]: json.loads(p.read_text()) for p in out.glob("timing_*.json")}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("config", type=pathlib.Path)
    ap.add_argument("data", type=pathlib.Path)
    ap.add_argument("--steps", type=int, nargs=3, default=[12, 8, 6], metavar=("POSE", "WARMUP", "PHYSICS"))
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    weft = pathlib.Path(os.environ.get("WEFT_BUILD_DIR", ROOT / "build")) / "apps" / "weft"
    with tempfile.TemporaryDirectory() as tmp:
        work = pathlib.Path(tmp)
        config = work / "bench.yaml"
        cfg = bench_config(a.config.resolve(), a.steps, config)
        print(f"{a.config} on {a.data}: steps {a.steps}, {a.threads} thread(s) per rank, {a.repeats} repeats "
              f"(medians)")
        print(f"{'stage':8} {'ranks':>5} {'batch':>5} {'samples/s':>10} {'ms/step':>8} {'all-reduce ms':>14} "
              f"{'waiting ms':>11}")
        for ranks in a.ranks:
            runs = [run(weft, config, a.data, ranks, a.threads, work) for _ in range(a.repeats)]
            for stage in ("pose", "warmup", "physics"):
                if stage not in runs[0]:
                    continue
                batch = cfg["stages"][stage]["batch_size"]
                if stage == "physics":
                    f = cfg.get("physics", {}).get("window_frames", 3)
                    batch = max(1, batch // f) * f
                step_ms, reduce_ms, wait_ms = [], [], []
                for r in runs:
                    parts = r[stage]["ms_per_step"]
                    step_ms.append(r[stage]["total_ms_per_step"] - parts.get("log, checkpoint, plot, validation", 0))
                    reduce_ms.append(parts.get("all-reduce of the gradients", 0.0))
                    wait_ms.append(parts.get("waiting for the other ranks", 0.0))
                ms = statistics.median(step_ms)
                print(f"{stage:8} {ranks:5d} {batch:5d} {1000 * batch / ms:10.2f} {ms:8.0f} "
                      f"{statistics.median(reduce_ms):14.1f} {statistics.median(wait_ms):11.1f}")
                sys.stdout.flush()


if __name__ == "__main__":
    main()
