// Deformation layer forward + backward for the ddc character (5,514 vertices, 852
// graph nodes, 107 dofs) at batch 8, float32: dofs → FK → dual quaternions → embedded
// deformation → DQS, loss = mean squared vertex position, backward to dofs, node
// rotations and translations. Needs ../shared/data/ddc.
//
//   build/bench/bench_deformation_layer [--repeats N] [--batch B]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "capture/deformation/deformation_layer.h"
#include "capture/character/skeletool_io.h"
#include "graph/profiler.h"
#include "graph/threads.h"
#include "ops/ops.h"

using namespace weft;

namespace {
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
}  // namespace

int main(int argc, char** argv) {
  int repeats = 20, batch = 8;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--repeats")) repeats = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--batch")) batch = std::atoi(argv[i + 1]);
  }
  const std::string root = std::string(WEFT_BENCH_SOURCE_DIR) + "/../shared/data/ddc";
  if (!std::filesystem::exists(root + "/ddc.skeleton")) {
    std::printf("ddc data not found at %s: skipped\n", root.c_str());
    return 0;
  }
  const capture::Character character =
      capture::load_character(std::string(WEFT_BENCH_SOURCE_DIR) + "/configs/characters/ddc.yaml");
  const capture::Motion motion =
      capture::read_motion(root + "/walk_0000_0299.motion", character.skeleton.num_dofs());
  const capture::DeformationLayer layer(character, DType::F32);
  const int64_t D = layer.num_dofs(), K = layer.body().num_nodes();
  std::vector<double> d;
  for (int b = 0; b < batch; ++b)
    for (int64_t k = 0; k < D; ++k) d.push_back(motion.dofs(b * 30 % motion.num_frames(), k));
  Generator gen(1);
  std::vector<double> fwd_ms, total_ms;
  for (int r = 0; r < repeats + 2; ++r) {
    Tensor dofs = Tensor::from_data({batch, D}, d, DType::F32).set_requires_grad();
    Tensor angles = Tensor::randn({batch, K, 3}, gen, DType::F32, 0, 0.05).set_requires_grad();
    Tensor trans = Tensor::randn({batch, K, 3}, gen, DType::F32, 0, 2.0).set_requires_grad();
    const auto t0 = std::chrono::steady_clock::now();
    Tensor v = layer.deform(layer.body(), layer.pose(dofs), angles, trans);
    Tensor loss = ops::mean(ops::mul(v, v));
    const auto t1 = std::chrono::steady_clock::now();
    loss.backward();
    const auto t2 = std::chrono::steady_clock::now();
    if (r < 2) continue;  // warm-up
    fwd_ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    total_ms.push_back(std::chrono::duration<double, std::milli>(t2 - t0).count());
  }
  std::printf("deformation layer, ddc (V=%lld, K=%lld, D=%lld), batch %d, float32, %d threads\n",
              static_cast<long long>(layer.body().rest.size(0)), static_cast<long long>(K),
              static_cast<long long>(D), batch, num_threads());
  std::printf("forward           median %.2f ms (min %.2f) over %d runs\n", median(fwd_ms),
              *std::min_element(fwd_ms.begin(), fwd_ms.end()), repeats);
  std::printf("forward+backward  median %.2f ms (min %.2f) over %d runs\n", median(total_ms),
              *std::min_element(total_ms.begin(), total_ms.end()), repeats);
  if (profiling_enabled()) std::printf("\n%s", profile_report().c_str());
  return 0;
}
