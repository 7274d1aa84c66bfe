#include "tests/gradcheck/cases.h"

namespace weft::testing {

WEFT_GRADCHECK_CASES(matmul) {
  return {uniform_case("matmul", "[3,4]@[4,5]", {{3, 4}, {4, 5}}),
          uniform_case("matmul", "batched [2,3,4]@[2,4,2]", {{2, 3, 4}, {2, 4, 2}}),
          uniform_case("matmul", "shared [2,3,4]@[4,5]", {{2, 3, 4}, {4, 5}}),
          uniform_case("matmul", "size-1 [1,1]@[1,3]", {{1, 1}, {1, 3}}),
          uniform_case("matmul", "batched size-1 [3,1,2]@[3,2,1]", {{3, 1, 2}, {3, 2, 1}})};
}

WEFT_GRADCHECK_CASES(linear) {
  return {uniform_case("linear", "x [3,4] w [5,4] b [5]", {{3, 4}, {5, 4}, {5}}),
          uniform_case("linear", "x [2,3,4] w [2,4] no bias", {{2, 3, 4}, {2, 4}}),
          uniform_case("linear", "x [4] w [3,4] b [3]", {{4}, {3, 4}, {3}}),
          uniform_case("linear", "x [1,1] w [1,1] b [1]", {{1, 1}, {1, 1}, {1}})};
}

}  // namespace weft::testing
