#pragma once
// Optimisers with PyTorch's update rules (torch.optim, single-tensor path), applied in
// place to the parameters' storage without recording a graph. All per-parameter state
// is allocated when the optimiser is built, so a step allocates nothing.
//
//   SGD:   d = g + wd·p; buf = d on the first step, else momentum·buf + (1−dampening)·d;
//          d = nesterov ? d + momentum·buf : buf (when momentum ≠ 0); p −= lr·d.
//   Adam:  g += wd·p; m = β1·m + (1−β1)·g; v = β2·v + (1−β2)·g²;
//          p −= lr/(1−β1ᵗ) · m / (sqrt(v)/sqrt(1−β2ᵗ) + eps)   (eps outside the sqrt).
//   AdamW: p ·= 1 − lr·wd (decoupled decay), then Adam without the decay in g.
// Parameters without a gradient are skipped (their step count does not advance).
#include <string>
#include <vector>

#include "nn/module.h"

namespace weft::nn {

class Optimizer {
 public:
  Optimizer(std::string type_name, std::vector<NamedTensor> params, double lr);
  virtual ~Optimizer() = default;
  Optimizer(const Optimizer&) = delete;
  Optimizer& operator=(const Optimizer&) = delete;

  virtual void step() = 0;
  // Zeroes every gradient, keeping its buffer (no allocation in the next backward) and
  // without a pass over it (Tensor::clear_grad: the next backward writes it instead of
  // adding to it); with set_to_none, drops them instead.
  void zero_grad(bool set_to_none = false);

  double lr() const { return lr_; }
  void set_lr(double lr);
  const std::string& type_name() const { return type_name_; }
  const std::vector<NamedTensor>& params() const { return params_; }

  // Per-parameter state as "<parameter name>.<slot>" (e.g. "fc.weight.exp_avg",
  // "fc.weight.step"), aliasing the optimiser's buffers.
  TensorMap state() const;
  // Copies `state` in; checks every key, dtype and shape first (nothing changes on
  // error; `source` prefixes the messages).
  void load_state(const TensorMap& state, const std::string& source);
  void check_state(const TensorMap& state, const std::string& source) const;

 protected:
  // Registers the slot `slot` (same shape and dtype as the parameter, zero) for every
  // parameter; returns one tensor per parameter.
  std::vector<Tensor> add_slot(const std::string& slot);
  // One int64 scalar step counter per parameter ("step").
  std::vector<Tensor> steps_;

 private:
  std::string type_name_;
  std::vector<NamedTensor> params_;
  double lr_;
  std::vector<std::pair<std::string, std::vector<Tensor>>> slots_;
};

struct SGDOptions {
  double lr = 0.01, momentum = 0.0, dampening = 0.0, weight_decay = 0.0;
  bool nesterov = false;
};

class SGD : public Optimizer {
 public:
  SGD(std::vector<NamedTensor> params, const SGDOptions& options);
  void step() override;
  const SGDOptions& options() const { return options_; }

 private:
  SGDOptions options_;
  std::vector<Tensor> momentum_buffer_;
};

struct AdamOptions {
  double lr = 1e-3, beta1 = 0.9, beta2 = 0.999, eps = 1e-8, weight_decay = 0.0;
};

// Adam, or AdamW when `decoupled_weight_decay` (see the class AdamW).
class Adam : public Optimizer {
 public:
  Adam(std::vector<NamedTensor> params, const AdamOptions& options);
  void step() override;
  const AdamOptions& options() const { return options_; }

 protected:
  Adam(std::string type_name, std::vector<NamedTensor> params, const AdamOptions& options,
       bool decoupled_weight_decay);

 private:
  AdamOptions options_;
  bool decoupled_;
  std::vector<Tensor> exp_avg_, exp_avg_sq_;
};

// AdamW's default weight decay is 0.01, as in PyTorch.
struct AdamWOptions : AdamOptions {
  AdamWOptions() { weight_decay = 1e-2; }
};

class AdamW : public Adam {
 public:
  AdamW(std::vector<NamedTensor> params, const AdamWOptions& options = {});
};

// Scales every gradient by min(1, max_norm / (‖g‖ + 1e-6)), ‖g‖ the L2 norm of all
// gradients together (torch.nn.utils.clip_grad_norm_); returns ‖g‖ before clipping.
double clip_grad_norm(const std::vector<NamedTensor>& params, double max_norm);

}  // namespace weft::nn
