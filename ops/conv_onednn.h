#pragma once
// conv2d in float32 on oneDNN's convolution primitives (see ops/conv_backend.h).
// Blocked activations go to the kernels as they are; NCHW ones, and the weights,
// are reordered per call to the layouts the kernels choose, as PyTorch does. Internal
// to ops/.
#include "ops/conv_geometry.h"

namespace weft {

// What conv2d_affine applies to the conv's output o, per output channel c, in the
// kernel's own epilogue: y = relu?(o · scale[c] + shift[c] + residual).
struct ConvEpilogue {
  Tensor scale, shift;  // [O]
  Tensor residual;      // the output's shape, or undefined
  bool relu = false;
};

// bias may be undefined; epilogue (blocked outputs only) may be null.
Tensor onednn_conv_forward(const Tensor& x, const Tensor& w, const Tensor& bias,
                           const ConvGeometry& g, const ConvEpilogue* epilogue = nullptr);

struct ConvGradients {
  Tensor x, w, bias;  // undefined where not wanted
};
ConvGradients onednn_conv_backward(const Tensor& x, const Tensor& w, const Tensor& gy,
                                   const ConvGeometry& g, bool want_x, bool want_w,
                                   bool want_bias);

}  // namespace weft
