#include "tests/gradcheck/cases.h"

namespace weft::testing {
namespace {

Attrs axes(std::vector<int64_t> a, bool keepdim = false) {
  return {{"axes", std::move(a)}, {"keepdim", keepdim}};
}

// All axes, one inner axis, a non-contiguous axis set, keepdim, negative and size-1 axes.
std::vector<GradcheckCase> reduce_cases(const std::string& op, double lo, double hi) {
  return {
      uniform_case(op, "all of [2,3]", {{2, 3}}, axes({}), lo, hi),
      uniform_case(op, "axis 1 of [2,3,4]", {{2, 3, 4}}, axes({1}), lo, hi),
      uniform_case(op, "axes 0,2 keepdim of [3,2,5]", {{3, 2, 5}}, axes({0, 2}, true), lo, hi),
      uniform_case(op, "axis -1 of [1,5]", {{1, 5}}, axes({-1}), lo, hi),
      uniform_case(op, "size-1 axis 1 of [3,1,2] keepdim", {{3, 1, 2}}, axes({1}, true), lo, hi),
      uniform_case(op, "axes 0,2 of [3,1,4] (size-1 between)", {{3, 1, 4}}, axes({0, 2}), lo, hi),
  };
}

}  // namespace

WEFT_GRADCHECK_CASES(sum) { return reduce_cases("sum", -1, 1); }
WEFT_GRADCHECK_CASES(mean) { return reduce_cases("mean", -1, 1); }
// Random continuous values have no ties, so the argmax is unique and stable under ±ε.
WEFT_GRADCHECK_CASES(max) { return reduce_cases("max", -1, 1); }
WEFT_GRADCHECK_CASES(norm) { return reduce_cases("norm", 0.2, 1); }

}  // namespace weft::testing
