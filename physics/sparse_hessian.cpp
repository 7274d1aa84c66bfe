#include "physics/sparse_hessian.h"

#include <algorithm>
#include <cmath>

#include "graph/error.h"

namespace weft::physics {

SparseHessian::SparseHessian(int n, const std::vector<std::array<int, 2>>& pairs)
    : num_vertices_(n) {
  std::vector<std::vector<int>> upper(n);
  for (const auto& p : pairs) {
    const int i = std::min(p[0], p[1]), j = std::max(p[0], p[1]);
    WEFT_CHECK(i >= 0 && j < n, "sparse hessian: pair (", p[0], ", ", p[1], ") outside ", n,
               " vertices");
    if (i != j) upper[j].push_back(i);
  }
  upper_start_.assign(n + 1, 0);
  for (int j = 0; j < n; ++j) {
    auto& u = upper[j];
    std::sort(u.begin(), u.end());
    u.erase(std::unique(u.begin(), u.end()), u.end());
    u.push_back(j);
    upper_start_[j + 1] = upper_start_[j] + static_cast<int>(u.size());
    upper_.insert(upper_.end(), u.begin(), u.end());
  }
  col_start_.assign(3 * n + 1, 0);
  diag_index_.assign(3 * n, 0);
  for (int j = 0; j < n; ++j) {
    const int deg = upper_start_[j + 1] - upper_start_[j];
    for (int b = 0; b < 3; ++b) {
      const int c = 3 * j + b;
      for (int k = 0; k + 1 < deg; ++k)
        for (int a = 0; a < 3; ++a) row_.push_back(3 * upper_[upper_start_[j] + k] + a);
      for (int a = 0; a <= b; ++a) row_.push_back(3 * j + a);
      col_start_[c + 1] = static_cast<int>(row_.size());
      diag_index_[c] = col_start_[c + 1] - 1;
    }
  }
  values_.assign(row_.size(), 0.0);
}

void SparseHessian::set_zero() { std::fill(values_.begin(), values_.end(), 0.0); }

int SparseHessian::block_position(int i, int j) const {
  const int* begin = upper_.data() + upper_start_[j];
  const int* end = upper_.data() + upper_start_[j + 1];
  const int* it = std::lower_bound(begin, end, i);
  WEFT_CHECK(it != end && *it == i, "sparse hessian: block (", i, ", ", j,
             ") is not in the pattern");
  return static_cast<int>(it - begin);
}

int SparseHessian::find_block(int i, int j) const {
  const int* begin = upper_.data() + upper_start_[j];
  const int* end = upper_.data() + upper_start_[j + 1];
  const int* it = std::lower_bound(begin, end, i);
  return it != end && *it == i ? static_cast<int>(it - begin) : -1;
}

void SparseHessian::bound_into(SparseHessian& coarse) const {
  WEFT_CHECK(coarse.num_vertices_ == num_vertices_, "sparse hessian: bound of ", num_vertices_,
             " vertices into ", coarse.num_vertices_);
  coarse.set_zero();
  // Two passes: a diagonal block is copied over, so the bounds are added after all copies.
  std::vector<std::array<double, 2>> bounds;  // (vertex, ‖B‖_F) per dropped block end
  for (int j = 0; j < num_vertices_; ++j) {
    for (int k = upper_start_[j]; k < upper_start_[j + 1]; ++k) {
      const int i = upper_[k];
      const int kc = coarse.find_block(i, j);
      const int local = k - upper_start_[j];
      if (kc >= 0) {
        for (int b = 0; b < 3; ++b) {
          const double* src = values_.data() + col_start_[3 * j + b] + 3 * local;
          double* dst = coarse.values_.data() + coarse.col_start_[3 * j + b] + 3 * kc;
          const int rows = i == j ? b + 1 : 3;
          for (int a = 0; a < rows; ++a) dst[a] = src[a];
        }
        continue;
      }
      double norm2 = 0;
      for (int b = 0; b < 3; ++b) {
        const double* src = values_.data() + col_start_[3 * j + b] + 3 * local;
        for (int a = 0; a < 3; ++a) norm2 += src[a] * src[a];
      }
      bounds.push_back({static_cast<double>(i), std::sqrt(norm2)});
      bounds.push_back({static_cast<double>(j), std::sqrt(norm2)});
    }
  }
  for (const auto& [v, bound] : bounds)
    for (int a = 0; a < 3; ++a) coarse.values_[coarse.diag_index_[3 * static_cast<int>(v) + a]] += bound;
}

// Adds the 3×3 block of `h` at (row0, col0) (leading dimension ld) to block (i, j), i <= j.
void SparseHessian::add_block(int i, int j, const double* h, int ld, int row0, int col0) {
  const int k = block_position(i, j);
  for (int b = 0; b < 3; ++b) {
    double* col = values_.data() + col_start_[3 * j + b] + 3 * k;
    const double* src = h + (col0 + b) * ld + row0;
    if (i == j) {
      for (int a = 0; a <= b; ++a) col[a] += src[a];
    } else {
      for (int a = 0; a < 3; ++a) col[a] += src[a];
    }
  }
}

void SparseHessian::add(const int* v, int k, const double* h) {
  const int ld = 3 * k;
  for (int q = 0; q < k; ++q)
    for (int p = 0; p < k; ++p) {
      if (v[p] < v[q] || p == q) {
        add_block(v[p], v[q], h, ld, 3 * p, 3 * q);
      }
    }
}

void SparseHessian::add_diagonal_block(int i, const Eigen::Matrix3d& block) {
  add_block(i, i, block.data(), 3, 0, 0);
}

void SparseHessian::add_to_diagonal(double delta) {
  for (int d : diag_index_) values_[d] += delta;
}

void SparseHessian::add_to_diagonal(const Eigen::VectorXd& d) {
  for (int c = 0; c < rows(); ++c) values_[diag_index_[c]] += d[c];
}

Eigen::VectorXd SparseHessian::multiply(const Eigen::VectorXd& x) const {
  Eigen::VectorXd y = Eigen::VectorXd::Zero(rows());
  for (int c = 0; c < rows(); ++c) {
    double acc = 0;
    const double xc = x[c];
    for (int p = col_start_[c]; p < col_start_[c + 1]; ++p) {
      const int r = row_[p];
      acc += values_[p] * x[r];
      if (r != c) y[r] += values_[p] * xc;
    }
    y[c] += acc;
  }
  return y;
}

Eigen::SparseMatrix<double> SparseHessian::to_full() const {
  std::vector<Eigen::Triplet<double>> t;
  for (int c = 0; c < rows(); ++c)
    for (int p = col_start_[c]; p < col_start_[c + 1]; ++p) {
      t.emplace_back(row_[p], c, values_[p]);
      if (row_[p] != c) t.emplace_back(c, row_[p], values_[p]);
    }
  Eigen::SparseMatrix<double> m(rows(), rows());
  m.setFromTriplets(t.begin(), t.end());
  return m;
}

}  // namespace weft::physics
