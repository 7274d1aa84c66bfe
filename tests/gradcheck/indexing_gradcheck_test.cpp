#include "tests/gradcheck/cases.h"

namespace weft::testing {
namespace {

// int64 tensor of `shape` with entries uniform in [0, n).
Tensor random_index(Generator& g, const Shape& shape, int64_t n) {
  std::vector<int64_t> v(static_cast<size_t>(shape_numel(shape)));
  for (auto& e : v) e = g.integer(0, n - 1);
  return Tensor::from_indices(shape, v);
}

GradcheckCase select_case(const std::string& name, Shape xs, int64_t axis,
                          std::vector<int64_t> index) {
  GradcheckCase c;
  c.op = "index_select";
  c.name = name;
  c.attrs = {{"axis", axis}};
  c.make_inputs = [xs, index](Generator& g) {
    return std::vector<Tensor>{uniform64(g, xs),
                               Tensor::from_indices({static_cast<int64_t>(index.size())}, index)};
  };
  return c;
}

GradcheckCase gather_case(const std::string& name, Shape xs, int64_t axis, Shape is) {
  GradcheckCase c;
  c.op = "gather";
  c.name = name;
  c.attrs = {{"axis", axis}};
  c.make_inputs = [xs, axis, is](Generator& g) {
    const int64_t n = xs[axis < 0 ? axis + xs.size() : axis];
    return std::vector<Tensor>{uniform64(g, xs), random_index(g, is, n)};
  };
  return c;
}

GradcheckCase scatter_case(const std::string& name, Shape xs, int64_t axis, Shape is, Shape ss) {
  GradcheckCase c;
  c.op = "scatter_add";
  c.name = name;
  c.attrs = {{"axis", axis}};
  c.make_inputs = [xs, axis, is, ss](Generator& g) {
    const int64_t n = xs[axis < 0 ? axis + xs.size() : axis];
    return std::vector<Tensor>{uniform64(g, xs), random_index(g, is, n), uniform64(g, ss)};
  };
  return c;
}

}  // namespace

WEFT_GRADCHECK_CASES(index_select) {
  return {select_case("[4,3] axis 0 repeated", {4, 3}, 0, {3, 0, 3, 1}),
          select_case("[2,5,2] axis 1", {2, 5, 2}, 1, {4, 0}),
          select_case("[3,1] axis -1", {3, 1}, -1, {0, 0, 0})};
}
WEFT_GRADCHECK_CASES(gather) {
  return {gather_case("[3,4] axis 0 index [2,4]", {3, 4}, 0, {2, 4}),
          gather_case("[2,5,3] axis 1 index [2,2,3]", {2, 5, 3}, 1, {2, 2, 3}),
          gather_case("[3,4] axis -1 index [2,6] (smaller on axis 0)", {3, 4}, -1, {2, 6})};
}
WEFT_GRADCHECK_CASES(scatter_add) {
  return {scatter_case("[4,3] axis 0 index [2,3]", {4, 3}, 0, {2, 3}, {2, 3}),
          scatter_case("[4,3] axis 0 src [3,4] larger than index [2,3]", {4, 3}, 0, {2, 3}, {3, 4}),
          scatter_case("[2,3,5] axis -1 index [2,3,4]", {2, 3, 5}, -1, {2, 3, 4}, {2, 3, 4})};
}

}  // namespace weft::testing
