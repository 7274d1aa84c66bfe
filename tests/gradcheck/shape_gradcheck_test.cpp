#include "tests/gradcheck/cases.h"

namespace weft::testing {
namespace {

Attrs slice_attrs(int64_t axis, int64_t start, int64_t end, int64_t step) {
  return {{"axis", axis}, {"start", start}, {"end", end}, {"step", step}};
}

}  // namespace

WEFT_GRADCHECK_CASES(reshape) {
  return {uniform_case("reshape", "[2,3,4] to [4,-1]", {{2, 3, 4}}, {{"shape", Shape{4, -1}}}),
          uniform_case("reshape", "[1,5] to [5]", {{1, 5}}, {{"shape", Shape{5}}})};
}
WEFT_GRADCHECK_CASES(permute) {
  return {uniform_case("permute", "[2,3,4] dims 2,0,1", {{2, 3, 4}},
                       {{"dims", std::vector<int64_t>{2, 0, 1}}}),
          uniform_case("permute", "[1,3,1,2] dims 3,1,0,2", {{1, 3, 1, 2}},
                       {{"dims", std::vector<int64_t>{3, 1, 0, 2}}})};
}
WEFT_GRADCHECK_CASES(transpose) {
  return {uniform_case("transpose", "[3,5] 0,1", {{3, 5}},
                       {{"dim0", int64_t{0}}, {"dim1", int64_t{1}}}),
          uniform_case("transpose", "[2,3,4] -1,0", {{2, 3, 4}},
                       {{"dim0", int64_t{-1}}, {"dim1", int64_t{0}}})};
}
WEFT_GRADCHECK_CASES(slice) {
  return {uniform_case("slice", "[5,4] rows 1..4 (alias)", {{5, 4}}, slice_attrs(0, 1, 4, 1)),
          uniform_case("slice", "[3,7] cols 0..7 step 2", {{3, 7}}, slice_attrs(1, 0, 7, 2)),
          uniform_case("slice", "[1,6,3] axis 1 1..5 (alias)", {{1, 6, 3}}, slice_attrs(1, 1, 5, 1)),
          uniform_case("slice", "[4,5] axis 1 -4..-1 step 3", {{4, 5}}, slice_attrs(1, -4, -1, 3))};
}
WEFT_GRADCHECK_CASES(concat) {
  return {uniform_case("concat", "[2,3] [2,1] [2,4] axis 1", {{2, 3}, {2, 1}, {2, 4}},
                       {{"axis", int64_t{1}}}),
          uniform_case("concat", "[1,3] [2,3] axis 0", {{1, 3}, {2, 3}}, {{"axis", int64_t{0}}}),
          uniform_case("concat", "[2,1,3] [2,2,3] axis -2", {{2, 1, 3}, {2, 2, 3}},
                       {{"axis", int64_t{-2}}})};
}
WEFT_GRADCHECK_CASES(stack) {
  return {uniform_case("stack", "3 x [2,3] axis 0", {{2, 3}, {2, 3}, {2, 3}}, {{"axis", int64_t{0}}}),
          uniform_case("stack", "2 x [3,1] axis 2", {{3, 1}, {3, 1}}, {{"axis", int64_t{2}}}),
          uniform_case("stack", "2 x [2,3] axis -2", {{2, 3}, {2, 3}}, {{"axis", int64_t{-2}}})};
}

}  // namespace weft::testing
