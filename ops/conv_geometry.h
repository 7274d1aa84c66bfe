#pragma once
// The geometry of one conv2d call, read and checked from its inputs and attributes
// (ops/conv.cpp); shared by the Eigen and oneDNN kernels. Internal to ops/.
#include <vector>

#include "graph/attrs.h"
#include "graph/tensor.h"

namespace weft {

struct ConvGeometry {
  int64_t N, C, H, W;     // input
  int64_t O, kh, kw;      // weight [O, C, kh, kw] in either layout
  int64_t sh, sw, ph, pw, dh, dw;
  int64_t Ho, Wo;         // output
  // Channel block L: 1 is NCHW; L > 1 (8 or 16) is the blocked layout the oneDNN
  // kernels work in, input [N, C/L, H, W, L] and output [N, O/L, Ho, Wo, L] (channel
  // c = cb·L + l), oneDNN's nChw16c.
  int64_t block;
  // The input's channel block: block, or 1 for an NCHW input to a blocked output (the
  // first conv of a network whose input has 3 channels).
  int64_t in_block;
  int64_t K() const { return C * kh * kw; }
  int64_t P() const { return Ho * Wo; }
  // The input image [C, H·W] is already the column matrix.
  bool pointwise() const {
    return kh == 1 && kw == 1 && sh == 1 && sw == 1 && ph == 0 && pw == 0;
  }
  Shape input_shape() const {
    return in_block > 1 ? Shape{N, C / in_block, H, W, in_block} : Shape{N, C, H, W};
  }
  Shape output_shape() const {
    return block > 1 ? Shape{N, O / block, Ho, Wo, block} : Shape{N, O, Ho, Wo};
  }
};

// in: x, weight and an optional bias; attrs stride, padding, dilation, channel_block.
ConvGeometry conv_geometry(const std::vector<Tensor>& in, const Attrs& a);

}  // namespace weft
