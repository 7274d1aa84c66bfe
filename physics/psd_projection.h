#pragma once
// Projects a small symmetric element matrix to the nearest positive semi-definite one by
// clamping its negative eigenvalues to zero. A Cholesky attempt first skips the
// eigen-decomposition for the common, already positive-definite, case.
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

namespace weft::physics {

template <int N>
void project_to_psd(Eigen::Matrix<double, N, N>& h) {
  using Mat = Eigen::Matrix<double, N, N>;
  // Eigenvalues above -1e-12 · max diagonal: keep as is (rounding-level negativity is
  // harmless next to the mass term of the incremental potential).
  const double shift = 1e-12 * std::max(h.diagonal().cwiseAbs().maxCoeff(), 1e-300);
  Mat shifted = h;
  shifted.diagonal().array() += shift;
  Eigen::LLT<Mat> llt(shifted);
  if (llt.info() == Eigen::Success) return;
  Eigen::SelfAdjointEigenSolver<Mat> eig(h);
  const auto lambda = eig.eigenvalues().cwiseMax(0.0);
  h = eig.eigenvectors() * lambda.asDiagonal() * eig.eigenvectors().transpose();
}

}  // namespace weft::physics
