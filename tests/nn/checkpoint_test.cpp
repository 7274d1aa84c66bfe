#include "nn/checkpoint.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "graph/error.h"
#include "nn/layers.h"
#include "ops/ops.h"

namespace weft::nn {
namespace {

namespace fs = std::filesystem;

class CheckpointTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("weft_checkpoint_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

// A small conv net with batch norm (buffers, int64 counters) and a linear head: the
// checkpoint logic is the same for a ResNet, only slower.
std::shared_ptr<Sequential> small_net(uint64_t seed) {
  Generator gen(seed);
  auto net = std::make_shared<Sequential>();
  Conv2dSpec c{.in_channels = 2, .out_channels = 8, .kernel = 3, .stride = 1, .padding = 1,
               .bias = true};
  net->push_back(std::make_shared<Conv2d>(c, gen));
  net->push_back(std::make_shared<BatchNorm2d>(8));
  net->push_back(std::make_shared<ReLU>());
  net->push_back(std::make_shared<MaxPool2d>(2, 2));
  c.in_channels = 8;
  c.stride = 2;
  net->push_back(std::make_shared<Conv2d>(c, gen));
  net->push_back(std::make_shared<BatchNorm2d>(8));
  net->push_back(std::make_shared<ReLU>());
  net->push_back(std::make_shared<AdaptiveAvgPool2d>(1, 1));
  net->push_back(std::make_shared<Flatten>());
  net->push_back(std::make_shared<Linear>(8, 3, gen));
  return net;
}

// One training step on a batch drawn from `gen` (so the random stream matters).
void train_step(Module& net, Optimizer& opt, Generator& gen) {
  const Tensor x = Tensor::randn({4, 2, 12, 12}, gen);
  const Tensor y = Tensor::randn({4, 3}, gen);
  opt.zero_grad();
  ops::mse_loss(net.forward(x), y).backward();
  clip_grad_norm(opt.params(), 1.0);
  opt.step();
}

bool same_bits(const Tensor& a, const Tensor& b) {
  return a.dtype() == b.dtype() && a.shape() == b.shape() &&
         std::memcmp(a.raw_data(), b.raw_data(), a.nbytes()) == 0;
}

TEST_F(CheckpointTest, ResumingGivesTheSameNextStepBitForBit) {
  AdamWOptions ao;
  ao.lr = 1e-3;
  auto net = small_net(1);
  AdamW opt(net->named_parameters(), ao);
  Generator gen(42);
  for (int i = 0; i < 2; ++i) train_step(*net, opt, gen);
  opt.set_lr(5e-4);
  save_checkpoint(path("ckpt.safetensors"), *net, &opt, 2, &gen, {{"note", "two steps"}});
  train_step(*net, opt, gen);  // the uninterrupted run's third step

  auto resumed = small_net(2);  // different initial weights, fresh optimiser state
  AdamW opt2(resumed->named_parameters(), ao);
  Generator gen2(7);
  const TrainingCheckpoint c = load_checkpoint(path("ckpt.safetensors"), *resumed, &opt2, &gen2);
  EXPECT_EQ(c.step, 2);
  EXPECT_EQ(c.metadata.at("note"), "two steps");
  EXPECT_EQ(opt2.lr(), 5e-4);
  train_step(*resumed, opt2, gen2);

  for (const auto& [name, t] : net->state_dict())
    EXPECT_TRUE(same_bits(t, resumed->state_dict().at(name))) << name;
  for (const auto& [name, t] : opt.state())
    EXPECT_TRUE(same_bits(t, opt2.state().at(name))) << name;
  EXPECT_EQ(gen.state(), gen2.state());
}

TEST_F(CheckpointTest, WeightsRoundTripUnderTheirModuleNames) {
  auto net = small_net(3);
  save_weights(path("w.safetensors"), *net);
  const SafetensorsFile f = load_safetensors(path("w.safetensors"));
  EXPECT_TRUE(f.tensors.count("5.num_batches_tracked"));
  EXPECT_TRUE(f.tensors.count("9.weight"));
  auto other = small_net(4);
  load_weights(path("w.safetensors"), *other);
  for (const auto& [name, t] : net->state_dict())
    EXPECT_TRUE(same_bits(t, other->state_dict().at(name))) << name;
}

// A reader of either kind of file (e.g. `weft infer --weights` on a checkpoint) gets the
// model's tensors under their module names, the optimiser's state left out.
TEST_F(CheckpointTest, ModelTensorsOfACheckpointAndOfWeightsAreTheModelsStateDict) {
  auto net = small_net(6);
  AdamW opt(net->named_parameters(), AdamWOptions{});
  Generator gen(3);
  train_step(*net, opt, gen);
  save_checkpoint(path("ckpt.safetensors"), *net, &opt, 1, &gen);
  save_weights(path("w.safetensors"), *net);
  const SafetensorsFile ckpt = load_safetensors(path("ckpt.safetensors"));
  const SafetensorsFile weights = load_safetensors(path("w.safetensors"));
  EXPECT_TRUE(is_training_checkpoint(ckpt));
  EXPECT_FALSE(is_training_checkpoint(weights));
  const TensorMap state = net->state_dict();
  for (const SafetensorsFile* f : {&ckpt, &weights}) {
    const TensorMap m = model_tensors(*f);
    ASSERT_EQ(m.size(), state.size());
    for (const auto& [name, t] : state) {
      ASSERT_TRUE(m.count(name)) << name;
      EXPECT_TRUE(same_bits(t, m.at(name))) << name;
    }
  }
}

TEST_F(CheckpointTest, BadCheckpointsLoadNothing) {
  auto net = small_net(5);
  SGDOptions so;
  so.momentum = 0.9;
  SGD sgd(net->named_parameters(), so);
  Generator gen(1);
  save_checkpoint(path("sgd.safetensors"), *net, &sgd, 0, &gen);

  auto target = small_net(6);
  const Tensor before = target->state_dict().at("0.weight").clone();
  Adam adam(target->named_parameters(), {});
  auto expect_error = [&](const std::string& p, Optimizer* opt, const std::string& needle) {
    Generator g(9);
    const std::string g_before = g.state();
    try {
      load_checkpoint(p, *target, opt, &g);
      ADD_FAILURE() << "no error";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
    EXPECT_TRUE(same_bits(before, target->state_dict().at("0.weight")));
    EXPECT_EQ(adam.state().at("0.weight.step").item(), 0.0);
    EXPECT_EQ(g.state(), g_before);
  };
  // An SGD checkpoint does not resume an Adam run.
  expect_error(path("sgd.safetensors"), &adam, "SGD");

  // A model tensor of the wrong shape, found after other tensors were fine.
  TensorMap tensors = load_safetensors(path("sgd.safetensors")).tensors;
  Metadata meta = load_safetensors(path("sgd.safetensors")).metadata;
  tensors["model.5.weight"] = Tensor::zeros({3});
  save_safetensors(path("shape.safetensors"), tensors, meta);
  SGD sgd2(target->named_parameters(), so);
  expect_error(path("shape.safetensors"), &sgd2, "5.weight");

  // A missing optimiser tensor.
  tensors = load_safetensors(path("sgd.safetensors")).tensors;
  tensors.erase("optimizer.9.bias.momentum_buffer");
  save_safetensors(path("missing.safetensors"), tensors, meta);
  expect_error(path("missing.safetensors"), &sgd2, "9.bias.momentum_buffer");

  // A broken random state.
  tensors = load_safetensors(path("sgd.safetensors")).tensors;
  meta["weft.rng_state"] = "not a state";
  save_safetensors(path("rng.safetensors"), tensors, meta);
  expect_error(path("rng.safetensors"), &sgd2, "weft.rng_state");

  // A truncated file.
  fs::copy_file(path("sgd.safetensors"), path("cut.safetensors"));
  fs::resize_file(path("cut.safetensors"), fs::file_size(path("cut.safetensors")) - 10);
  expect_error(path("cut.safetensors"), &sgd2, "truncated");
}

}  // namespace
}  // namespace weft::nn
