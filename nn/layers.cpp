#include "nn/layers.h"

#include <cmath>

#include "graph/autograd.h"
#include "graph/error.h"
#include "nn/init.h"
#include "ops/ops.h"

namespace weft::nn {

Conv2d::Conv2d(const Conv2dSpec& spec, Generator& gen) : Module("Conv2d"), spec_(spec) {
  if (spec.in_channels <= 0 || spec.out_channels <= 0 || spec.kernel <= 0 || spec.stride <= 0 ||
      spec.padding < 0)
    fail("Conv2d: invalid spec (in ", spec.in_channels, ", out ", spec.out_channels,
         ", kernel ", spec.kernel, ", stride ", spec.stride, ", padding ", spec.padding, ")");
  Tensor w = Tensor::zeros({spec.out_channels, spec.in_channels, spec.kernel, spec.kernel},
                           spec.dtype);
  if (spec.init == ConvInit::kaiming_normal_fan_out)
    kaiming_normal_fan_out_relu(w, gen);
  else if (spec.init == ConvInit::torch_default)
    uniform_fan_in(w, fan_in(w), gen);
  weight = register_parameter("weight", w);
  if (spec.bias) {
    Tensor b = Tensor::zeros({spec.out_channels}, spec.dtype);
    if (spec.init != ConvInit::zeros) uniform_fan_in(b, fan_in(w), gen);
    bias = register_parameter("bias", b);
  }
}

Tensor Conv2d::forward(const Tensor& x) { return forward(x, x.dim() == 5 ? x.size(4) : 1); }

Tensor Conv2d::forward(const Tensor& x, int64_t block) {
  ops::Conv2dOptions o;
  o.stride_h = o.stride_w = spec_.stride;
  o.pad_h = o.pad_w = spec_.padding;
  o.channel_block = block;
  return ops::conv2d(x, weight, bias, o);
}

Tensor Conv2d::forward_folded(const Tensor& x, int64_t block, const BatchNorm2d& bn,
                              const Tensor& residual, bool relu) {
  auto [scale, shift] = bn.eval_affine();
  if (bias.defined()) shift = ops::add(shift, ops::mul(bias, scale));
  ops::Conv2dOptions o;
  o.stride_h = o.stride_w = spec_.stride;
  o.pad_h = o.pad_w = spec_.padding;
  o.channel_block = block;
  return ops::conv2d_affine(x, weight, scale, shift, residual, relu, o);
}

BatchNorm2d::BatchNorm2d(int64_t channels, DType dtype, double eps, double momentum)
    : Module("BatchNorm2d"), eps(eps), momentum(momentum) {
  if (channels <= 0) fail("BatchNorm2d: channels ", channels, " must be positive");
  weight = register_parameter("weight", Tensor::ones({channels}, dtype));
  bias = register_parameter("bias", Tensor::zeros({channels}, dtype));
  running_mean = register_buffer("running_mean", Tensor::zeros({channels}, dtype));
  running_var = register_buffer("running_var", Tensor::ones({channels}, dtype));
  num_batches_tracked = register_buffer("num_batches_tracked", Tensor::zeros({}, DType::I64));
}

Tensor BatchNorm2d::forward(const Tensor& x) {
  if (is_training()) num_batches_tracked.data<int64_t>()[0] += 1;
  return ops::batch_norm(x, weight, bias, running_mean, running_var, is_training(), momentum,
                         eps, {x.dim() == 5 ? x.size(4) : 1});
}

std::pair<Tensor, Tensor> BatchNorm2d::eval_affine() const {
  const std::vector<double> w = weight.to_vector(), b = bias.to_vector(),
                            m = running_mean.to_vector(), v = running_var.to_vector();
  std::vector<double> scale(w.size()), shift(w.size());
  for (size_t c = 0; c < w.size(); ++c) {
    scale[c] = w[c] / std::sqrt(v[c] + eps);
    shift[c] = b[c] - m[c] * scale[c];
  }
  const Shape s{static_cast<int64_t>(w.size())};
  return {Tensor::from_data(s, scale, weight.dtype()), Tensor::from_data(s, shift, weight.dtype())};
}

Tensor BatchNorm2d::forward_relu(const Tensor& x, const Tensor& residual) {
  if (is_training()) num_batches_tracked.data<int64_t>()[0] += 1;
  return ops::batch_norm(x, weight, bias, running_mean, running_var, is_training(), momentum,
                         eps, {x.dim() == 5 ? x.size(4) : 1, residual, /*relu=*/true});
}

Linear::Linear(int64_t in_features, int64_t out_features, Generator& gen, bool with_bias,
               DType dtype, bool initialise)
    : Module("Linear") {
  if (in_features <= 0 || out_features <= 0)
    fail("Linear: sizes in ", in_features, ", out ", out_features, " must be positive");
  Tensor w = Tensor::zeros({out_features, in_features}, dtype);
  if (initialise) uniform_fan_in(w, in_features, gen);
  weight = register_parameter("weight", w);
  if (with_bias) {
    Tensor b = Tensor::zeros({out_features}, dtype);
    if (initialise) uniform_fan_in(b, in_features, gen);
    bias = register_parameter("bias", b);
  }
}

Tensor Linear::forward(const Tensor& x) { return ops::linear(x, weight, bias); }

Tensor ReLU::forward(const Tensor& x) { return ops::relu(x); }

Tensor MaxPool2d::forward(const Tensor& x) {
  return ops::max_pool2d(x, kernel, stride, padding, x.dim() == 5 ? x.size(4) : 1);
}

Tensor AdaptiveAvgPool2d::forward(const Tensor& x) {
  return ops::adaptive_avg_pool2d(x, out_h, out_w);
}

Tensor Flatten::forward(const Tensor& x) {
  if (x.dim() < 1) fail("Flatten: needs at least one dimension, got ", describe(x));
  return ops::reshape(x, {x.size(0), -1});
}

}  // namespace weft::nn
