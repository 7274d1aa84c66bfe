#pragma once
// Helpers shared by the op unit tests: value comparison and error-message checks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
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

// Relative L2 error ‖got − want‖ / ‖want‖ (sizes must match).
inline double rel_l2(const std::vector<double>& got, const std::vector<double>& want) {
  EXPECT_EQ(got.size(), want.size());
  double num = 0, den = 0;
  for (size_t i = 0; i < want.size() && i < got.size(); ++i) {
    num += (got[i] - want[i]) * (got[i] - want[i]);
    den += want[i] * want[i];
  }
  return std::sqrt(num / std::max(den, 1e-300));
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
