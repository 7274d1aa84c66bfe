// Matrix products C = A·B summed over their depth (the reduction index) in short blocks,
// for float32 accuracy at no measurable cost in speed.
//
// Eigen's GEMM sums each output over a whole depth panel (its kc: ~300–600 terms on this
// machine) in one register, so a float32 result carries the rounding of hundreds of
// additions in a row (relative error ~ u·√kc, u = 2⁻²⁴). Summing blocks of
// kGemmDepthBlock terms into a partial, and the partials of up to kGemmDepthSuperBlock
// terms into the result, keeps every chain of additions short. On ResNet conv shapes
// (depth 576–4608) this takes the relative L2 error of the output from 2–4e-7 to
// 1.1–1.3e-7, below PyTorch/oneDNN's ~1.5e-7 (see docs/BENCHMARKS.md, accuracy against
// PyTorch). Speed: each block is one Eigen GEMM that packs the same panels Eigen would
// pack anyway; the extra work is one load and store of C per 64 terms, plus one pass
// over C per super-block.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <type_traits>
#include <vector>

namespace weft {

constexpr int64_t kGemmDepthBlock = 64;        // terms summed in one register
constexpr int64_t kGemmDepthSuperBlock = 512;  // terms summed into one partial of C

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
    const int64_t s1 = std::min(k, s0 + kGemmDepthSuperBlock);
    // The first super-block of a fresh product is summed in C itself.
    const bool into_c = s0 == 0 && !accumulate;
    Eigen::Map<RowMat> partial(into_c ? nullptr : detail::depth_partial<T>(m * n), m, n);
    for (int64_t b0 = s0; b0 < s1; b0 += kGemmDepthBlock) {
      const int64_t d = std::min(kGemmDepthBlock, s1 - b0);
      const auto product = A.middleCols(b0, d) * B.middleRows(b0, d);
      if (into_c) {
        if (b0 == s0) C.noalias() = product;
        else C.noalias() += product;
      } else {
        if (b0 == s0) partial.noalias() = product;
        else partial.noalias() += product;
      }
    }
    if (!into_c) C += partial;
  }
}

}  // namespace weft
