// Walks every registered op: each differentiable one must have a gradient-check case,
// and every case must pass in float64 against central differences.
#include <gtest/gtest.h>

#include <iostream>
#include <set>

#include "graph/gradcheck.h"
#include "graph/op_registry.h"

namespace weft {
namespace {

TEST(GradcheckCoverage, EveryDifferentiableOpHasACase) {
  std::set<std::string> covered;
  for (const GradcheckCase& c : gradcheck_cases()) covered.insert(c.op);
  std::vector<std::string> missing;
  for (const OpDef* op : OpRegistry::instance().all())
    if (op->differentiable && !covered.count(op->name)) missing.push_back(op->name);
  std::string list;
  for (auto& m : missing) list += " " + m;
  EXPECT_TRUE(missing.empty()) << "differentiable ops without a WEFT_GRADCHECK_CASES entry:"
                               << list;
}

TEST(GradcheckCoverage, EveryCaseNamesARegisteredOp) {
  for (const GradcheckCase& c : gradcheck_cases())
    EXPECT_NE(OpRegistry::instance().find(c.op), nullptr) << c.op << " / " << c.name;
}

class Gradcheck : public ::testing::TestWithParam<size_t> {};

TEST_P(Gradcheck, MatchesCentralDifferences) {
  const GradcheckCase& c = gradcheck_cases().at(GetParam());
  const GradcheckResult r = gradcheck(c);
  EXPECT_TRUE(r.passed) << r.message;
  std::cout << "  " << r.message << "\n";
  RecordProperty("max_abs_error", std::to_string(r.max_abs_error));
}

std::string case_name(const ::testing::TestParamInfo<size_t>& info) {
  const GradcheckCase& c = gradcheck_cases().at(info.param);
  std::string s = c.op + "_" + c.name;
  for (char& ch : s)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return s + "_" + std::to_string(info.param);
}

INSTANTIATE_TEST_SUITE_P(AllOps, Gradcheck,
                         ::testing::Range<size_t>(0, gradcheck_cases().size()), case_name);

}  // namespace
}  // namespace weft
