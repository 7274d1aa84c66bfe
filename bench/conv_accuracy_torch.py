#!/usr/bin/env python3
"""PyTorch's side of bench_conv_accuracy: the float32 relative L2 error of torch's conv2d
(output, input gradient, weight gradient) against float64 on the same ResNet shapes,
batch 8, in PyTorch's default (NCHW) layout and channels-last."""
import sys

try:
    import torch
except ImportError as e:
    print(f"SKIP: PyTorch not importable by {sys.executable}: {e}")
    sys.exit(77)

SHAPES = [("resnet18 layer1 3x3 64", 64, 64, 3, 1, 1, 32),
          ("resnet18 layer2 3x3 128", 128, 128, 3, 1, 1, 16),
          ("resnet50 layer3 1x1 1024-256", 1024, 256, 1, 1, 0, 8),
          ("resnet50 layer4 3x3 512", 512, 512, 3, 1, 1, 4)]


def run(x, w, gy, stride, pad, dtype, channels_last):
    x = x.to(dtype).clone()
    if channels_last:
        x = x.contiguous(memory_format=torch.channels_last)
    w = w.to(dtype).clone()
    x.requires_grad_()
    w.requires_grad_()
    y = torch.nn.functional.conv2d(x, w, stride=stride, padding=pad)
    y.backward(gy.to(dtype))
    return [t.double() for t in (y, x.grad, w.grad)]


def main():
    torch.set_num_threads(2)
    torch.manual_seed(3)
    print(f"torch {torch.__version__} conv2d float32 relative L2 error against float64, batch 8")
    print(f"{'shape':30s} {'layout':14s} {'output':>10s} {'input grad':>10s} {'weight grad':>10s}")
    for name, c, o, k, s, p, size in SHAPES:
        x = torch.relu(torch.randn(8, c, size, size))
        w = torch.randn(o, c, k, k) * 0.02
        out = (size + 2 * p - k) // s + 1
        gy = torch.randn(8, o, out, out)
        ref = run(x, w, gy, s, p, torch.float64, False)
        for cl in (False, True):
            got = run(x, w, gy, s, p, torch.float32, cl)
            err = [float((a - b).norm() / b.norm()) for a, b in zip(got, ref)]
            print(f"{name:30s} {'channels-last' if cl else 'NCHW':14s} "
                  f"{err[0]:10.2e} {err[1]:10.2e} {err[2]:10.2e}")


if __name__ == "__main__":
    main()
