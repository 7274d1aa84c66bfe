#include "tests/gradcheck/cases.h"

namespace weft::testing {

// batch_norm inputs: x, weight, bias, then fresh running statistics (mean ~0, var ~1, not
// checked: they get no gradient). In training the forward updates the running statistics
// in place on every evaluation, but the output depends only on the batch statistics, so
// the central differences see one function.
static GradcheckCase bn_case(const std::string& name, Shape x, bool training) {
  GradcheckCase c;
  c.op = "batch_norm";
  c.name = name;
  c.attrs = {{"training", training}, {"momentum", 0.1}, {"eps", 1e-5}};
  c.wrt = {0, 1, 2};
  const int64_t C = x[1];
  c.make_inputs = [x, C](Generator& g) {
    return std::vector<Tensor>{uniform64(g, x, -2, 2), uniform64(g, {C}, 0.5, 1.5),
                               uniform64(g, {C}, -1, 1), uniform64(g, {C}, -0.5, 0.5),
                               uniform64(g, {C}, 0.5, 2.0)};
  };
  return c;
}

WEFT_GRADCHECK_CASES(batch_norm) {
  return {
      bn_case("training [3,2,3,2]", {3, 2, 3, 2}, true),
      bn_case("training [2,3] (rank 2)", {4, 3}, true),
      bn_case("training N=1 [1,2,3,1]", {1, 2, 3, 1}, true),
      bn_case("eval [2,3,2,3]", {2, 3, 2, 3}, false),
      bn_case("eval size-1 [1,1,1,1]", {1, 1, 1, 1}, false),
  };
}

}  // namespace weft::testing
