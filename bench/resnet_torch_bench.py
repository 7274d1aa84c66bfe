#!/usr/bin/env python3
"""PyTorch's side of `weft bench resnet`: the same training step (forward, MSE loss,
backward, Adam) and inference (eval mode, no grad) on random data, median over timed
steps after warm-up, and the process's peak resident memory. Prints the same lines as
weft. Needs torch and torchvision (exit 77 when they do not import)."""
import argparse
import resource
import statistics
import sys
import time

try:
    import torch
    import torchvision
except ImportError as e:
    print(f"SKIP: PyTorch/torchvision not importable by {sys.executable}: {e}")
    sys.exit(77)


def rss_mib():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * resource.getpagesize() / 2**20


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--arch", default="resnet50", choices=["resnet18", "resnet34", "resnet50"])
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--outputs", type=int, default=1000)
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--warmup", type=int, default=2)
    ap.add_argument("--threads", type=int, default=0)
    args = ap.parse_args()
    if args.threads > 0:
        torch.set_num_threads(args.threads)
    torch.manual_seed(0)
    net = getattr(torchvision.models, args.arch)(num_classes=args.outputs)
    opt = torch.optim.Adam(net.parameters())
    x = torch.randn(args.batch, 3, args.size, args.size)
    y = torch.randn(args.batch, args.outputs)

    net.train()
    train, rss = [], []
    for i in range(args.warmup + args.steps):
        t0 = time.perf_counter()
        opt.zero_grad()
        torch.nn.functional.mse_loss(net(x), y).backward()
        opt.step()
        ms = (time.perf_counter() - t0) * 1e3
        if i >= args.warmup:
            train.append(ms)
            rss.append(rss_mib())
    net.eval()
    infer = []
    with torch.no_grad():
        for i in range(args.warmup + args.steps):
            t0 = time.perf_counter()
            net(x)
            if i >= args.warmup:
                infer.append((time.perf_counter() - t0) * 1e3)
    tm, im = statistics.median(train), statistics.median(infer)
    params = sum(p.numel() for p in net.parameters())
    print(f"{args.arch}, batch {args.batch}, {args.size}x{args.size}, {params} parameters, "
          f"median of {args.steps} steps (torch {torch.__version__}, "
          f"{torch.get_num_threads()} threads)")
    print(f"train step: {tm:.1f} ms  ({1e3 * args.batch / tm:.1f} images/s)")
    print(f"inference:  {im:.1f} ms  ({1e3 * args.batch / im:.1f} images/s)")
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak memory: {peak:.0f} MiB  (resident after first/last timed train step: "
          f"{rss[0]:.0f} / {rss[-1]:.0f} MiB)")


if __name__ == "__main__":
    main()
