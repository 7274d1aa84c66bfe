#include "tests/gradcheck/cases.h"

namespace weft::testing {

// batch_norm inputs: x, weight, bias, then fresh running statistics (mean ~0, var ~1, not
// checked: they get no gradient). In training the forward updates the running statistics
// in place on every evaluation, but the output depends only on the batch statistics, so
// the central differences see one function.
// block > 1: x is blocked [N, C/block, ..., block].
static GradcheckCase bn_case(const std::string& name, Shape x, bool training,
                             int64_t block = 1, bool relu = false, bool residual = false) {
  GradcheckCase c;
  c.op = "batch_norm";
  c.name = name;
  c.attrs = {{"training", training}, {"momentum", 0.1}, {"eps", 1e-5}};
  if (block > 1) c.attrs.set("channel_block", block);
  if (relu) c.attrs.set("relu", true);
  c.wrt = residual ? std::vector<int>{0, 1, 2, 5} : std::vector<int>{0, 1, 2};
  const int64_t C = x[1] * block;
  c.make_inputs = [x, C, residual](Generator& g) {
    std::vector<Tensor> in{uniform64(g, x, -2, 2), uniform64(g, {C}, 0.5, 1.5),
                           uniform64(g, {C}, -1, 1), uniform64(g, {C}, -0.5, 0.5),
                           uniform64(g, {C}, 0.5, 2.0)};
    if (residual) in.push_back(uniform64(g, x, -1, 1));
    return in;
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
      bn_case("training, channel blocks of 8 [2,2,3,2,8]", {2, 2, 3, 2, 8}, true, 8),
      bn_case("eval, channel blocks of 16 [2,1,2,2,16]", {2, 1, 2, 2, 16}, false, 16),
      // relu fused: x in [-2, 2] keeps the normalised values away from 0 except by chance;
      // the seeds used have no value within the finite-difference step of the kink.
      bn_case("training + relu [3,2,3,2]", {3, 2, 3, 2}, true, 1, true),
      bn_case("training + relu, channel blocks of 8 [2,1,3,2,8]", {2, 1, 3, 2, 8}, true, 8, true),
      bn_case("eval + relu [2,3,2,3]", {2, 3, 2, 3}, false, 1, true),
      bn_case("training + residual [3,2,3,2]", {3, 2, 3, 2}, true, 1, false, true),
      bn_case("training + residual + relu, channel blocks of 8 [2,1,3,2,8]", {2, 1, 3, 2, 8},
              true, 8, true, true),
      bn_case("eval + residual + relu [2,3,2,3]", {2, 3, 2, 3}, false, 1, true, true),
  };
}

}  // namespace weft::testing
