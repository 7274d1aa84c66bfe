// conv2d speed on the distinct conv layer shapes of ResNet-50 (torchvision v1.5: stride on
// the 3×3), batch 8, 3×128×128 input, float32, next to Eigen's sgemm measured in the same
// run. Prints a table: median milliseconds over the repeats and GFLOP/s, forward
// (2·N·O·C·kh·kw·Ho·Wo flops) and forward+backward (3× that: dx and dW each cost one
// forward's worth).
//
//   bench_conv2d [--repeats 7] [--batch 8] [--size 128] [--threads 2]
#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "graph/autograd.h"
#include "graph/threads.h"
#include "ops/ops.h"

namespace {

using namespace weft;
using Clock = std::chrono::steady_clock;

struct Layer {
  const char* name;
  int64_t C, O, k, stride, pad, in;  // in: input spatial size at 128×128
  int count;                         // occurrences in ResNet-50
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

template <class F>
double median_seconds(int repeats, F f) {
  f();  // warm-up: buffers, page faults
  std::vector<double> t;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = Clock::now();
    f();
    t.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
  }
  return median(t);
}

double sgemm_gflops(int repeats) {
  const int n = 1024;
  Eigen::MatrixXf a = Eigen::MatrixXf::Random(n, n), b = Eigen::MatrixXf::Random(n, n), c(n, n);
  const double s = median_seconds(repeats, [&] { c.noalias() = a * b; });
  if (c(0, 0) == 12345.f) std::puts("");  // keep the product alive
  return 2.0 * n * n * n / s * 1e-9;
}

}  // namespace

int main(int argc, char** argv) {
  int repeats = 7, threads = 2;
  int64_t batch = 8, size = 128;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    const long v = std::atol(argv[i + 1]);
    if (a == "--repeats") repeats = static_cast<int>(v);
    else if (a == "--batch") batch = v;
    else if (a == "--size") size = v;
    else if (a == "--threads") threads = static_cast<int>(v);
    else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  set_num_threads(threads);
  const int64_t s1 = size / 4, s2 = size / 8, s3 = size / 16, s4 = size / 32;
  const std::vector<Layer> layers = {
      {"stem 7x7/2", 3, 64, 7, 2, 3, size, 1},
      {"l1 1x1 64-64", 64, 64, 1, 1, 0, s1, 1},
      {"l1 3x3 64", 64, 64, 3, 1, 1, s1, 3},
      {"l1 1x1 64-256", 64, 256, 1, 1, 0, s1, 4},  // incl. the stride-1 downsample
      {"l1 1x1 256-64", 256, 64, 1, 1, 0, s1, 2},
      {"l2 1x1 256-128", 256, 128, 1, 1, 0, s1, 1},
      {"l2 3x3/2 128", 128, 128, 3, 2, 1, s1, 1},
      {"l2 ds 1x1/2 256-512", 256, 512, 1, 2, 0, s1, 1},
      {"l2 1x1 128-512", 128, 512, 1, 1, 0, s2, 4},
      {"l2 1x1 512-128", 512, 128, 1, 1, 0, s2, 3},
      {"l2 3x3 128", 128, 128, 3, 1, 1, s2, 3},
      {"l3 1x1 512-256", 512, 256, 1, 1, 0, s2, 1},
      {"l3 3x3/2 256", 256, 256, 3, 2, 1, s2, 1},
      {"l3 ds 1x1/2 512-1024", 512, 1024, 1, 2, 0, s2, 1},
      {"l3 1x1 256-1024", 256, 1024, 1, 1, 0, s3, 6},
      {"l3 1x1 1024-256", 1024, 256, 1, 1, 0, s3, 5},
      {"l3 3x3 256", 256, 256, 3, 1, 1, s3, 5},
      {"l4 1x1 1024-512", 1024, 512, 1, 1, 0, s3, 1},
      {"l4 3x3/2 512", 512, 512, 3, 2, 1, s3, 1},
      {"l4 ds 1x1/2 1024-2048", 1024, 2048, 1, 2, 0, s3, 1},
      {"l4 1x1 512-2048", 512, 2048, 1, 1, 0, s4, 3},
      {"l4 1x1 2048-512", 2048, 512, 1, 1, 0, s4, 2},
      {"l4 3x3 512", 512, 512, 3, 1, 1, s4, 2},
  };

  const double gemm = sgemm_gflops(repeats);
  std::printf("conv2d, float32, batch %ld, input 3x%ldx%ld, %d threads, median of %d\n",
              static_cast<long>(batch), static_cast<long>(size), static_cast<long>(size),
              threads, repeats);
  std::printf("Eigen sgemm 1024^3: %.1f GFLOP/s\n\n", gemm);
  std::printf("%-22s %4s %9s %8s %8s %5s %8s %8s %5s\n", "layer", "n", "out", "fwd ms",
              "GFLOP/s", "%gemm", "f+b ms", "GFLOP/s", "%gemm");

  Generator gen(1);
  double net_flops = 0, net_fwd = 0, net_fb = 0;
  for (const Layer& L : layers) {
    const int64_t out = (L.in + 2 * L.pad - L.k) / L.stride + 1;
    const double flops = 2.0 * batch * L.O * L.C * L.k * L.k * out * out;
    Tensor x = Tensor::randn({batch, L.C, L.in, L.in}, gen);
    Tensor w = Tensor::randn({L.O, L.C, L.k, L.k}, gen, DType::F32, 0.0, 0.05);
    const ops::Conv2dOptions o{L.stride, L.stride, L.pad, L.pad, 1, 1};
    const double fwd = median_seconds(repeats, [&] {
      NoGradGuard no_grad;
      Tensor y = ops::conv2d(x, w, Tensor(), o);
    });
    Tensor xg = x.clone(), wg = w.clone();
    xg.set_requires_grad();
    wg.set_requires_grad();
    const Tensor gy = Tensor::randn({batch, L.O, out, out}, gen);
    const double fb = median_seconds(repeats, [&] {
      xg.zero_grad();
      wg.zero_grad();
      Tensor y = ops::conv2d(xg, wg, Tensor(), o);
      y.backward(gy);
    });
    const double gf = flops / fwd * 1e-9, gfb = 3 * flops / fb * 1e-9;
    std::printf("%-22s %4d %9s %8.2f %8.1f %4.0f%% %8.2f %8.1f %4.0f%%\n", L.name, L.count,
                (std::to_string(L.O) + "x" + std::to_string(out)).c_str(), fwd * 1e3, gf,
                100 * gf / gemm, fb * 1e3, gfb, 100 * gfb / gemm);
    net_flops += L.count * flops;
    net_fwd += L.count * fwd;
    net_fb += L.count * fb;
  }
  std::printf("\nall 53 convs of ResNet-50 (weighted by n): forward %.1f ms, %.1f GFLOP/s "
              "(%.0f%% of sgemm); forward+backward %.1f ms, %.1f GFLOP/s (%.0f%%)\n",
              net_fwd * 1e3, net_flops / net_fwd * 1e-9, 100 * net_flops / net_fwd * 1e-9 / gemm,
              net_fb * 1e3, 3 * net_flops / net_fb * 1e-9,
              100 * 3 * net_flops / net_fb * 1e-9 / gemm);
  return 0;
}
