#include "graph/gradcheck.h"

#include <cmath>
#include <sstream>

#include "graph/autograd.h"
#include "graph/op_registry.h"

namespace weft {

std::vector<GradcheckCase>& gradcheck_cases() {
  static std::vector<GradcheckCase> cases;
  return cases;
}

namespace {

Tensor evaluate(const GradcheckCase& c, const std::vector<Tensor>& inputs) {
  if (c.function) return c.function(inputs);
  return apply(c.op, inputs, c.attrs);
}

double weighted_sum(const Tensor& y, const Tensor& r) {
  const double* py = y.data<double>();
  const double* pr = r.data<double>();
  double s = 0;
  for (int64_t i = 0, n = y.numel(); i < n; ++i) s += py[i] * pr[i];
  return s;
}

}  // namespace

GradcheckResult gradcheck(const GradcheckCase& c, const GradcheckOptions& o) {
  GradcheckResult res;
  Generator gen(o.seed);
  std::vector<Tensor> inputs = c.make_inputs(gen);
  std::vector<int> wrt = c.wrt;
  if (wrt.empty())
    for (size_t i = 0; i < inputs.size(); ++i)
      if (inputs[i].dtype() == DType::F64) wrt.push_back(static_cast<int>(i));
  for (int i : wrt)
    if (inputs.at(i).dtype() != DType::F64)
      fail("gradcheck ", c.op, " / ", c.name, ": input ", i, " must be float64");

  // Analytic gradient.
  std::vector<Tensor> leaves;
  for (size_t i = 0; i < inputs.size(); ++i) {
    Tensor leaf = inputs[i].clone();
    for (int w : wrt)
      if (w == static_cast<int>(i)) leaf.set_requires_grad(true);
    leaves.push_back(leaf);
  }
  Tensor y = evaluate(c, leaves);
  if (y.dtype() != DType::F64) fail("gradcheck ", c.op, ": output is not float64");
  const Tensor r = Tensor::randn(y.shape(), gen, DType::F64);
  if (!y.requires_grad()) {
    res.message = "output does not require grad: op recorded nothing";
    return res;
  }
  y.backward(r);

  // Numeric gradient by central differences, one element at a time.
  NoGradGuard no_grad;
  std::ostringstream first_failure;
  bool ok = true;
  double diff_sq = 0, numeric_sq = 0;
  for (int w : wrt) {
    Tensor analytic = leaves[w].grad();
    if (!analytic.defined()) analytic = Tensor::zeros(leaves[w].shape(), DType::F64);
    std::vector<Tensor> probe = inputs;
    Tensor x = inputs[w].clone();
    probe[w] = x;
    double* px = x.data<double>();
    for (int64_t k = 0, n = x.numel(); k < n; ++k) {
      const double saved = px[k];
      px[k] = saved + o.eps;
      const double plus = weighted_sum(evaluate(c, probe), r);
      px[k] = saved - o.eps;
      const double minus = weighted_sum(evaluate(c, probe), r);
      px[k] = saved;
      const double numeric = (plus - minus) / (2 * o.eps);
      const double a = analytic.data<double>()[k];
      const double err = std::abs(a - numeric);
      res.max_abs_error = std::max(res.max_abs_error, err);
      res.max_rel_error = std::max(res.max_rel_error, err / std::max(std::abs(numeric), 1.0));
      diff_sq += err * err;
      numeric_sq += numeric * numeric;
      ++res.elements;
      if (!(err <= o.atol + o.rtol * std::abs(numeric))) {
        if (ok)
          first_failure << "input " << w << " element " << k << ": analytic " << a
                        << " vs numeric " << numeric;
        ok = false;
      }
    }
  }
  res.passed = ok;
  res.norm_rel_error = std::sqrt(diff_sq) / std::max(std::sqrt(numeric_sq), 1e-300);
  std::ostringstream msg;
  msg << c.op << " / " << c.name << ": " << res.elements << " elements, max abs error "
      << res.max_abs_error << ", max rel error " << res.max_rel_error
      << ", normwise rel error " << res.norm_rel_error;
  if (!ok) msg << "; first failure " << first_failure.str();
  res.message = msg.str();
  return res;
}

}  // namespace weft
