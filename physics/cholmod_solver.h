#pragma once
// A thin owner of CHOLMOD state for one SparseHessian pattern: the symbolic analysis
// (fill-reducing ordering, supernodes) runs once, numeric factorisations reuse it.
#include <Eigen/Core>
#include <memory>

#include "physics/sparse_hessian.h"

namespace weft::physics {

enum class CholeskyKind { automatic, simplicial, supernodal };

// Fill-reducing ordering of the symbolic analysis.
enum class CholeskyOrdering {
  amd,                // approximate minimum degree
  nested_dissection,  // CHOLMOD's nested dissection (METIS separators + constrained AMD)
  metis,              // METIS's nested dissection
};

// CHOLMOD's relaxed amalgamation: a supernode is merged with its parent while the merged
// one has fewer than nrelax[0] columns, or fewer than nrelax[1] (nrelax[2]) columns and
// at most a fraction zrelax[0] (zrelax[1], zrelax[2]) of explicit zeros. CHOLMOD's own
// defaults are {4, 16, 48} and {0.8, 0.1, 0.05}. Debian's CHOLMOD opens an OpenMP region
// (with a futex wake at its barrier even on one thread) per supernode, so on cloth
// meshes fewer, wider supernodes are cheaper (docs/BENCHMARKS.md).
struct SupernodeAmalgamation {
  double nrelax[3] = {16, 64, 256};
  double zrelax[3] = {0.8, 0.2, 0.1};
};

class CholmodSolver {
 public:
  // Every CHOLMOD call runs on the calling thread only (CHOLMOD's own OpenMP teams are
  // switched off for it) and is deterministic: the METIS-based orderings are computed
  // under a process-wide lock, because METIS's random number state is global, so
  // simulators built in parallel get the same ordering as one built alone.
  explicit CholmodSolver(const SparseHessian& pattern,
                         CholeskyKind kind = CholeskyKind::automatic,
                         CholeskyOrdering ordering = CholeskyOrdering::amd,
                         SupernodeAmalgamation amalgamation = {});
  ~CholmodSolver();
  CholmodSolver(const CholmodSolver&) = delete;
  CholmodSolver& operator=(const CholmodSolver&) = delete;

  // Factorises the current values of `h` (same pattern as at construction). Returns false
  // if the matrix is not positive definite.
  bool factorize(const SparseHessian& h);
  // Solves with the last successful factorisation.
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;
  bool has_factor() const { return factored_; }
  // From the symbolic analysis: nonzeros of L, flops of one numeric factorisation, and
  // whether CHOLMOD chose (or was told to use) the supernodal method.
  double factor_nonzeros() const;
  double factor_flops() const;
  bool supernodal() const;

 private:
  struct State;
  std::unique_ptr<State> s_;
  bool factored_ = false;
};

}  // namespace weft::physics
