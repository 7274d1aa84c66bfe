#pragma once
// The gradient-check harness: compares an op's backward with central differences in
// float64. Each differentiable op has at least one case (WEFT_GRADCHECK_CASES in
// tests/gradcheck/); the suite fails for an op without one.
//
// Method: L(x) = Σ r ⊙ op(x) with a fixed random r; the analytic gradient is the
// backward of r; the numeric one is (L(x + εe_i) − L(x − εe_i)) / 2ε per element.
// An element passes when |analytic − numeric| ≤ atol + rtol·|numeric|.
// Defaults (documented in docs/ENGINE.md): ε = 1e-6, atol = 1e-6, rtol = 1e-5; in
// float64 the observed error is typically 1e-9..1e-7 relative. Inputs must keep away
// from kinks (relu at 0, abs at 0, max ties, clamp bounds): cases choose them so.
#include <functional>
#include <string>
#include <vector>

#include "graph/attrs.h"
#include "graph/tensor.h"

namespace weft {

struct GradcheckCase {
  std::string op;    // registered op name
  std::string name;  // what this case covers, e.g. "broadcast [3,1] with [4]"
  std::function<std::vector<Tensor>(Generator&)> make_inputs;  // float64 (or int64) inputs
  Attrs attrs;
  std::vector<int> wrt;  // inputs to check; empty: every float input
  // Optional: a function of the inputs to check instead of a bare `apply(op)` (for ops
  // whose inputs must satisfy a constraint, e.g. a normalised quaternion).
  std::function<Tensor(const std::vector<Tensor>&)> function;
};

struct GradcheckOptions {
  double eps = 1e-6;
  double atol = 1e-6;
  double rtol = 1e-5;
  uint64_t seed = 1234;
};

struct GradcheckResult {
  bool passed = false;
  double max_abs_error = 0;
  double max_rel_error = 0;   // max over elements of |a − n| / max(|n|, 1)
  double norm_rel_error = 0;  // ‖a − n‖₂ / max(‖n‖₂, 1e-300) over all checked elements
  int64_t elements = 0;
  std::string message;  // the first failing element, or a summary
};

GradcheckResult gradcheck(const GradcheckCase& c, const GradcheckOptions& options = {});

// All registered cases (filled by WEFT_GRADCHECK_CASES at static initialisation).
std::vector<GradcheckCase>& gradcheck_cases();

namespace detail {
struct GradcheckRegistrar {
  explicit GradcheckRegistrar(std::vector<GradcheckCase> (*make)()) {
    for (auto& c : make()) gradcheck_cases().push_back(std::move(c));
  }
};
}  // namespace detail

#define WEFT_GRADCHECK_CASES(ident)                                                \
  static std::vector<::weft::GradcheckCase> weft_make_gradcheck_##ident();          \
  static const ::weft::detail::GradcheckRegistrar weft_gradcheck_registrar_##ident( \
      &weft_make_gradcheck_##ident);                                                \
  static std::vector<::weft::GradcheckCase> weft_make_gradcheck_##ident()

}  // namespace weft
