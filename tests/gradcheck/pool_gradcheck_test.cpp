#include <algorithm>
#include <numeric>

#include "tests/gradcheck/cases.h"

namespace weft::testing {

// Max pooling has a kink wherever two window entries tie: the inputs are a random
// permutation of well-separated values, so no tie is within ε of another.
static GradcheckCase max_case(const std::string& name, Shape x, int64_t k, int64_t s,
                              int64_t p) {
  GradcheckCase c;
  c.op = "max_pool2d";
  c.name = name;
  c.attrs = {{"kernel", k}, {"stride", s}, {"padding", p}};
  c.make_inputs = [x](Generator& g) {
    const int64_t n = shape_numel(x);
    std::vector<double> v(n);
    std::iota(v.begin(), v.end(), 0.0);
    for (int64_t i = n - 1; i > 0; --i)
      std::swap(v[i], v[static_cast<int64_t>(g.uniform() * (i + 1)) % (i + 1)]);
    for (double& e : v) e = 0.1 * e - 1.0;
    return std::vector<Tensor>{Tensor::from_data(x, v, DType::F64)};
  };
  return c;
}

WEFT_GRADCHECK_CASES(max_pool2d) {
  return {
      max_case("3x3 stride 2 pad 1 odd", {2, 2, 7, 5}, 3, 2, 1),
      max_case("2x2 stride 2", {1, 3, 4, 6}, 2, 2, 0),
      max_case("overlapping 3x3 stride 1", {1, 1, 5, 5}, 3, 1, 0),
      max_case("size-1 dims", {1, 1, 1, 1}, 1, 1, 0),
  };
}

static GradcheckCase pool_case(const std::string& op, const std::string& name, Shape x,
                               int64_t k, int64_t s, int64_t p) {
  return uniform_case(op, name, {std::move(x)}, {{"kernel", k}, {"stride", s}, {"padding", p}});
}

WEFT_GRADCHECK_CASES(avg_pool2d) {
  return {
      pool_case("avg_pool2d", "3x3 stride 2 pad 1 odd", {2, 2, 7, 5}, 3, 2, 1),
      pool_case("avg_pool2d", "2x2 stride 2", {1, 3, 4, 6}, 2, 2, 0),
      pool_case("avg_pool2d", "overlapping 3x3 stride 1", {1, 1, 5, 5}, 3, 1, 0),
      pool_case("avg_pool2d", "size-1 dims", {1, 1, 1, 1}, 1, 1, 0),
  };
}

WEFT_GRADCHECK_CASES(adaptive_avg_pool2d) {
  return {
      uniform_case("adaptive_avg_pool2d", "7x5 -> 3x2 (overlapping bins)", {{2, 2, 7, 5}},
                   {{"out_h", int64_t{3}}, {"out_w", int64_t{2}}}),
      uniform_case("adaptive_avg_pool2d", "3x3 -> 5x4 (upsampling bins)", {{1, 2, 3, 3}},
                   {{"out_h", int64_t{5}}, {"out_w", int64_t{4}}}),
      uniform_case("adaptive_avg_pool2d", "size-1", {{1, 1, 1, 1}},
                   {{"out_h", int64_t{1}}, {"out_w", int64_t{1}}}),
  };
}

WEFT_GRADCHECK_CASES(global_avg_pool2d) {
  return {
      uniform_case("global_avg_pool2d", "[2,3,5,4]", {{2, 3, 5, 4}}),
      uniform_case("global_avg_pool2d", "size-1", {{1, 1, 1, 1}}),
  };
}

}  // namespace weft::testing
