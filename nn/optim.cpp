#include "nn/optim.h"

#include <cmath>

#include "graph/autograd.h"
#include "graph/error.h"

namespace weft::nn {

namespace {

// Elementwise loops parallelise only when a tensor is large enough to pay for it.
constexpr int64_t kParallelMin = 1 << 15;

template <class Fn>
void for_each_float(const Tensor& p, const char* what, Fn&& fn) {
  dispatch_float(p.dtype(), what, std::forward<Fn>(fn));
}

}  // namespace

Optimizer::Optimizer(std::string type_name, std::vector<NamedTensor> params, double lr)
    : type_name_(std::move(type_name)), params_(std::move(params)) {
  set_lr(lr);
  for (const NamedTensor& p : params_) {
    if (!p.tensor.defined() || !p.tensor.requires_grad() || !p.tensor.is_leaf())
      fail(type_name_, ": '", p.name, "' is not a leaf tensor that requires grad");
    if (p.tensor.dtype() == DType::I64) fail(type_name_, ": '", p.name, "' is int64");
    steps_.push_back(Tensor::zeros({}, DType::I64));
  }
  for (size_t i = 0; i < params_.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      if (params_[i].name == params_[j].name || params_[i].tensor.impl() == params_[j].tensor.impl())
        fail(type_name_, ": parameter '", params_[i].name, "' is listed twice");
}

void Optimizer::set_lr(double lr) {
  if (!(lr >= 0.0) || !std::isfinite(lr))
    fail(type_name_, ": learning rate ", lr, " must be finite and non-negative");
  lr_ = lr;
}

void Optimizer::zero_grad(bool set_to_none) {
  for (NamedTensor& p : params_) {
    if (set_to_none) {
      p.tensor.zero_grad();
      continue;
    }
    p.tensor.clear_grad();  // zeroed lazily: the next backward overwrites it in one pass
  }
}

std::vector<Tensor> Optimizer::add_slot(const std::string& slot) {
  std::vector<Tensor> tensors;
  for (const NamedTensor& p : params_)
    tensors.push_back(Tensor::zeros(p.tensor.shape(), p.tensor.dtype()));
  slots_.emplace_back(slot, tensors);
  return tensors;
}

TensorMap Optimizer::state() const {
  TensorMap out;
  for (size_t i = 0; i < params_.size(); ++i) {
    out.emplace(params_[i].name + ".step", steps_[i]);
    for (const auto& [slot, tensors] : slots_) out.emplace(params_[i].name + "." + slot, tensors[i]);
  }
  return out;
}

void Optimizer::check_state(const TensorMap& state, const std::string& source) const {
  const TensorMap mine = this->state();
  for (const auto& [key, t] : mine) {
    auto it = state.find(key);
    if (it == state.end()) fail(source, ": missing ", type_name_, " state tensor '", key, "'");
    if (it->second.dtype() != t.dtype() || it->second.shape() != t.shape())
      fail(source, ": ", type_name_, " state tensor '", key, "' is ", describe(it->second),
           ", expected ", describe(t));
  }
  for (const auto& [key, t] : state)
    if (!mine.count(key))
      fail(source, ": unexpected ", type_name_, " state tensor '", key,
           "' (no such parameter or slot)");
}

void Optimizer::load_state(const TensorMap& state, const std::string& source) {
  check_state(state, source);
  const TensorMap mine = this->state();
  for (const auto& [key, t] : mine) {
    Tensor dst = t;
    dst.copy_from(state.at(key));
  }
}

// --- SGD ---

SGD::SGD(std::vector<NamedTensor> params, const SGDOptions& options)
    : Optimizer("SGD", std::move(params), options.lr), options_(options) {
  if (options.momentum < 0 || options.weight_decay < 0)
    fail("SGD: momentum ", options.momentum, " and weight decay ", options.weight_decay,
         " must be non-negative");
  if (options.nesterov && (options.momentum <= 0 || options.dampening != 0))
    fail("SGD: Nesterov momentum requires a momentum and zero dampening");
  if (options.momentum != 0) momentum_buffer_ = add_slot("momentum_buffer");
}

void SGD::step() {
  NoGradGuard no_grad;
  const SGDOptions& o = options_;
  for (size_t i = 0; i < params().size(); ++i) {
    Tensor p = params()[i].tensor;
    const Tensor g = p.grad();
    if (!g.defined()) continue;
    int64_t& t = steps_[i].data<int64_t>()[0];
    const bool first = t == 0;
    ++t;
    for_each_float(p, "SGD", [&]<class T>() {
      T* pd = p.data<T>();
      const T* gd = g.data<T>();
      T* buf = o.momentum != 0 ? momentum_buffer_[i].data<T>() : nullptr;
      const T wd = static_cast<T>(o.weight_decay), mom = static_cast<T>(o.momentum),
              keep = static_cast<T>(1.0 - o.dampening), rate = static_cast<T>(lr());
      const int64_t n = p.numel();
#pragma omp parallel for if (n > kParallelMin)
      for (int64_t k = 0; k < n; ++k) {
        T d = gd[k];
        if (o.weight_decay != 0) d += wd * pd[k];
        if (buf) {
          buf[k] = first ? d : mom * buf[k] + keep * d;
          d = o.nesterov ? d + mom * buf[k] : buf[k];
        }
        pd[k] -= rate * d;
      }
    });
  }
}

// --- Adam and AdamW ---

Adam::Adam(std::vector<NamedTensor> params, const AdamOptions& options)
    : Adam("Adam", std::move(params), options, false) {}

Adam::Adam(std::string type_name, std::vector<NamedTensor> params, const AdamOptions& options,
           bool decoupled_weight_decay)
    : Optimizer(std::move(type_name), std::move(params), options.lr),
      options_(options),
      decoupled_(decoupled_weight_decay) {
  if (!(options.beta1 >= 0 && options.beta1 < 1 && options.beta2 >= 0 && options.beta2 < 1))
    fail(this->type_name(), ": betas (", options.beta1, ", ", options.beta2,
         ") must lie in [0, 1)");
  if (!(options.eps >= 0) || !(options.weight_decay >= 0))
    fail(this->type_name(), ": eps ", options.eps, " and weight decay ", options.weight_decay,
         " must be non-negative");
  exp_avg_ = add_slot("exp_avg");
  exp_avg_sq_ = add_slot("exp_avg_sq");
}

void Adam::step() {
  NoGradGuard no_grad;
  const AdamOptions& o = options_;
  for (size_t i = 0; i < params().size(); ++i) {
    Tensor p = params()[i].tensor;
    const Tensor g = p.grad();
    if (!g.defined()) continue;
    const int64_t t = ++steps_[i].data<int64_t>()[0];
    const double bias_correction1 = 1.0 - std::pow(o.beta1, static_cast<double>(t));
    const double bias_correction2 = 1.0 - std::pow(o.beta2, static_cast<double>(t));
    const double step_size = lr() / bias_correction1;
    const double bias_correction2_sqrt = std::sqrt(bias_correction2);
    for_each_float(p, "Adam", [&]<class T>() {
      T* pd = p.data<T>();
      const T* gd = g.data<T>();
      T* m = exp_avg_[i].data<T>();
      T* v = exp_avg_sq_[i].data<T>();
      const T b1 = static_cast<T>(o.beta1), b2 = static_cast<T>(o.beta2),
              one_b1 = static_cast<T>(1.0 - o.beta1), one_b2 = static_cast<T>(1.0 - o.beta2),
              eps = static_cast<T>(o.eps), wd = static_cast<T>(o.weight_decay),
              decay = static_cast<T>(1.0 - lr() * o.weight_decay),
              bc2 = static_cast<T>(bias_correction2_sqrt), ss = static_cast<T>(step_size);
      const bool coupled = !decoupled_ && o.weight_decay != 0;
      const bool decoupled = decoupled_ && o.weight_decay != 0;
      const int64_t n = p.numel();
#pragma omp parallel for if (n > kParallelMin)
      for (int64_t k = 0; k < n; ++k) {
        T grad = gd[k];
        if (decoupled) pd[k] *= decay;
        if (coupled) grad += wd * pd[k];
        m[k] = m[k] * b1 + grad * one_b1;
        v[k] = v[k] * b2 + grad * grad * one_b2;
        const T denom = std::sqrt(v[k]) / bc2 + eps;
        pd[k] -= ss * (m[k] / denom);
      }
    });
  }
}

AdamW::AdamW(std::vector<NamedTensor> params, const AdamWOptions& options)
    : Adam("AdamW", std::move(params), options, true) {}

// --- gradient clipping ---

double clip_grad_norm(const std::vector<NamedTensor>& params, double max_norm) {
  if (!(max_norm > 0)) fail("clip_grad_norm: max_norm ", max_norm, " must be positive");
  double sum_sq = 0.0;
  for (const NamedTensor& p : params) {
    const Tensor g = p.tensor.grad();
    if (!g.defined()) continue;
    for_each_float(g, "clip_grad_norm", [&]<class T>() {
      const T* gd = g.data<T>();
      const int64_t n = g.numel();
      double s = 0.0;
#pragma omp parallel for reduction(+ : s) if (n > kParallelMin)
      for (int64_t k = 0; k < n; ++k) s += static_cast<double>(gd[k]) * gd[k];
      sum_sq += s;
    });
  }
  const double total = std::sqrt(sum_sq);
  const double coef = max_norm / (total + 1e-6);
  if (coef < 1.0) {
    NoGradGuard no_grad;
    for (const NamedTensor& p : params) {
      Tensor g = p.tensor.grad();
      if (!g.defined()) continue;
      for_each_float(g, "clip_grad_norm", [&]<class T>() {
        T* gd = g.data<T>();
        const T c = static_cast<T>(coef);
        const int64_t n = g.numel();
#pragma omp parallel for if (n > kParallelMin)
        for (int64_t k = 0; k < n; ++k) gd[k] *= c;
      });
    }
  }
  return total;
}

}  // namespace weft::nn
