#include "physics/cholmod_solver.h"

#include <cholmod.h>

#include <algorithm>
#include <cstring>

#include "graph/error.h"

namespace weft::physics {

struct CholmodSolver::State {
  cholmod_common common;
  cholmod_sparse* a = nullptr;
  cholmod_factor* l = nullptr;
};

CholmodSolver::CholmodSolver(const SparseHessian& pattern, CholeskyKind kind)
    : s_(std::make_unique<State>()) {
  cholmod_start(&s_->common);
  s_->common.quick_return_if_not_posdef = 1;
  s_->common.print = 0;
  s_->common.error_handler = nullptr;
  s_->common.nmethods = 1;
  s_->common.method[0].ordering = CHOLMOD_AMD;
  s_->common.postorder = 1;
  // LLᵀ also in the simplicial case: an LDLᵀ factorisation succeeds on indefinite
  // matrices, and the Newton solver relies on failure to detect them.
  s_->common.final_ll = 1;
  if (kind == CholeskyKind::simplicial) s_->common.supernodal = CHOLMOD_SIMPLICIAL;
  if (kind == CholeskyKind::supernodal) s_->common.supernodal = CHOLMOD_SUPERNODAL;
  const int n = pattern.rows();
  const auto& cols = pattern.column_starts();
  const auto& rows = pattern.row_indices();
  s_->a = cholmod_allocate_sparse(n, n, rows.size(), /*sorted=*/1, /*packed=*/1, /*stype=*/1,
                                  CHOLMOD_REAL, &s_->common);
  WEFT_CHECK(s_->a != nullptr, "cholmod: could not allocate a ", n, " x ", n, " matrix");
  std::copy(cols.begin(), cols.end(), static_cast<int*>(s_->a->p));
  std::copy(rows.begin(), rows.end(), static_cast<int*>(s_->a->i));
  std::fill_n(static_cast<double*>(s_->a->x), rows.size(), 0.0);
  s_->l = cholmod_analyze(s_->a, &s_->common);
  WEFT_CHECK(s_->l != nullptr, "cholmod: symbolic analysis failed (status ", s_->common.status,
             ")");
}

double CholmodSolver::factor_nonzeros() const { return s_->common.lnz; }
double CholmodSolver::factor_flops() const { return s_->common.fl; }
bool CholmodSolver::supernodal() const { return s_->l->is_super; }

CholmodSolver::~CholmodSolver() {
  if (s_->l) cholmod_free_factor(&s_->l, &s_->common);
  if (s_->a) cholmod_free_sparse(&s_->a, &s_->common);
  cholmod_finish(&s_->common);
}

bool CholmodSolver::factorize(const SparseHessian& h) {
  const auto& v = h.values();
  std::copy(v.begin(), v.end(), static_cast<double*>(s_->a->x));
  const int ok = cholmod_factorize(s_->a, s_->l, &s_->common);
  factored_ = ok && s_->common.status == CHOLMOD_OK &&
              static_cast<int>(s_->l->minor) == static_cast<int>(s_->l->n);
  return factored_;
}

Eigen::VectorXd CholmodSolver::solve(const Eigen::VectorXd& b) const {
  WEFT_CHECK(factored_, "cholmod: solve without a successful factorisation");
  cholmod_dense rhs;
  std::memset(&rhs, 0, sizeof(rhs));
  rhs.nrow = b.size();
  rhs.ncol = 1;
  rhs.nzmax = b.size();
  rhs.d = b.size();
  rhs.x = const_cast<double*>(b.data());
  rhs.xtype = CHOLMOD_REAL;
  rhs.dtype = CHOLMOD_DOUBLE;
  cholmod_dense* x = cholmod_solve(CHOLMOD_A, s_->l, &rhs, &s_->common);
  WEFT_CHECK(x != nullptr, "cholmod: solve failed (status ", s_->common.status, ")");
  Eigen::VectorXd out = Eigen::Map<const Eigen::VectorXd>(static_cast<double*>(x->x), b.size());
  cholmod_free_dense(&x, &s_->common);
  return out;
}

}  // namespace weft::physics
