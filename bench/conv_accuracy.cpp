// float32 accuracy of conv2d's backends against float64 (weft's Eigen kernels), on ResNet
// shapes at batch 8, 128×128 input: the relative L2 error of the output, the input
// gradient and the weight gradient. bench/conv_accuracy_torch.py prints PyTorch's own
// float32 error on the same shapes, the bar the default backend is held to.
//
//   bench_conv_accuracy
#include <cmath>
#include <cstdio>
#include <vector>

#include "graph/autograd.h"
#include "ops/conv_backend.h"
#include "ops/ops.h"

namespace {

using namespace weft;

double rel_l2(const std::vector<double>& a, const std::vector<double>& b) {
  double num = 0, den = 0;
  for (size_t i = 0; i < a.size(); ++i) num += (a[i] - b[i]) * (a[i] - b[i]), den += b[i] * b[i];
  return std::sqrt(num / den);
}

struct Shape3 {
  const char* name;
  int64_t C, O, k, stride, pad, in;
};

// Output, input gradient, weight gradient of one conv (NCHW in and out).
std::vector<std::vector<double>> run(const Tensor& x0, const Tensor& w0, const Tensor& gy,
                                     const Shape3& s, DType dtype, int64_t block) {
  Tensor x = x0.to(dtype), w = w0.to(dtype);
  x.set_requires_grad();
  w.set_requires_grad();
  ops::Conv2dOptions o{s.stride, s.stride, s.pad, s.pad, 1, 1};
  o.channel_block = block;
  Tensor xin = x;
  if (block > 1) {
    const Shape d = x.shape();
    xin = ops::permute(ops::reshape(x, {d[0], d[1] / block, block, d[2], d[3]}), {0, 1, 3, 4, 2});
  }
  Tensor y = ops::conv2d(xin, w, Tensor(), o);
  if (block > 1) {
    const Shape d = y.shape();
    y = ops::reshape(ops::permute(y, {0, 1, 4, 2, 3}), {d[0], d[1] * d[4], d[2], d[3]});
  }
  y.backward(gy.to(dtype));
  return {y.to_vector(), x.grad().to_vector(), w.grad().to_vector()};
}

}  // namespace

int main() {
  const std::vector<Shape3> shapes = {
      {"resnet18 layer1 3x3 64", 64, 64, 3, 1, 1, 32},
      {"resnet18 layer2 3x3 128", 128, 128, 3, 1, 1, 16},
      {"resnet50 layer3 1x1 1024-256", 1024, 256, 1, 1, 0, 8},
      {"resnet50 layer4 3x3 512", 512, 512, 3, 1, 1, 4},
  };
  struct Candidate {
    ConvBackend backend;
    int64_t block;
  };
  const std::vector<Candidate> candidates = {{ConvBackend::eigen, 1},
                                             {ConvBackend::onednn, 1},
                                             {ConvBackend::onednn, 16},
                                             {ConvBackend::onednn_winograd, 16}};
  std::printf("conv2d float32 relative L2 error against float64, batch 8 (x: relu(randn), "
              "w: randn * 0.02, dy: randn)\n");
  std::printf("%-30s %-16s %6s %10s %10s %10s\n", "shape", "backend", "block", "output",
              "input grad", "weight grad");
  for (const Shape3& s : shapes) {
    Generator gen(3);
    const Tensor x = ops::relu(Tensor::randn({8, s.C, s.in, s.in}, gen));
    const Tensor w = ops::scale(Tensor::randn({s.O, s.C, s.k, s.k}, gen), 0.02);
    const int64_t out = (s.in + 2 * s.pad - s.k) / s.stride + 1;
    const Tensor gy = Tensor::randn({8, s.O, out, out}, gen);
    set_conv_backend(ConvBackend::eigen);
    const auto ref = run(x, w, gy, s, DType::F64, 1);
    for (const Candidate& c : candidates) {
      set_conv_backend(c.backend);
      const auto got = run(x, w, gy, s, DType::F32, c.block);
      std::printf("%-30s %-16s %6ld %10.2e %10.2e %10.2e\n", s.name, conv_backend_name(c.backend),
                  static_cast<long>(c.block), rel_l2(got[0], ref[0]), rel_l2(got[1], ref[1]),
                  rel_l2(got[2], ref[2]));
    }
  }
  return 0;
}
