#include "capture/detection/person_detector.h"

#include "capture/io/openpose.h"
#include "graph/error.h"
#include "graph/random.h"
#include "ops/ops.h"

namespace weft::capture {

Tensor pixel_shuffle2(const Tensor& x) {
  WEFT_CHECK(x.dim() == 4 && x.size(1) % 4 == 0, "pixel_shuffle2: expected [B, 4C, H, W], got ", shape_str(x.shape()));
  const int64_t B = x.size(0), C = x.size(1) / 4, H = x.size(2), W = x.size(3);
  const Tensor split = ops::reshape(x, {B, C, 2, 2, H, W});     // [b, c, di, dj, i, j]
  const Tensor moved = ops::permute(split, {0, 1, 4, 2, 5, 3});  // [b, c, i, di, j, dj]
  return ops::reshape(moved, {B, C, 2 * H, 2 * W});
}

PersonDetector::ConvBn PersonDetector::conv_bn(const std::string& name, int64_t in, int64_t out, int64_t kernel,
                                               int64_t stride, Generator& gen) {
  nn::Conv2dSpec s;
  s.in_channels = in;
  s.out_channels = out;
  s.kernel = kernel;
  s.stride = stride;
  s.padding = kernel / 2;
  s.init = nn::ConvInit::kaiming_normal_fan_out;
  ConvBn c;
  c.conv = register_module(name + "_conv", std::make_shared<nn::Conv2d>(s, gen));
  c.bn = register_module(name + "_bn", std::make_shared<nn::BatchNorm2d>(out));
  return c;
}

PersonDetector::PersonDetector(const DetectorConfig& config, uint64_t seed)
    : nn::Module("PersonDetector"), config_(config) {
  WEFT_CHECK(config.input_size >= 32 && config.input_size % 16 == 0 && config.width >= 4,
             "PersonDetector: input_size ", config.input_size, " must be a multiple of 16 (≥ 32), width ",
             config.width, " at least 4");
  Generator gen(seed);
  const int64_t w = config.width;
  stem_ = conv_bn("stem", 3, w, 3, 2, gen);
  down4_ = conv_bn("down4", w, 2 * w, 3, 2, gen);
  block4_a_ = conv_bn("block4_a", 2 * w, 2 * w, 3, 1, gen);
  block4_b_ = conv_bn("block4_b", 2 * w, 2 * w, 3, 1, gen);
  down8_ = conv_bn("down8", 2 * w, 4 * w, 3, 2, gen);
  block8_a_ = conv_bn("block8_a", 4 * w, 4 * w, 3, 1, gen);
  block8_b_ = conv_bn("block8_b", 4 * w, 4 * w, 3, 1, gen);
  down16_ = conv_bn("down16", 4 * w, 8 * w, 3, 2, gen);
  block16_a_ = conv_bn("block16_a", 8 * w, 8 * w, 3, 1, gen);
  block16_b_ = conv_bn("block16_b", 8 * w, 8 * w, 3, 1, gen);
  block16_c_ = conv_bn("block16_c", 8 * w, 8 * w, 3, 1, gen);
  block16_d_ = conv_bn("block16_d", 8 * w, 8 * w, 3, 1, gen);
  up8_ = conv_bn("up8", 8 * w, 4 * 4 * w, 1, 1, gen);
  fuse8_ = conv_bn("fuse8", 4 * w, 4 * w, 3, 1, gen);
  up4_ = conv_bn("up4", 4 * w, 4 * 2 * w, 1, 1, gen);
  fuse4_ = conv_bn("fuse4", 2 * w, 2 * w, 3, 1, gen);
  up2_ = conv_bn("up2", 2 * w, 4 * w, 1, 1, gen);
  fuse2_ = conv_bn("fuse2", w, w, 3, 1, gen);
  nn::Conv2dSpec h;
  h.in_channels = 2 * w;
  h.out_channels = kBody25Count;
  h.kernel = 3;
  h.padding = 1;
  h.bias = true;
  heatmap_head_ = register_module("heatmap_head", std::make_shared<nn::Conv2d>(h, gen));
  h.in_channels = w;
  h.out_channels = 1;
  h.kernel = 1;
  h.padding = 0;
  mask_head_ = register_module("mask_head", std::make_shared<nn::Conv2d>(h, gen));
}

Tensor PersonDetector::apply(const ConvBn& c, const Tensor& x, const Tensor& residual) {
  return c.bn->forward_relu(c.conv->forward(x), residual);
}

Tensor PersonDetector::block(const ConvBn& a, const ConvBn& b, const Tensor& x) {
  return apply(b, apply(a, x), x);
}

DetectorOutput PersonDetector::run(const Tensor& images) {
  const int64_t S = config_.input_size;
  WEFT_CHECK(images.dim() == 4 && images.size(1) == 3 && images.size(2) == S && images.size(3) == S,
             "PersonDetector: expected images [B, 3, ", S, ", ", S, "], got ", shape_str(images.shape()));
  const Tensor f2 = apply(stem_, images);
  const Tensor f4 = block(block4_a_, block4_b_, apply(down4_, f2));
  const Tensor f8 = block(block8_a_, block8_b_, apply(down8_, f4));
  const Tensor f16 = block(block16_c_, block16_d_, block(block16_a_, block16_b_, apply(down16_, f8)));
  const Tensor g8 = apply(fuse8_, ops::add(pixel_shuffle2(apply(up8_, f16)), f8));
  const Tensor g4 = apply(fuse4_, ops::add(pixel_shuffle2(apply(up4_, g8)), f4));
  const Tensor g2 = apply(fuse2_, ops::add(pixel_shuffle2(apply(up2_, g4)), f2));
  return {heatmap_head_->forward(g4), mask_head_->forward(g2)};
}

Tensor PersonDetector::forward(const Tensor& images) { return run(images).heatmaps; }

}  // namespace weft::capture
