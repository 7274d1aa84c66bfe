#include "tests/gradcheck/cases.h"

namespace weft::testing {
namespace {

// pred = target + d, with every |d| kept away from the penalty's kinks.
GradcheckCase offset_case(const std::string& op, const std::string& name, Shape s, Attrs attrs,
                          std::vector<double> kinks) {
  GradcheckCase c;
  c.op = op;
  c.name = name;
  c.attrs = std::move(attrs);
  c.make_inputs = [s, kinks](Generator& g) {
    Tensor target = uniform64(g, s);
    Tensor pred = target.clone();
    double* p = pred.data<double>();
    for (int64_t i = 0; i < pred.numel(); ++i) {
      double d;
      bool near;
      do {
        d = g.uniform(-2.0, 2.0);
        near = false;
        for (double k : kinks) near |= std::abs(std::abs(d) - k) < 0.05;
      } while (near);
      p[i] += d;
    }
    return std::vector<Tensor>{pred, target};
  };
  return c;
}

}  // namespace

WEFT_GRADCHECK_CASES(mse_loss) {
  return {uniform_case("mse_loss", "[3,4]", {{3, 4}, {3, 4}}),
          uniform_case("mse_loss", "scalar []", {{}, {}}),
          uniform_case("mse_loss", "[1,5,1]", {{1, 5, 1}, {1, 5, 1}})};
}
WEFT_GRADCHECK_CASES(l1_loss) {
  return {offset_case("l1_loss", "[3,4]", {3, 4}, {}, {0.0}),
          offset_case("l1_loss", "[1,7]", {1, 7}, {}, {0.0})};
}
WEFT_GRADCHECK_CASES(smooth_l1_loss) {
  return {offset_case("smooth_l1_loss", "[3,4] beta 1", {3, 4}, {{"beta", 1.0}}, {0.0, 1.0}),
          offset_case("smooth_l1_loss", "[5] beta 0.5", {5}, {{"beta", 0.5}}, {0.0, 0.5}),
          offset_case("smooth_l1_loss", "[2,3] beta 0 (l1)", {2, 3}, {{"beta", 0.0}}, {0.0})};
}

}  // namespace weft::testing
