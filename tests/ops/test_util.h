#pragma once
// Helpers shared by the op unit tests: value comparison and error-message checks.
#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

#include "graph/error.h"
#include "graph/tensor.h"

namespace weft::testing {

// Tolerance for values computed in `d`: float32 keeps ~7 digits.
inline double tol(DType d) { return d == DType::F32 ? 1e-5 : 1e-12; }

inline void expect_values(const Tensor& t, const std::vector<double>& expected, double atol) {
  const std::vector<double> v = t.to_vector();
  ASSERT_EQ(v.size(), expected.size()) << "shape " << shape_str(t.shape());
  for (size_t i = 0; i < v.size(); ++i)
    EXPECT_NEAR(v[i], expected[i], atol * (1 + std::abs(expected[i]))) << "element " << i;
}

// Runs fn, expects a weft::Error whose message contains every one of `parts`.
inline void expect_error(const std::function<void()>& fn, const std::vector<std::string>& parts) {
  try {
    fn();
  } catch (const Error& e) {
    const std::string msg = e.what();
    for (const std::string& p : parts)
      EXPECT_NE(msg.find(p), std::string::npos) << "message \"" << msg << "\" lacks \"" << p << "\"";
    return;
  }
  ADD_FAILURE() << "expected a weft::Error";
}

inline const char* dtype_label(const ::testing::TestParamInfo<DType>& info) {
  return info.param == DType::F32 ? "float32" : "float64";
}

}  // namespace weft::testing
