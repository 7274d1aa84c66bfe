#include "physics/cholmod_solver.h"

#include <cholmod.h>
#include <dlfcn.h>
#include <omp.h>

#include <algorithm>
#include <cstring>
#include <mutex>

#include "graph/error.h"

namespace weft::physics {

namespace {

// Debian's CHOLMOD opens OpenMP parallel regions with a fixed team of four threads inside
// its supernodal factorisation. On one simulation per core that only adds thread
// hand-offs (measured, 1k drape: 1.1 s cpu per frame with them, 0.62 s without), and
// inside simulate_windows' TBB tasks it oversubscribes the cores. A maximum of zero
// active levels makes every parallel region run on the calling thread alone; the setting
// belongs to the calling thread (libgomp keeps it per thread) and is restored afterwards,
// so OpenMP elsewhere (ops/) is unaffected.
class CallingThreadOnly {
 public:
  CallingThreadOnly() : saved_(omp_get_max_active_levels()) { omp_set_max_active_levels(0); }
  ~CallingThreadOnly() { omp_set_max_active_levels(saved_); }
  CallingThreadOnly(const CallingThreadOnly&) = delete;
  CallingThreadOnly& operator=(const CallingThreadOnly&) = delete;

 private:
  int saved_;
};

// CHOLMOD's supernodal kernels call the system BLAS. Debian's OpenBLAS (scripts/setup.sh
// installs the pthread build) would run them on all cores, with results that depend on
// the thread count; one thread per call keeps a simulation on its own core and
// deterministic, and simulate_windows runs windows side by side instead. Looked up at run
// time because the library is whichever BLAS the system provides (the reference BLAS
// has no threads). The serial and OpenMP builds of OpenBLAS are not used: the serial
// one corrupts its buffers when two threads call it at once (measured: factorisations
// on four threads failed), the OpenMP one hung with calls from TBB threads.
void use_one_blas_thread() {
  static std::once_flag once;
  std::call_once(once, [] {
    using SetThreads = void (*)(int);
    if (auto set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads")))
      set(1);
  });
}

// METIS keeps its random number state in globals and reseeds it per call: serialised,
// every analysis of the same pattern gives the same ordering.
std::mutex metis_mutex;

}  // namespace

struct CholmodSolver::State {
  cholmod_common common;
  cholmod_sparse* a = nullptr;
  cholmod_factor* l = nullptr;
};

CholmodSolver::CholmodSolver(const SparseHessian& pattern, CholeskyKind kind,
                             CholeskyOrdering ordering, SupernodeAmalgamation amalgamation)
    : s_(std::make_unique<State>()) {
  use_one_blas_thread();
  const CallingThreadOnly serial;
  cholmod_start(&s_->common);
  s_->common.quick_return_if_not_posdef = 1;
  s_->common.print = 0;
  s_->common.error_handler = nullptr;
  s_->common.nmethods = 1;
  s_->common.method[0].ordering = ordering == CholeskyOrdering::nested_dissection ? CHOLMOD_NESDIS
                                  : ordering == CholeskyOrdering::metis           ? CHOLMOD_METIS
                                                                                  : CHOLMOD_AMD;
  s_->common.postorder = 1;
  for (int k = 0; k < 3; ++k) {
    s_->common.nrelax[k] = static_cast<size_t>(amalgamation.nrelax[k]);
    s_->common.zrelax[k] = amalgamation.zrelax[k];
  }
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
  {
    std::unique_lock<std::mutex> lock(metis_mutex, std::defer_lock);
    if (ordering != CholeskyOrdering::amd) lock.lock();
    s_->l = cholmod_analyze(s_->a, &s_->common);
  }
  WEFT_CHECK(s_->l != nullptr, "cholmod: symbolic analysis failed (status ", s_->common.status,
             ")");
}

double CholmodSolver::factor_nonzeros() const { return s_->common.lnz; }
double CholmodSolver::factor_flops() const { return s_->common.fl; }
bool CholmodSolver::supernodal() const { return s_->l->is_super; }

CholmodSolver::~CholmodSolver() {
  const CallingThreadOnly serial;
  if (s_->l) cholmod_free_factor(&s_->l, &s_->common);
  if (s_->a) cholmod_free_sparse(&s_->a, &s_->common);
  cholmod_finish(&s_->common);
}

bool CholmodSolver::factorize(const SparseHessian& h) {
  const auto& v = h.values();
  std::copy(v.begin(), v.end(), static_cast<double*>(s_->a->x));
  const CallingThreadOnly serial;
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
  const CallingThreadOnly serial;
  cholmod_dense* x = cholmod_solve(CHOLMOD_A, s_->l, &rhs, &s_->common);
  WEFT_CHECK(x != nullptr, "cholmod: solve failed (status ", s_->common.status, ")");
  Eigen::VectorXd out = Eigen::Map<const Eigen::VectorXd>(static_cast<double*>(x->x), b.size());
  cholmod_free_dense(&x, &s_->common);
  return out;
}

}  // namespace weft::physics
