// Eigen's depth panel for float32 products, capped for accuracy (ops/depth_blocked_gemm.h).
#include "ops/depth_blocked_gemm.h"

namespace weft {
namespace {

// The depth panel Eigen's heuristic picks for a deep float32 product on one thread.
int64_t eigen_depth_panel() {
  Eigen::Index k = 1 << 14, m = 256, n = 256;
  Eigen::internal::computeProductBlockingSizes<float, float>(k, m, n, Eigen::Index(1));
  return k;
}

int64_t set_depth_panel() {
  std::ptrdiff_t l1 = 0, l2 = 0, l3 = 0;
  Eigen::internal::manage_caching_sizes(Eigen::GetAction, &l1, &l2, &l3);
  const int64_t target = kGemmDepthBlock;
  // The largest L1 size for which the heuristic's panel is at most the target (the panel
  // grows with L1): bisect between 256 bytes and the detected size.
  std::ptrdiff_t hi = l1, lo = 256;
  if (eigen_depth_panel() <= target) return eigen_depth_panel();
  while (hi - lo > 16) {
    const std::ptrdiff_t mid = (lo + hi) / 2;
    Eigen::setCpuCacheSizes(mid, l2, l3);
    if (eigen_depth_panel() <= target) lo = mid;
    else hi = mid;
  }
  Eigen::setCpuCacheSizes(lo, l2, l3);
  return eigen_depth_panel();
}

// Set when the library loads, before any thread runs a product.
const int64_t depth_panel_at_load = limit_gemm_depth_panel();

}  // namespace

int64_t limit_gemm_depth_panel() {
  static const int64_t panel = set_depth_panel();
  return panel;
}

}  // namespace weft
