#pragma once
// The person detector: a small fully convolutional network of its own (not on PoseNet's
// backbone, whose global pool leaves no place; at the demo's 64² PoseNet's last feature map
// is 2×2) that reads one square crop and predicts the BODY_25 keypoints as heatmaps
// (keypoint_heatmaps.h) and the person's mask as logits:
//
//   crop S² → conv 3×3/2 (w)            S/2   ─────────────────────────┐
//           → conv 3×3/2 (2w) + block   S/4   ───────────────┐          │
//           → conv 3×3/2 (4w) + block   S/8   ─────┐         │          │
//           → conv 3×3/2 (8w) + 2 blocks S/16      │         │          │
//           → up ×2 (4w) + skip, conv   S/8  ←─────┘         │          │
//           → up ×2 (2w) + skip, conv   S/4  ←───────────────┘          │
//               → conv 3×3 → 25 heatmaps at S/4                          │
//           → up ×2 (w) + skip, conv    S/2  ←──────────────────────────┘
//               → conv 1×1 → mask logits at S/2
//
// Every conv is followed by batch norm and ReLU except the two output convs (with bias);
// a block is a ResNet basic block (two 3×3 convs and the identity); "up ×2" is a 1×1 conv
// to 4× the channels and a pixel shuffle (depth to space, Shi et al. 2016), made of the
// engine's reshape and permute. Parameters are named under the module's children
// (stem, down4, block4, …), and the whole detector under "detector." in CaptureNetworks.
#include <memory>

#include "nn/layers.h"
#include "nn/module.h"

namespace weft::capture {

// The `network.detector` section of a training config (docs/TRAINING.md): the detector's
// shape and its crop; the model folder rebuilds the network from it.
struct DetectorConfig {
  bool enabled = false;      // a `network.detector` section is present
  int input_size = 128;      // crop side S (pixels), a multiple of 16
  int width = 32;            // w: channels of the first conv
  double margin = 0.25;      // crop margin around the person's box (fraction of its side, each side)
  double sigma_px = 3.0;     // the heatmaps' target σ (crop pixels)
  static constexpr int kHeatmapStride = 4;  // crop pixels per heatmap cell
  static constexpr int kMaskStride = 2;     // crop pixels per mask cell
};

struct DetectorOutput {
  Tensor heatmaps;     // [B, 25, S/4, S/4]
  Tensor mask_logits;  // [B, 1, S/2, S/2]
};

class PersonDetector : public nn::Module {
 public:
  PersonDetector(const DetectorConfig& config, uint64_t seed);
  // images [B, 3, S, S] (ImageNet-normalised RGB, as the dataset reader makes them).
  DetectorOutput run(const Tensor& images);
  Tensor forward(const Tensor& images) override;  // the heatmaps of run()
  const DetectorConfig& config() const { return config_; }

 private:
  DetectorConfig config_;
  struct ConvBn {
    std::shared_ptr<nn::Conv2d> conv;
    std::shared_ptr<nn::BatchNorm2d> bn;
  };
  ConvBn conv_bn(const std::string& name, int64_t in, int64_t out, int64_t kernel, int64_t stride, Generator& gen);
  static Tensor apply(const ConvBn& c, const Tensor& x, const Tensor& residual = Tensor());
  Tensor block(const ConvBn& a, const ConvBn& b, const Tensor& x);
  ConvBn stem_, down4_, down8_, down16_;
  ConvBn block4_a_, block4_b_, block8_a_, block8_b_, block16_a_, block16_b_, block16_c_, block16_d_;
  ConvBn up8_, fuse8_, up4_, fuse4_, up2_, fuse2_;
  std::shared_ptr<nn::Conv2d> heatmap_head_, mask_head_;
};

// [B, 4C, H, W] → [B, C, 2H, 2W]: out[b, c, 2i + di, 2j + dj] = in[b, 4c + 2di + dj, i, j].
Tensor pixel_shuffle2(const Tensor& x);

}  // namespace weft::capture
