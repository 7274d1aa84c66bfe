#include "nn/resnet.h"

#include "graph/autograd.h"
#include "graph/error.h"
#include "ops/conv_backend.h"
#include "ops/ops.h"

namespace weft::nn {

namespace {

// The channel block of the backend (ops/conv_backend.h) for float32; float64 always
// runs NCHW on the Eigen kernels.
int64_t float_channel_block(const Tensor& x) {
  return x.dtype() == DType::F32 ? preferred_channel_block() : 1;
}

// gen null: zero weights, no random draw.
std::shared_ptr<Conv2d> conv(int64_t in, int64_t out, int64_t kernel, int64_t stride,
                             Generator* gen, DType dtype) {
  Generator unused;
  Conv2dSpec s;
  s.in_channels = in;
  s.out_channels = out;
  s.kernel = kernel;
  s.stride = stride;
  s.padding = kernel / 2;
  s.init = gen ? ConvInit::kaiming_normal_fan_out : ConvInit::zeros;
  s.dtype = dtype;
  return std::make_shared<Conv2d>(s, gen ? *gen : unused);
}

// torchvision's shortcut: a strided 1×1 conv and a batch norm, when shapes change.
std::shared_ptr<Sequential> make_downsample(int64_t inplanes, int64_t outplanes, int64_t stride,
                                            Generator* gen, DType dtype) {
  if (stride == 1 && inplanes == outplanes) return nullptr;
  auto seq = std::make_shared<Sequential>();
  seq->push_back(conv(inplanes, outplanes, 1, stride, gen, dtype));
  seq->push_back(std::make_shared<BatchNorm2d>(outplanes, dtype));
  return seq;
}

}  // namespace

BasicBlock::BasicBlock(int64_t inplanes, int64_t planes, int64_t stride, Generator* gen,
                       DType dtype)
    : Module("BasicBlock") {
  conv1 = register_module("conv1", conv(inplanes, planes, 3, stride, gen, dtype));
  bn1 = register_module("bn1", std::make_shared<BatchNorm2d>(planes, dtype));
  conv2 = register_module("conv2", conv(planes, planes, 3, 1, gen, dtype));
  bn2 = register_module("bn2", std::make_shared<BatchNorm2d>(planes, dtype));
  if (auto ds = make_downsample(inplanes, planes * expansion, stride, gen, dtype))
    downsample = register_module("downsample", ds);
}

namespace {

// Inference: every conv with its batch norm folded in, ReLU and the shortcut in the
// conv's epilogue (Conv2d::forward_folded).
bool folded(const Module& m) { return !m.is_training() && !grad_enabled(); }

int64_t block_of(const Tensor& x) { return x.dim() == 5 ? x.size(4) : 1; }

Tensor shortcut(const std::shared_ptr<Sequential>& downsample, const Tensor& x) {
  if (!downsample) return x;
  if (!folded(*downsample)) return downsample->forward(x);
  auto* conv = dynamic_cast<Conv2d*>(downsample->children()[0].second.get());
  auto* bn = dynamic_cast<BatchNorm2d*>(downsample->children()[1].second.get());
  return conv->forward_folded(x, block_of(x), *bn);
}

}  // namespace

Tensor BasicBlock::forward(const Tensor& x) {
  if (folded(*this)) {
    const int64_t L = block_of(x);
    const Tensor out = conv1->forward_folded(x, L, *bn1, Tensor(), true);
    return conv2->forward_folded(out, L, *bn2, shortcut(downsample, x), true);
  }
  const Tensor out = bn1->forward_relu(conv1->forward(x));
  const Tensor identity = downsample ? downsample->forward(x) : x;
  return bn2->forward_relu(conv2->forward(out), identity);  // relu(bn2(·) + identity)
}

Bottleneck::Bottleneck(int64_t inplanes, int64_t planes, int64_t stride, Generator* gen,
                       DType dtype)
    : Module("Bottleneck") {
  conv1 = register_module("conv1", conv(inplanes, planes, 1, 1, gen, dtype));
  bn1 = register_module("bn1", std::make_shared<BatchNorm2d>(planes, dtype));
  conv2 = register_module("conv2", conv(planes, planes, 3, stride, gen, dtype));
  bn2 = register_module("bn2", std::make_shared<BatchNorm2d>(planes, dtype));
  conv3 = register_module("conv3", conv(planes, planes * expansion, 1, 1, gen, dtype));
  bn3 = register_module("bn3", std::make_shared<BatchNorm2d>(planes * expansion, dtype));
  if (auto ds = make_downsample(inplanes, planes * expansion, stride, gen, dtype))
    downsample = register_module("downsample", ds);
}

Tensor Bottleneck::forward(const Tensor& x) {
  if (folded(*this)) {
    const int64_t L = block_of(x);
    Tensor out = conv1->forward_folded(x, L, *bn1, Tensor(), true);
    out = conv2->forward_folded(out, L, *bn2, Tensor(), true);
    return conv3->forward_folded(out, L, *bn3, shortcut(downsample, x), true);
  }
  Tensor out = bn1->forward_relu(conv1->forward(x));
  out = bn2->forward_relu(conv2->forward(out));
  const Tensor identity = downsample ? downsample->forward(x) : x;
  return bn3->forward_relu(conv3->forward(out), identity);  // relu(bn3(·) + identity)
}

ResNet::ResNet(BlockKind kind, const std::vector<int64_t>& blocks, const ResNetOptions& options)
    : Module("ResNet"), options_(options) {
  if (blocks.size() != 4) fail("ResNet: expected 4 stage sizes, got ", blocks.size());
  if (options.in_channels <= 0 || options.outputs <= 0)
    fail("ResNet: in_channels ", options.in_channels, " and outputs ", options.outputs,
         " must be positive");
  Generator seeded(options.seed);
  Generator* gen = options.initialise ? &seeded : nullptr;
  const DType dt = options.dtype;
  const int64_t expansion = kind == BlockKind::basic ? BasicBlock::expansion
                                                     : Bottleneck::expansion;
  conv1 = register_module("conv1", conv(options.in_channels, 64, 7, 2, gen, dt));
  bn1 = register_module("bn1", std::make_shared<BatchNorm2d>(64, dt));
  relu = register_module("relu", std::make_shared<ReLU>());
  maxpool = register_module("maxpool", std::make_shared<MaxPool2d>(3, 2, 1));
  int64_t inplanes = 64;
  auto make_layer = [&](int64_t planes, int64_t count, int64_t stride) {
    auto layer = std::make_shared<Sequential>();
    for (int64_t i = 0; i < count; ++i) {
      const int64_t s = i == 0 ? stride : 1;
      if (kind == BlockKind::basic)
        layer->push_back(std::make_shared<BasicBlock>(inplanes, planes, s, gen, dt));
      else
        layer->push_back(std::make_shared<Bottleneck>(inplanes, planes, s, gen, dt));
      inplanes = planes * expansion;
    }
    return layer;
  };
  layer1 = register_module("layer1", make_layer(64, blocks[0], 1));
  layer2 = register_module("layer2", make_layer(128, blocks[1], 2));
  layer3 = register_module("layer3", make_layer(256, blocks[2], 2));
  layer4 = register_module("layer4", make_layer(512, blocks[3], 2));
  // torchvision registers avgpool here; it has no state, features() applies it.
  fc = register_module("fc", std::make_shared<Linear>(512 * expansion, options.outputs, seeded,
                                                      true, dt, options.initialise));
  if (options.zero_init_residual) {
    for (const auto* layer : {&layer1, &layer2, &layer3, &layer4})
      for (const auto& [name, block] : (*layer)->children()) {
        if (auto* b = dynamic_cast<Bottleneck*>(block.get())) b->bn3->weight.fill(0.0);
        if (auto* b = dynamic_cast<BasicBlock*>(block.get())) b->bn2->weight.fill(0.0);
      }
  }
}

Tensor ResNet::features(const Tensor& x) {
  if (x.dim() != 4 || x.size(1) != options_.in_channels)
    fail("ResNet: input ", describe(x), " is not [N, ", options_.in_channels, ", H, W]");
  // Everything after the stem conv runs in the convolution backend's layout: for
  // oneDNN, channel blocks [N, C/16, H, W, 16], so that no conv reorders its activations
  // (Conv2d, BatchNorm2d and MaxPool2d follow their input's rank).
  const int64_t L = float_channel_block(x);
  Tensor y = maxpool->forward(folded(*this) ? conv1->forward_folded(x, L, *bn1, Tensor(), true)
                                            : bn1->forward_relu(conv1->forward(x, L)));
  y = layer4->forward(layer3->forward(layer2->forward(layer1->forward(y))));
  if (L == 1) return ops::global_avg_pool2d(y);
  // Mean over H and W of [N, C/L, H, W, L]: [N, C/L, L], i.e. [N, C] in channel order.
  return ops::reshape(ops::mean(y, {2, 3}), {y.size(0), y.size(1) * L});
}

Tensor ResNet::forward(const Tensor& x) { return fc->forward(features(x)); }

std::shared_ptr<ResNet> resnet18(const ResNetOptions& o) {
  return std::make_shared<ResNet>(BlockKind::basic, std::vector<int64_t>{2, 2, 2, 2}, o);
}
std::shared_ptr<ResNet> resnet34(const ResNetOptions& o) {
  return std::make_shared<ResNet>(BlockKind::basic, std::vector<int64_t>{3, 4, 6, 3}, o);
}
std::shared_ptr<ResNet> resnet50(const ResNetOptions& o) {
  return std::make_shared<ResNet>(BlockKind::bottleneck, std::vector<int64_t>{3, 4, 6, 3}, o);
}

std::shared_ptr<ResNet> make_resnet(const std::string& arch, const ResNetOptions& o) {
  if (arch == "resnet18") return resnet18(o);
  if (arch == "resnet34") return resnet34(o);
  if (arch == "resnet50") return resnet50(o);
  fail("unknown ResNet architecture '", arch, "' (expected resnet18, resnet34 or resnet50)");
}

}  // namespace weft::nn
