#include "tests/gradcheck/cases.h"

namespace weft::testing {

WEFT_GRADCHECK_CASES(neg) { return {uniform_case("neg", "[2,3]", {{2, 3}})}; }

}  // namespace weft::testing
