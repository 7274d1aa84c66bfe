#pragma once
// A symmetric 3n × 3n matrix with a fixed sparsity pattern made of 3×3 vertex blocks,
// stored as its upper triangle in compressed columns (the layout CHOLMOD factorises with
// stype = 1). The pattern is built once from the vertex pairs that share an element;
// every Newton iteration only overwrites the values, so the symbolic analysis is reused.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <vector>

namespace weft::physics {

class SparseHessian {
 public:
  SparseHessian() = default;
  // `pairs` lists vertex pairs (either order) coupled by some element; the diagonal
  // blocks are always present.
  SparseHessian(int num_vertices, const std::vector<std::array<int, 2>>& pairs);

  int rows() const { return 3 * num_vertices_; }
  int num_vertices() const { return num_vertices_; }
  long nonzeros() const { return static_cast<long>(values_.size()); }

  void set_zero();
  // Adds the 3k × 3k element matrix `h` (column-major, all blocks) of the k vertices `v`;
  // the vertices must be distinct and every pair must be in the pattern.
  void add(const int* v, int k, const double* h);
  template <int K>
  void add(const std::array<int, K>& v, const Eigen::Matrix<double, 3 * K, 3 * K>& h) {
    add(v.data(), K, h.data());
  }
  void add_diagonal_block(int i, const Eigen::Matrix3d& block);
  void add_to_diagonal(double delta);          // += delta · I
  void add_to_diagonal(const Eigen::VectorXd& d);  // += diag(d), d of size 3n

  // Writes into `coarse` (a pattern that is a subset of this one) an upper bound of this
  // matrix in the Loewner order: the blocks both patterns hold are copied, and each
  // block B_ij that `coarse` lacks is dropped with ‖B_ij‖_F·I added to the diagonal
  // blocks of i and j (the dropped part [0 B; Bᵀ 0] is below diag(‖B‖I, ‖B‖I)).
  void bound_into(SparseHessian& coarse) const;
  // y = H x using both triangles.
  Eigen::VectorXd multiply(const Eigen::VectorXd& x) const;
  // The full symmetric matrix, for tests and small problems.
  Eigen::SparseMatrix<double> to_full() const;

  const std::vector<int>& column_starts() const { return col_start_; }
  const std::vector<int>& row_indices() const { return row_; }
  std::vector<double>& values() { return values_; }
  const std::vector<double>& values() const { return values_; }

 private:
  int block_position(int i, int j) const;  // index of i in the upper neighbours of j (i <= j)
  int find_block(int i, int j) const;      // the same, or −1 if (i, j) is not in the pattern
  void add_block(int i, int j, const double* h, int ld, int row0, int col0);

  int num_vertices_ = 0;
  std::vector<int> upper_start_;   // per vertex j: start of its neighbours i <= j (sorted)
  std::vector<int> upper_;         // concatenated neighbour lists, j itself last
  std::vector<int> col_start_;     // 3n + 1 scalar column starts
  std::vector<int> row_;           // scalar row indices
  std::vector<int> diag_index_;    // 3n positions of the diagonal entries
  std::vector<double> values_;
};

}  // namespace weft::physics
