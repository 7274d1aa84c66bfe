#pragma once
// A thin owner of CHOLMOD state for one SparseHessian pattern: the symbolic analysis
// (fill-reducing ordering, supernodes) runs once, numeric factorisations reuse it.
#include <Eigen/Core>
#include <memory>

#include "physics/sparse_hessian.h"

namespace weft::physics {

class CholmodSolver {
 public:
  explicit CholmodSolver(const SparseHessian& pattern);
  ~CholmodSolver();
  CholmodSolver(const CholmodSolver&) = delete;
  CholmodSolver& operator=(const CholmodSolver&) = delete;

  // Factorises the current values of `h` (same pattern as at construction). Returns false
  // if the matrix is not positive definite.
  bool factorize(const SparseHessian& h);
  // Solves with the last successful factorisation.
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;
  bool has_factor() const { return factored_; }

 private:
  struct State;
  std::unique_ptr<State> s_;
  bool factored_ = false;
};

}  // namespace weft::physics
