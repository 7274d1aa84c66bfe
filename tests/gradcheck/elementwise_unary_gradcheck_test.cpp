#include "tests/gradcheck/cases.h"

namespace weft::testing {
namespace {

// Shapes every pointwise op is checked on: plain, size-1, odd and a scalar.
std::vector<GradcheckCase> pointwise_cases(const std::string& op, double lo, double hi,
                                           Attrs attrs = {}) {
  return {
      uniform_case(op, "[2,3]", {{2, 3}}, attrs, lo, hi),
      uniform_case(op, "size-1 [1,5,1]", {{1, 5, 1}}, attrs, lo, hi),
      uniform_case(op, "scalar []", {{}}, attrs, lo, hi),
  };
}

// A case with one input made by `make` (for inputs that must avoid a kink).
GradcheckCase one_input_case(const std::string& op, const std::string& name, Attrs attrs,
                             std::function<Tensor(Generator&)> make) {
  GradcheckCase c;
  c.op = op;
  c.name = name;
  c.attrs = std::move(attrs);
  c.make_inputs = [make](Generator& g) { return std::vector<Tensor>{make(g)}; };
  return c;
}

// Uniform values in [-1, 1] kept at least `gap` away from each of `kinks`.
Tensor avoiding(Generator& g, const Shape& s, std::vector<double> kinks, double gap) {
  Tensor t = Tensor::empty(s, DType::F64);
  double* p = t.data<double>();
  for (int64_t i = 0; i < t.numel(); ++i) {
    double v;
    bool near;
    do {
      v = g.uniform(-1.0, 1.0);
      near = false;
      for (double k : kinks) near |= std::abs(v - k) < gap;
    } while (near);
    p[i] = v;
  }
  return t;
}

}  // namespace

WEFT_GRADCHECK_CASES(neg) { return {uniform_case("neg", "[2,3]", {{2, 3}})}; }
WEFT_GRADCHECK_CASES(exp) { return pointwise_cases("exp", -2, 2); }
WEFT_GRADCHECK_CASES(log) { return pointwise_cases("log", 0.3, 3); }
WEFT_GRADCHECK_CASES(sqrt) { return pointwise_cases("sqrt", 0.3, 3); }
WEFT_GRADCHECK_CASES(pow) {
  auto cases = pointwise_cases("pow", -1.5, 1.5, {{"exponent", 3.0}});
  cases.push_back(uniform_case("pow", "fractional p on [3,3]", {{3, 3}}, {{"exponent", 0.5}}, 0.3, 2));
  cases.push_back(uniform_case("pow", "negative p on [5]", {{5}}, {{"exponent", -1.5}}, 0.3, 2));
  return cases;
}
WEFT_GRADCHECK_CASES(abs) {
  return {one_input_case("abs", "[3,4] away from 0", {},
                         [](Generator& g) { return away_from_zero64(g, {3, 4}); }),
          one_input_case("abs", "[1,5]", {}, [](Generator& g) { return away_from_zero64(g, {1, 5}); })};
}
WEFT_GRADCHECK_CASES(sin) { return pointwise_cases("sin", -3, 3); }
WEFT_GRADCHECK_CASES(cos) { return pointwise_cases("cos", -3, 3); }
WEFT_GRADCHECK_CASES(clamp) {
  return {one_input_case("clamp", "[4,5] both sides of both bounds", {{"lo", -0.5}, {"hi", 0.5}},
                         [](Generator& g) { return avoiding(g, {4, 5}, {-0.5, 0.5}, 0.05); }),
          one_input_case("clamp", "[7] asymmetric", {{"lo", -0.2}, {"hi", 0.7}},
                         [](Generator& g) { return avoiding(g, {7}, {-0.2, 0.7}, 0.05); })};
}
WEFT_GRADCHECK_CASES(relu) {
  return {one_input_case("relu", "[3,5]", {}, [](Generator& g) { return away_from_zero64(g, {3, 5}); }),
          one_input_case("relu", "[2,1,3]", {},
                         [](Generator& g) { return away_from_zero64(g, {2, 1, 3}); })};
}
WEFT_GRADCHECK_CASES(sigmoid) { return pointwise_cases("sigmoid", -3, 3); }
WEFT_GRADCHECK_CASES(tanh) { return pointwise_cases("tanh", -2, 2); }
WEFT_GRADCHECK_CASES(softplus) {
  auto cases = pointwise_cases("softplus", -3, 3, {{"beta", 1.0}, {"threshold", 20.0}});
  // beta 2, threshold 1: the linear branch starts at x = 0.5; keep away from it.
  cases.push_back(one_input_case("softplus", "[3,4] both branches", {{"beta", 2.0}, {"threshold", 1.0}},
                                 [](Generator& g) { return avoiding(g, {3, 4}, {0.5}, 0.05); }));
  return cases;
}

WEFT_GRADCHECK_CASES(where) {
  // Conditions are int64 (never perturbed); one case uses a float64 condition and checks
  // only a and b, because perturbing a 0/1 condition would flip the selection.
  auto int_cond = [](const std::string& name, Shape cs, Shape as, Shape bs) {
    GradcheckCase c;
    c.op = "where";
    c.name = name;
    c.make_inputs = [cs, as, bs](Generator& g) {
      std::vector<int64_t> v(static_cast<size_t>(shape_numel(cs)));
      for (auto& e : v) e = g.integer(0, 1);
      return std::vector<Tensor>{Tensor::from_indices(cs, v), uniform64(g, as), uniform64(g, bs)};
    };
    return c;
  };
  GradcheckCase float_cond;
  float_cond.op = "where";
  float_cond.name = "float64 cond [2,3]";
  float_cond.wrt = {1, 2};
  float_cond.make_inputs = [](Generator& g) {
    Tensor cond = Tensor::from_data({2, 3}, std::vector<double>{1, 0, 0, 1, 1, 0}, DType::F64);
    return std::vector<Tensor>{cond, uniform64(g, {2, 3}), uniform64(g, {2, 3})};
  };
  return {int_cond("same [2,3]", {2, 3}, {2, 3}, {2, 3}),
          int_cond("broadcast cond [3,1] a [1,4] b [4]", {3, 1}, {1, 4}, {4}),
          int_cond("scalar a, cond [2,1,3], b [2,3]", {2, 1, 3}, {}, {2, 3}), float_cond};
}

}  // namespace weft::testing
