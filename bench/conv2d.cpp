// conv2d speed on the distinct conv layer shapes of ResNet-50 (torchvision v1.5: stride on
// the 3×3), batch 8, 3×128×128 input, float32, next to Eigen's sgemm measured in the same
// run. Prints a table: median milliseconds over the repeats and GFLOP/s, forward
// (2·N·O·C·kh·kw·Ho·Wo flops) and forward+backward (3× that: dx and dW each cost one
// forward's worth).
//
// Candidates side by side: --backend eigen (im2col + Eigen GEMM) or onednn, and
// --block 1 (NCHW) or 16 (oneDNN's channel blocks; the stem stays NCHW, as in ResNet).
//
//   bench_conv2d [--repeats 7] [--batch 8] [--size 128] [--threads 2] [--layer SUBSTRING]
//                [--backend eigen|onednn] [--block 1|16]
#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <string>
#include <vector>

#include "graph/autograd.h"
#include "graph/threads.h"
#include "ops/conv_backend.h"
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

// CPU seconds used so far by the OpenMP team (the threads Eigen and the conv kernels
// run on), each thread reading its own clock: the process clock only catches up with
// the other threads' time at scheduler ticks, too coarse for runs of a few ms.
double cpu_seconds(int threads) {
  double total = 0;
#pragma omp parallel num_threads(threads) reduction(+ : total)
  {
    timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    total += t.tv_sec + 1e-9 * t.tv_nsec;
  }
  return total;
}

struct Timing {
  double wall, cpu;  // seconds, medians; cpu already divided by the thread count
};

template <class F>
Timing median_time(int repeats, int threads, F f) {
  // Warm-up: scratch buffers, allocator, page faults. The first calls of a new shape run
  // several times slower on this (virtualised) machine, for up to a dozen calls at 2
  // threads (the stem conv: ~18 ms for 12 calls, then 3.3 ms), so at least 12 calls and
  // 0.3 s go before timing starts.
  const auto warm_start = Clock::now();
  for (int i = 0; i < 12 || Clock::now() - warm_start < std::chrono::milliseconds(300); ++i) f();
  std::vector<double> wall, cpu;
  for (int r = 0; r < repeats; ++r) {
    const double c0 = cpu_seconds(threads);
    const auto t0 = Clock::now();
    f();
    wall.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    cpu.push_back((cpu_seconds(threads) - c0) / threads);
  }
  return {median(wall), median(cpu)};
}

Timing sgemm_time(int repeats, int threads) {
  const int n = 1024;
  Eigen::MatrixXf a = Eigen::MatrixXf::Random(n, n), b = Eigen::MatrixXf::Random(n, n), c(n, n);
  const Timing t = median_time(repeats, threads, [&] { c.noalias() = a * b; });
  if (c(0, 0) == 12345.f) std::puts("");  // keep the product alive
  return t;
}

std::string loadavg() {
  std::ifstream f("/proc/loadavg");
  std::string a, b, c;
  f >> a >> b >> c;
  return a + " " + b + " " + c;
}

}  // namespace

int main(int argc, char** argv) {
  int repeats = 7, threads = 2;
  int64_t batch = 8, size = 128;
  std::string only;  // run only the layers whose name contains this
  int64_t block = 1;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    const long v = std::atol(argv[i + 1]);
    if (a == "--layer") only = argv[i + 1];
    else if (a == "--repeats") repeats = static_cast<int>(v);
    else if (a == "--batch") batch = v;
    else if (a == "--size") size = v;
    else if (a == "--threads") threads = static_cast<int>(v);
    else if (a == "--block") block = v;
    else if (a == "--backend") set_conv_backend(parse_conv_backend(argv[i + 1], "--backend"));
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

  const std::string load_before = loadavg();
  const double gemm_flops = 2.0 * 1024 * 1024 * 1024;
  const Timing gemm_before = sgemm_time(repeats, threads);

  Generator gen(1);
  struct Row {
    const Layer* layer;
    int64_t out;
    double flops;
    Timing fwd, fb;
  };
  std::vector<Row> rows;
  for (const Layer& L : layers) {
    if (!only.empty() && std::string(L.name).find(only) == std::string::npos) continue;
    const int64_t out = (L.in + 2 * L.pad - L.k) / L.stride + 1;
    const double flops = 2.0 * batch * L.O * L.C * L.k * L.k * out * out;
    const int64_t b = L.C % block == 0 ? block : 1;
    Tensor x = b > 1 ? Tensor::randn({batch, L.C / b, L.in, L.in, b}, gen)
                     : Tensor::randn({batch, L.C, L.in, L.in}, gen);
    Tensor w = Tensor::randn({L.O, L.C, L.k, L.k}, gen, DType::F32, 0.0, 0.05);
    ops::Conv2dOptions o{L.stride, L.stride, L.pad, L.pad, 1, 1};
    o.channel_block = b;
    const Timing fwd = median_time(repeats, threads, [&] {
      NoGradGuard no_grad;
      Tensor y = ops::conv2d(x, w, Tensor(), o);
    });
    Tensor xg = x.clone(), wg = w.clone();
    xg.set_requires_grad();
    wg.set_requires_grad();
    const Tensor gy = b > 1 ? Tensor::randn({batch, L.O / b, out, out, b}, gen)
                            : Tensor::randn({batch, L.O, out, out}, gen);
    const Timing fb = median_time(repeats, threads, [&] {
      xg.zero_grad();
      wg.zero_grad();
      Tensor y = ops::conv2d(xg, wg, Tensor(), o);
      y.backward(gy);
    });
    rows.push_back({&L, out, flops, fwd, fb});
  }
  const Timing gemm_after = sgemm_time(repeats, threads);
  const double gemm_wall = gemm_flops / (0.5 * (gemm_before.wall + gemm_after.wall)) * 1e-9;
  const double gemm_cpu = gemm_flops / (0.5 * (gemm_before.cpu + gemm_after.cpu)) * 1e-9;

  std::printf("conv2d, float32, backend %s, channel block %ld, batch %ld, input 3x%ldx%ld, "
              "%d threads, median of %d; load average %s (before) %s (after)\n",
              conv_backend_name(conv_backend()), static_cast<long>(block),
              static_cast<long>(batch), static_cast<long>(size), static_cast<long>(size),
              threads, repeats, load_before.c_str(), loadavg().c_str());
  std::printf("Eigen sgemm 1024^3: wall %.1f GFLOP/s (%.1f before, %.1f after), cpu %.1f GFLOP/s\n\n",
              gemm_wall, gemm_flops / gemm_before.wall * 1e-9,
              gemm_flops / gemm_after.wall * 1e-9, gemm_cpu);
  std::printf("%-21s %2s %8s | %7s %7s %4s %7s %4s | %7s %7s %4s %7s %4s\n", "layer", "n", "out",
              "fwd ms", "GFLOP/s", "%", "cpu", "%", "f+b ms", "GFLOP/s", "%", "cpu", "%");
  double net_flops = 0, net_fwd = 0, net_fb = 0, net_fwd_cpu = 0, net_fb_cpu = 0;
  for (const Row& r : rows) {
    const double f = r.flops * 1e-9;
    std::printf("%-21s %2d %8s | %7.2f %7.1f %3.0f%% %7.1f %3.0f%% | %7.2f %7.1f %3.0f%% %7.1f "
                "%3.0f%%\n",
                r.layer->name, r.layer->count,
                (std::to_string(r.layer->O) + "x" + std::to_string(r.out)).c_str(),
                r.fwd.wall * 1e3, f / r.fwd.wall, 100 * f / r.fwd.wall / gemm_wall,
                f / r.fwd.cpu, 100 * f / r.fwd.cpu / gemm_cpu, r.fb.wall * 1e3,
                3 * f / r.fb.wall, 100 * 3 * f / r.fb.wall / gemm_wall, 3 * f / r.fb.cpu,
                100 * 3 * f / r.fb.cpu / gemm_cpu);
    net_flops += r.layer->count * f;
    net_fwd += r.layer->count * r.fwd.wall;
    net_fb += r.layer->count * r.fb.wall;
    net_fwd_cpu += r.layer->count * r.fwd.cpu;
    net_fb_cpu += r.layer->count * r.fb.cpu;
  }
  std::printf("\nall 53 convs of ResNet-50 (each shape weighted by n):\n"
              "  forward          %7.1f ms  %6.1f GFLOP/s (%3.0f%% of sgemm); cpu %6.1f GFLOP/s "
              "(%3.0f%%)\n"
              "  forward+backward %7.1f ms  %6.1f GFLOP/s (%3.0f%% of sgemm); cpu %6.1f GFLOP/s "
              "(%3.0f%%)\n",
              net_fwd * 1e3, net_flops / net_fwd, 100 * net_flops / net_fwd / gemm_wall,
              net_flops / net_fwd_cpu, 100 * net_flops / net_fwd_cpu / gemm_cpu, net_fb * 1e3,
              3 * net_flops / net_fb, 100 * 3 * net_flops / net_fb / gemm_wall,
              3 * net_flops / net_fb_cpu, 100 * 3 * net_flops / net_fb_cpu / gemm_cpu);
  return 0;
}
