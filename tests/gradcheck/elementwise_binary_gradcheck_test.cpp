#include "tests/gradcheck/cases.h"

namespace weft::testing {

// Shapes that exercise broadcasting: equal, scalar, trailing, leading size-1 axes.
static std::vector<GradcheckCase> broadcast_cases(const std::string& op, double lo, double hi) {
  return {
      uniform_case(op, "same [2,3]", {{2, 3}, {2, 3}}, {}, lo, hi),
      uniform_case(op, "broadcast [3,1] [4]", {{3, 1}, {4}}, {}, lo, hi),
      uniform_case(op, "broadcast [1] [2,1,3]", {{1}, {2, 1, 3}}, {}, lo, hi),
      uniform_case(op, "scalar [] [5]", {{}, {5}}, {}, lo, hi),
      uniform_case(op, "size-1 [1,1] [1,1]", {{1, 1}, {1, 1}}, {}, lo, hi),
  };
}

WEFT_GRADCHECK_CASES(add) { return broadcast_cases("add", -1, 1); }
WEFT_GRADCHECK_CASES(sub) { return broadcast_cases("sub", -1, 1); }
WEFT_GRADCHECK_CASES(mul) { return broadcast_cases("mul", -1, 1); }
WEFT_GRADCHECK_CASES(div) { return broadcast_cases("div", 0.5, 2); }
WEFT_GRADCHECK_CASES(scale) {
  return {uniform_case("scale", "[3,4]", {{3, 4}}, {{"s", -2.5}})};
}
WEFT_GRADCHECK_CASES(add_scalar) {
  return {uniform_case("add_scalar", "[3,4]", {{3, 4}}, {{"s", 0.7}})};
}

}  // namespace weft::testing
