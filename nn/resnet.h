#pragma once
// torchvision's ResNets (v1.5: the stride sits on the 3×3 conv of a bottleneck) with a
// configurable number of input channels and a linear head of any size, so the same
// builders serve classification and PoseNet/PADefNet-style regression. Parameter names,
// shapes and initialisation follow torchvision.models.resnet exactly:
//   conv1.weight [64, C, 7, 7], bn1.*, layer{1..4}.{i}.conv{1,2[,3]}.weight,
//   layer{k}.0.downsample.0.weight / .1.*, fc.weight [outputs, 512·expansion], fc.bias;
// convs Kaiming normal (fan-out, ReLU gain), batch norms weight 1 bias 0, fc like
// torch.nn.Linear.
#include <memory>
#include <string>
#include <vector>

#include "nn/layers.h"

namespace weft::nn {

struct ResNetOptions {
  int64_t in_channels = 3;
  int64_t outputs = 1000;
  uint64_t seed = 0;  // seeds the initialisation
  DType dtype = DType::F32;
  // Start each residual branch's last batch norm at weight 0 (torchvision's
  // zero_init_residual), so every block begins as the identity.
  bool zero_init_residual = false;
  // false: parameters start at zero without drawing random numbers (fast), for a model
  // whose weights are loaded right after.
  bool initialise = true;
};

// Blocks draw their initial weights from `gen`, or start at zero when it is null.
class BasicBlock : public Module {
 public:
  static constexpr int64_t expansion = 1;
  BasicBlock(int64_t inplanes, int64_t planes, int64_t stride, Generator* gen, DType dtype);
  Tensor forward(const Tensor& x) override;
  std::shared_ptr<Conv2d> conv1, conv2;
  std::shared_ptr<BatchNorm2d> bn1, bn2;
  std::shared_ptr<Sequential> downsample;  // null when the shortcut is the identity
};

class Bottleneck : public Module {
 public:
  static constexpr int64_t expansion = 4;
  Bottleneck(int64_t inplanes, int64_t planes, int64_t stride, Generator* gen, DType dtype);
  Tensor forward(const Tensor& x) override;
  std::shared_ptr<Conv2d> conv1, conv2, conv3;
  std::shared_ptr<BatchNorm2d> bn1, bn2, bn3;
  std::shared_ptr<Sequential> downsample;
};

enum class BlockKind { basic, bottleneck };

class ResNet : public Module {
 public:
  // blocks: the number of blocks of layer1..layer4.
  ResNet(BlockKind kind, const std::vector<int64_t>& blocks, const ResNetOptions& options);
  Tensor forward(const Tensor& x) override;  // [N, C, H, W] -> [N, outputs]
  // Everything up to and including the global average pool: [N, 512·expansion].
  Tensor features(const Tensor& x);
  const ResNetOptions& options() const { return options_; }

  std::shared_ptr<Conv2d> conv1;
  std::shared_ptr<BatchNorm2d> bn1;
  std::shared_ptr<ReLU> relu;
  std::shared_ptr<MaxPool2d> maxpool;
  std::shared_ptr<Sequential> layer1, layer2, layer3, layer4;
  std::shared_ptr<Linear> fc;

 private:
  ResNetOptions options_;
};

std::shared_ptr<ResNet> resnet18(const ResNetOptions& options = {});
std::shared_ptr<ResNet> resnet34(const ResNetOptions& options = {});
std::shared_ptr<ResNet> resnet50(const ResNetOptions& options = {});
// "resnet18", "resnet34" or "resnet50"; anything else is an error listing those.
std::shared_ptr<ResNet> make_resnet(const std::string& arch, const ResNetOptions& options = {});

}  // namespace weft::nn
