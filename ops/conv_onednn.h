#pragma once
// conv2d in float32 on oneDNN's convolution primitives (see ops/conv_backend.h).
// Blocked activations go to the kernels as they are; NCHW ones, and the weights,
// are reordered per call to the layouts the kernels choose, as PyTorch does. Internal
// to ops/.
#include "ops/conv_geometry.h"

namespace weft {

// bias may be undefined.
Tensor onednn_conv_forward(const Tensor& x, const Tensor& w, const Tensor& bias,
                           const ConvGeometry& g);

struct ConvGradients {
  Tensor x, w, bias;  // undefined where not wanted
};
ConvGradients onednn_conv_backward(const Tensor& x, const Tensor& w, const Tensor& gy,
                                   const ConvGeometry& g, bool want_x, bool want_w,
                                   bool want_bias);

}  // namespace weft
