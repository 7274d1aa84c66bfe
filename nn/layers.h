#pragma once
// The layers of a ResNet, with torch.nn's names, parameter layouts and defaults.
// Parameters are float32 unless a dtype is given; every random initialisation draws
// from the Generator passed in, so a seed fixes a network.
#include <cstdint>
#include <memory>

#include "graph/random.h"
#include "nn/module.h"

namespace weft::nn {

enum class ConvInit {
  torch_default,           // U(±1/sqrt(fan_in)), torch.nn.Conv2d's own default
  kaiming_normal_fan_out,  // N(0, sqrt(2/fan_out)), what torchvision's ResNet uses
  zeros,                   // no random draw: for weights that are loaded right after
};

struct Conv2dSpec {
  int64_t in_channels = 0, out_channels = 0, kernel = 1, stride = 1, padding = 0;
  bool bias = false;
  ConvInit init = ConvInit::torch_default;
  DType dtype = DType::F32;
};

// weight [out, in, k, k] (OIHW), optional bias [out].
class Conv2d : public Module {
 public:
  Conv2d(const Conv2dSpec& spec, Generator& gen);
  // The output in the input's layout: NCHW, or channel blocks for a blocked input.
  Tensor forward(const Tensor& x) override;
  // The output in channel blocks of `block` (ops::Conv2dOptions::channel_block) whatever
  // the input's layout: how a network's first conv enters the blocked layout.
  Tensor forward(const Tensor& x, int64_t block);
  // Inference (eval-mode `bn`, no gradient): relu?(bn(forward(x, block)) + residual)
  // with the batch norm folded into the conv (ops::conv2d_affine).
  Tensor forward_folded(const Tensor& x, int64_t block, const class BatchNorm2d& bn,
                        const Tensor& residual = Tensor(), bool relu = false);
  const Conv2dSpec& spec() const { return spec_; }
  Tensor weight, bias;

 private:
  Conv2dSpec spec_;
};

// weight [C] (1), bias [C] (0); buffers running_mean [C] (0), running_var [C] (1),
// num_batches_tracked int64 [] (counts training-mode forwards).
class BatchNorm2d : public Module {
 public:
  explicit BatchNorm2d(int64_t channels, DType dtype = DType::F32, double eps = 1e-5,
                       double momentum = 0.1);
  Tensor forward(const Tensor& x) override;
  // relu(forward(x) [+ residual]) in one pass over memory (ops::BatchNormExtras).
  Tensor forward_relu(const Tensor& x, const Tensor& residual = Tensor());
  // Eval mode as a per-channel affine map y = x · scale + shift, computed in double:
  // scale = weight / sqrt(running_var + eps), shift = bias − running_mean · scale.
  std::pair<Tensor, Tensor> eval_affine() const;
  Tensor weight, bias, running_mean, running_var, num_batches_tracked;
  double eps, momentum;
};

// y = x·weightᵀ + bias; weight [out, in], bias [out], both U(±1/sqrt(in)) (zero and
// without a random draw when not `initialise`).
class Linear : public Module {
 public:
  Linear(int64_t in_features, int64_t out_features, Generator& gen, bool with_bias = true,
         DType dtype = DType::F32, bool initialise = true);
  Tensor forward(const Tensor& x) override;
  Tensor weight, bias;
};

class ReLU : public Module {
 public:
  ReLU() : Module("ReLU") {}
  Tensor forward(const Tensor& x) override;
};

class MaxPool2d : public Module {
 public:
  MaxPool2d(int64_t kernel, int64_t stride, int64_t padding = 0)
      : Module("MaxPool2d"), kernel(kernel), stride(stride), padding(padding) {}
  Tensor forward(const Tensor& x) override;
  int64_t kernel, stride, padding;
};

// [N, C, H, W] -> [N, C, out_h, out_w].
class AdaptiveAvgPool2d : public Module {
 public:
  AdaptiveAvgPool2d(int64_t out_h, int64_t out_w)
      : Module("AdaptiveAvgPool2d"), out_h(out_h), out_w(out_w) {}
  Tensor forward(const Tensor& x) override;
  int64_t out_h, out_w;
};

// [N, ...] -> [N, prod(...)], no copy (torch.flatten(x, 1)).
class Flatten : public Module {
 public:
  Flatten() : Module("Flatten") {}
  Tensor forward(const Tensor& x) override;
};

}  // namespace weft::nn
