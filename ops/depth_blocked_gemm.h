// Matrix products C = A·B summed over their depth (the reduction index) in short chains,
// for float32 accuracy.
//
// Eigen's GEMM sums each output over one depth panel (its kc) in a register, then adds
// the panel's sum into C. Its default kc on this machine is 928 for float32 (AVX-512,
// 48 KiB L1): a float32 result carries the rounding of up to ~900 additions in a row
// (relative error ~ u·√kc, u = 2⁻²⁴), and ResNet's deep 3×3 convs came out 2–3× further
// from float64 than PyTorch/oneDNN's. Here
//   - Eigen's depth panel is capped at kGemmDepthBlock terms (its L1 cache size is set so
//     that its own blocking heuristic picks kc ≤ 64; see limit_gemm_depth_panel), and
//   - the panels of up to kGemmDepthSuperBlock terms are summed into a partial of C,
//     the partials into C,
// so no chain of float32 additions is longer than 64 + 8 + depth/512 terms. On ResNet
// conv shapes (depth 576–4608) the output's relative L2 error goes from 2–4e-7 to
// ~1.1e-7, below PyTorch's ~1.5e-7 (docs/BENCHMARKS.md, accuracy against PyTorch).
// Speed: one Eigen product per 512 terms of depth (most ResNet products are one or a few);
// the short panel costs one more pass over C's register tiles per 64 terms. Measured: a
// single-threaded conv is as fast as before, a ResNet training step at two threads 2–3.5 %
// slower (docs/BENCHMARKS.md).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <type_traits>
#include <vector>

namespace weft {

constexpr int64_t kGemmDepthBlock = 64;        // Eigen's depth panel: terms in one register
constexpr int64_t kGemmDepthSuperBlock = 512;  // terms summed into one partial of C

// Sets Eigen's L1 cache size (process-wide, once) so that its blocking heuristic picks a
// float32 depth panel of at most kGemmDepthBlock; L2 and L3 keep their detected sizes.
// Returns the depth panel Eigen now uses for a deep float32 product on one thread.
int64_t limit_gemm_depth_panel();

namespace detail {
// The calling thread's [m, n] partial for super-blocks (grows, kept across calls).
template <class T>
T* depth_partial(int64_t elements) {
  thread_local std::vector<T> buffer;
  if (static_cast<int64_t>(buffer.size()) < elements) {
    buffer.clear();
    buffer.shrink_to_fit();
    buffer.resize(elements);
  }
  return buffer.data();
}
}  // namespace detail

// C = A·B, or C += A·B when accumulate. A is an [m, k] and B a [k, n] Eigen expression
// with direct access (matrices, maps, their transposes); C is an [m, n] row-major map or
// matrix that aliases neither. Single-threaded inside an OpenMP region, Eigen-threaded
// outside one, like a plain product.
template <class Dst, class Lhs, class Rhs>
void gemm_in_depth_blocks(Dst&& C, const Lhs& A, const Rhs& B, bool accumulate) {
  using T = typename std::decay_t<Dst>::Scalar;
  using RowMat = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const int64_t m = C.rows(), n = C.cols(), k = A.cols();
  if (k == 0) {
    if (!accumulate) C.setZero();
    return;
  }
  for (int64_t s0 = 0; s0 < k; s0 += kGemmDepthSuperBlock) {
    const int64_t d = std::min(kGemmDepthSuperBlock, k - s0);
    const auto product = A.middleCols(s0, d) * B.middleRows(s0, d);
    if (s0 == 0 && !accumulate) {
      C.noalias() = product;  // the first super-block of a fresh product is summed in C
    } else {
      Eigen::Map<RowMat> partial(detail::depth_partial<T>(m * n), m, n);
      partial.noalias() = product;
      C += partial;
    }
  }
}

}  // namespace weft
