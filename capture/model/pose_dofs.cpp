#include "capture/model/pose_dofs.h"

#include <algorithm>
#include <cmath>

#include "graph/error.h"
#include "ops/ops.h"

namespace weft::capture {

namespace {

constexpr double kRhoMin = 0.01;  // where the rest value may sit in the range, at the closest

double logit(double p) { return std::log(p / (1 - p)); }

}  // namespace

PoseDofs::PoseDofs(const Skeleton& sk, const Eigen::VectorXd& rest, const std::vector<int>& free_dofs,
                   double s, DType dtype)
    : rest_(rest) {
  WEFT_CHECK(rest.size() == sk.num_dofs(), "PoseDofs: ", rest.size(), " rest values for ", sk.num_dofs(), " dofs");
  WEFT_CHECK(s > 0, "PoseDofs: dof_scale must be > 0, got ", s);
  const int64_t F = static_cast<int64_t>(free_dofs.size()), D = rest.size();
  std::vector<double> sel(F * D, 0.0), linear(F, 0.0), slope(F, 0.0), bias(F, 0.0), span(F, 0.0), offset(F, 0.0);
  for (int64_t i = 0; i < F; ++i) {
    const int d = free_dofs[i];
    WEFT_CHECK(d >= 0 && d < D, "PoseDofs: free dof ", d, " out of range");
    sel[i * D + d] = 1.0;
    const Dof& dof = sk.dofs[d];
    Free f{d, dof.limited, dof.lower, dof.upper, 0, 0, s};
    if (f.limited) {
      WEFT_CHECK(f.lo <= f.hi, "PoseDofs: dof '", dof.name, "' has lower limit ", f.lo, " > upper ", f.hi);
      const double range = f.hi - f.lo;
      if (range > 0) {
        const double rho = std::clamp((rest[d] - f.lo) / range, kRhoMin, 1 - kRhoMin);
        f.b = logit(rho);
        f.k = s / (range * rho * (1 - rho));
      }
      slope[i] = f.k;
      bias[i] = f.b;
      span[i] = range;
      offset[i] = f.lo - rest[d];
    } else {
      linear[i] = s;
    }
    free_.push_back(f);
  }
  std::vector<double> r(rest.data(), rest.data() + D);
  free_to_dofs_ = Tensor::from_data({F, D}, sel, dtype);
  rest_tensor_ = Tensor::from_data({D}, r, dtype);
  linear_ = Tensor::from_data({F}, linear, dtype);
  slope_ = Tensor::from_data({F}, slope, dtype);
  bias_ = Tensor::from_data({F}, bias, dtype);
  span_ = Tensor::from_data({F}, span, dtype);
  offset_ = Tensor::from_data({F}, offset, dtype);
}

int PoseDofs::limited_count() const {
  return static_cast<int>(std::count_if(free_.begin(), free_.end(), [](const Free& f) { return f.limited; }));
}

Tensor PoseDofs::dofs(const Tensor& x) const {
  WEFT_CHECK(x.dim() == 2 && x.size(1) == free_count(), "PoseDofs: outputs ", shape_str(x.shape()), ", expected [B, ",
             free_count(), "]");
  // θ − r per free dof: s·x (unlimited) + (lo − r) + (hi − lo)·σ(k·x + b) (limited).
  const Tensor limited = ops::add(ops::mul(ops::sigmoid(ops::add(ops::mul(x, slope_), bias_)), span_), offset_);
  const Tensor change = ops::add(ops::mul(x, linear_), limited);
  return ops::add(ops::matmul(change, free_to_dofs_), rest_tensor_);
}

Eigen::VectorXd PoseDofs::outputs_for(const Eigen::VectorXd& dofs) const {
  WEFT_CHECK(dofs.size() == rest_.size(), "PoseDofs: ", dofs.size(), " dofs, expected ", rest_.size());
  Eigen::VectorXd out(free_count());
  for (int i = 0; i < free_count(); ++i) {
    const Free& f = free_[i];
    if (!f.limited) {
      out[i] = (dofs[f.dof] - rest_[f.dof]) / f.s;
    } else if (f.hi > f.lo) {
      const double p = std::clamp((dofs[f.dof] - f.lo) / (f.hi - f.lo), 1e-6, 1 - 1e-6);
      out[i] = (logit(p) - f.b) / f.k;
    } else {
      out[i] = 0;  // locked
    }
  }
  return out;
}

}  // namespace weft::capture
