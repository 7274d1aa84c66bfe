#include "nn/resnet.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "graph/autograd.h"
#include "graph/error.h"
#include "ops/conv_backend.h"
#include "ops/ops.h"

namespace weft::nn {
namespace {

std::map<std::string, Shape> shapes(const Module& m) {
  std::map<std::string, Shape> out;
  for (const auto& [name, t] : m.state_dict()) out[name] = t.shape();
  return out;
}

double stddev(const Tensor& t) {
  const std::vector<double> v = t.to_vector();
  double mean = 0, sq = 0;
  for (double x : v) mean += x;
  mean /= v.size();
  for (double x : v) sq += (x - mean) * (x - mean);
  return std::sqrt(sq / v.size());
}

ResNetOptions uninitialised() {
  ResNetOptions o;
  o.initialise = false;
  return o;
}

TEST(ResNet, ParameterCountsMatchTorchvision) {
  const auto r18 = resnet18(uninitialised()), r50 = resnet50(uninitialised());
  // torchvision.models.resnet{18,34,50}(): sum(p.numel() for p in m.parameters()).
  EXPECT_EQ(r18->num_parameters(), 11689512);
  EXPECT_EQ(resnet34(uninitialised())->num_parameters(), 21797672);
  EXPECT_EQ(r50->num_parameters(), 25557032);
  // len(m.state_dict()) and len(list(m.parameters())).
  EXPECT_EQ(r18->state_dict().size(), 122u);
  EXPECT_EQ(r18->named_parameters().size(), 62u);
  EXPECT_EQ(r50->state_dict().size(), 320u);
  EXPECT_EQ(r50->named_parameters().size(), 161u);
  // Uninitialised: batch-norm weights and running variances 1, everything else 0.
  for (const auto& [name, t] : r50->state_dict()) {
    const bool one = name.ends_with("running_var") || (name.ends_with(".weight") && t.dim() == 1);
    ASSERT_EQ(t.view({-1}).at({0}), one ? 1.0 : 0.0) << name;
  }
}

TEST(ResNet, NamesAndLayoutsAreTorchvisions) {
  ResNetOptions o = uninitialised();
  o.in_channels = 4;
  o.outputs = 7;
  const auto s50 = shapes(*resnet50(o));
  EXPECT_EQ(s50.at("conv1.weight"), (Shape{64, 4, 7, 7}));
  EXPECT_EQ(s50.at("bn1.running_var"), (Shape{64}));
  EXPECT_EQ(s50.at("bn1.num_batches_tracked"), (Shape{}));
  EXPECT_EQ(s50.at("layer1.0.conv1.weight"), (Shape{64, 64, 1, 1}));
  EXPECT_EQ(s50.at("layer1.0.conv3.weight"), (Shape{256, 64, 1, 1}));
  EXPECT_EQ(s50.at("layer1.0.downsample.0.weight"), (Shape{256, 64, 1, 1}));
  EXPECT_EQ(s50.at("layer1.0.downsample.1.running_mean"), (Shape{256}));
  EXPECT_EQ(s50.at("layer2.0.conv2.weight"), (Shape{128, 128, 3, 3}));  // v1.5 stride here
  EXPECT_EQ(s50.at("layer4.2.bn3.bias"), (Shape{2048}));
  EXPECT_EQ(s50.count("layer1.1.downsample.0.weight"), 0u);
  EXPECT_EQ(s50.at("fc.weight"), (Shape{7, 2048}));
  EXPECT_EQ(s50.at("fc.bias"), (Shape{7}));

  const auto s18 = shapes(*resnet18(o));
  EXPECT_EQ(s18.count("layer1.0.downsample.0.weight"), 0u);  // 64 -> 64, stride 1
  EXPECT_EQ(s18.at("layer2.0.downsample.0.weight"), (Shape{128, 64, 1, 1}));
  EXPECT_EQ(s18.at("layer4.1.conv2.weight"), (Shape{512, 512, 3, 3}));
  EXPECT_EQ(s18.at("fc.weight"), (Shape{7, 512}));
  EXPECT_EQ(resnet18(o)->state_dict().at("bn1.num_batches_tracked").dtype(), DType::I64);

  // Torch's order: a module's own parameters, then its children's.
  const auto names = resnet18(uninitialised())->named_parameters();
  EXPECT_EQ(names.front().name, "conv1.weight");
  EXPECT_EQ(names[1].name, "bn1.weight");
  EXPECT_EQ(names[3].name, "layer1.0.conv1.weight");
  EXPECT_EQ(names.back().name, "fc.bias");
}

TEST(ResNet, InitialisesLikeTorchvisionAndFromTheSeed) {
  ResNetOptions o;
  o.outputs = 10;
  o.seed = 7;
  auto a = resnet18(o), b = resnet18(o);
  o.seed = 8;
  auto c = resnet18(o);
  const Tensor w = a->conv1->weight;
  EXPECT_EQ(w.to_vector(), b->conv1->weight.to_vector());
  EXPECT_NE(w.to_vector(), c->conv1->weight.to_vector());
  // Kaiming normal, fan-out: std sqrt(2 / (64·7·7)).
  EXPECT_NEAR(stddev(w), std::sqrt(2.0 / (64 * 49)), 0.03 * std::sqrt(2.0 / (64 * 49)));
  const Tensor w3 = a->state_dict().at("layer3.1.conv2.weight");
  EXPECT_NEAR(stddev(w3), std::sqrt(2.0 / (256 * 9)), 0.02 * std::sqrt(2.0 / (256 * 9)));
  for (double v : a->bn1->weight.to_vector()) ASSERT_EQ(v, 1.0);
  for (double v : a->bn1->bias.to_vector()) ASSERT_EQ(v, 0.0);
  for (double v : a->bn1->running_var.to_vector()) ASSERT_EQ(v, 1.0);
  // fc: U(±1/sqrt(512)).
  const double bound = 1.0 / std::sqrt(512.0);
  double lo = 1, hi = -1;
  for (double v : a->fc->weight.to_vector()) lo = std::min(lo, v), hi = std::max(hi, v);
  EXPECT_GE(lo, -bound);
  EXPECT_LE(hi, bound);
  EXPECT_LT(lo, -0.9 * bound);
  EXPECT_GT(hi, 0.9 * bound);
  o.zero_init_residual = true;
  auto z = resnet18(o);
  for (double v : z->state_dict().at("layer2.1.bn2.weight").to_vector()) ASSERT_EQ(v, 0.0);
  for (double v : z->state_dict().at("layer2.1.bn1.weight").to_vector()) ASSERT_EQ(v, 1.0);
}

TEST(ResNet, ForwardShapesAndTrainEvalModes) {
  ResNetOptions o;
  o.in_channels = 1;
  o.outputs = 5;
  auto net = resnet18(o);
  Generator gen(3);
  const Tensor x = Tensor::randn({2, 1, 32, 32}, gen);
  const Tensor before = net->bn1->running_mean.clone();
  Tensor y = net->forward(x);
  EXPECT_EQ(y.shape(), (Shape{2, 5}));
  EXPECT_TRUE(y.requires_grad());
  EXPECT_EQ(net->bn1->num_batches_tracked.item(), 1.0);
  EXPECT_NE(net->bn1->running_mean.to_vector(), before.to_vector());

  net->eval();
  EXPECT_FALSE(net->layer3->is_training());
  const Tensor mean_eval = net->bn1->running_mean.clone();
  const Tensor y1 = net->forward(x), y2 = net->forward(x.slice_view(0, 0, 1));
  EXPECT_EQ(net->bn1->num_batches_tracked.item(), 1.0);
  EXPECT_EQ(net->bn1->running_mean.to_vector(), mean_eval.to_vector());
  // Evaluation is per sample: the first row does not depend on the batch.
  for (int64_t j = 0; j < 5; ++j) EXPECT_NEAR(y1.at({0, j}), y2.at({0, j}), 1e-5);

  // Backward reaches every parameter.
  net->train();
  ops::sum(net->forward(x)).backward();
  for (const auto& p : net->named_parameters())
    EXPECT_TRUE(p.tensor.grad().defined()) << p.name;
  net->zero_grad();
  EXPECT_FALSE(net->fc->weight.grad().defined());

  EXPECT_THROW(net->forward(Tensor::zeros({2, 3, 32, 32})), Error);
  EXPECT_THROW(make_resnet("resnet101"), Error);
}

// Inference without a graph folds every batch norm into its conv (ops::conv2d_affine);
// the result is the unfolded eval forward's (run with gradients on) to float32 rounding,
// on both convolution backends, with trained-looking batch-norm statistics.
TEST(ResNet, FoldedInferenceMatchesTheUnfoldedEvalForward) {
  for (ConvBackend backend : {ConvBackend::onednn, ConvBackend::eigen}) {
    const ConvBackend saved = conv_backend();
    set_conv_backend(backend);
    for (const char* arch : {"resnet18", "resnet50"}) {
      ResNetOptions o;
      o.outputs = 7;
      auto net = make_resnet(arch, o);
      Generator gen(31);
      for (auto [name, t] : net->named_buffers()) {
        if (name.find("running_mean") != std::string::npos)
          t.copy_from(Tensor::randn(t.shape(), gen, DType::F32, 0.0, 0.2));
        if (name.find("running_var") != std::string::npos)
          t.copy_from(Tensor::rand(t.shape(), gen, DType::F32, 0.5, 1.5));
      }
      for (auto [name, t] : net->named_parameters())
        if (name.find("bn") != std::string::npos || name.find("downsample.1") != std::string::npos)
          t.copy_from(Tensor::rand(t.shape(), gen, DType::F32, 0.5, 1.5));
      net->eval();
      Tensor x = Tensor::randn({2, 3, 64, 64}, gen);
      x.set_requires_grad();  // a graph: the unfolded path
      const std::vector<double> unfolded = net->forward(x).to_vector();
      std::vector<double> foldedv;
      {
        NoGradGuard no_grad;
        foldedv = net->forward(x.detach()).to_vector();
      }
      double num = 0, den = 0;
      for (size_t i = 0; i < unfolded.size(); ++i)
        num += (foldedv[i] - unfolded[i]) * (foldedv[i] - unfolded[i]), den += unfolded[i] * unfolded[i];
      EXPECT_LE(std::sqrt(num / den), 2e-6) << arch << " on " << conv_backend_name(backend);
    }
    set_conv_backend(saved);
  }
}

TEST(Module, LoadStateDictChecksEverythingFirst) {
  ResNetOptions o;
  o.outputs = 3;
  auto net = resnet18(o);
  o.seed = 99;
  TensorMap other;
  for (const auto& [name, t] : resnet18(o)->state_dict()) other[name] = t.clone();
  const std::vector<double> conv_before = net->conv1->weight.to_vector();

  auto expect_unchanged_error = [&](const TensorMap& state, const std::string& needle) {
    try {
      net->load_state_dict(state, "file.safetensors");
      ADD_FAILURE() << "no error";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("file.safetensors"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
    EXPECT_EQ(net->conv1->weight.to_vector(), conv_before);
  };
  TensorMap missing = other;
  missing.erase("layer4.1.bn2.running_var");
  expect_unchanged_error(missing, "layer4.1.bn2.running_var");
  TensorMap wrong_shape = other;
  wrong_shape["fc.weight"] = Tensor::zeros({4, 512});
  expect_unchanged_error(wrong_shape, "fc.weight");
  TensorMap wrong_dtype = other;
  wrong_dtype["bn1.num_batches_tracked"] = Tensor::zeros({}, DType::F32);
  expect_unchanged_error(wrong_dtype, "bn1.num_batches_tracked");
  TensorMap extra = other;
  extra["fc.scale"] = Tensor::zeros({1});
  expect_unchanged_error(extra, "fc.scale");
  net->load_state_dict(extra, "file.safetensors", /*strict=*/false);

  Tensor handle = net->conv1->weight;
  net->load_state_dict(other, "file.safetensors");
  EXPECT_EQ(handle.to_vector(), other.at("conv1.weight").to_vector());  // in place
  EXPECT_TRUE(handle.requires_grad());
}

}  // namespace
}  // namespace weft::nn
