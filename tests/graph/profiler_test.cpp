#include <gtest/gtest.h>

#include "graph/profiler.h"
#include "graph/threads.h"
#include "ops/ops.h"

namespace weft {
namespace {

TEST(Profiler, CountsForwardAndBackwardCallsPerOp) {
  set_profiling(true);
  reset_profile();
  Tensor x = Tensor::ones({4}, DType::F64).set_requires_grad();
  Tensor y = ops::mul(ops::add(x, x), x);
  ops::add(x, x);
  y.backward(Tensor::ones({4}, DType::F64));
  const std::string report = profile_report();
  set_profiling(false);
  EXPECT_NE(report.find("add                         fwd         2"), std::string::npos) << report;
  EXPECT_NE(report.find("mul                         bwd         1"), std::string::npos) << report;
  EXPECT_EQ(report.find("sub"), std::string::npos) << report;
}

TEST(Threads, BudgetIsAppliedAndChangeable) {
  const int before = num_threads();
  EXPECT_GE(before, 1);
  set_num_threads(1);
  EXPECT_EQ(num_threads(), 1);
  set_num_threads(before);
  EXPECT_EQ(num_threads(), before);
}

}  // namespace
}  // namespace weft
