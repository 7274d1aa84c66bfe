// nn::DataParallel on one process with two shards: the gradient is the sum of the
// shards' weighted gradients and the batch-norm statistics the mean of the shards'
// updates, each shard starting from the step's statistics (what two ranks compute; the
// two-rank run itself: tests/capture/data_parallel_integration_test.cpp).
#include "nn/data_parallel.h"

#include <gtest/gtest.h>

#include <cstring>

#include "nn/layers.h"
#include "ops/ops.h"

namespace weft::nn {
namespace {

// x [4, 2, 1, 1]: two channels, four samples.
Tensor input() {
  return Tensor::from_data({4, 2, 1, 1}, std::vector<double>{0.5, -1.0, 2.0, 0.25, -1.5, 3.0, 0.75, 1.25}, DType::F32);
}

// L = Σ (bn(x) · c) over the rows [first, last), weighted by `w`; backward into fresh gradients.
void shard_backward(BatchNorm2d& bn, int first, int last, double w) {
  const std::vector<double> all = {1.0, -2.0, 0.5, 3.0, -1.0, 0.25, 2.0, 1.5};
  const Tensor c = Tensor::from_data({last - first, 2, 1, 1},
                                     std::vector<double>(all.begin() + 2 * first, all.begin() + 2 * last), DType::F32);
  const Tensor x = input().slice_view(0, first, last).clone();
  bn.weight.zero_grad();
  bn.bias.zero_grad();
  ops::scale(ops::sum(ops::mul(bn.forward(x), c)), w).backward();
}

using Range = std::pair<int64_t, int64_t>;

TEST(DataParallel, ShardRangesCoverTheBatchInOrder) {
  EXPECT_EQ(shard_range(10, 0, 3), Range(0, 3));
  EXPECT_EQ(shard_range(10, 1, 3), Range(3, 6));
  EXPECT_EQ(shard_range(10, 2, 3), Range(6, 10));
  EXPECT_EQ(shard_range(4, 0, 1), Range(0, 4)) << "one shard: the batch";
  EXPECT_THROW(shard_range(4, 2, 2), weft::Error);
}

TEST(DataParallel, TwoShardsSumTheirGradientsAndAverageTheirStatistics) {
  ProcessGroup& group = ProcessGroup::world();
  ASSERT_EQ(group.size(), 1) << "a unit test runs as one process";
  BatchNorm2d bn(2);
  bn.train();
  DataParallel dp(group, bn.named_parameters(), bn.named_buffers(), 2);
  ASSERT_TRUE(dp.active());
  dp.begin_step();
  for (auto [first, last] : {shard_range(4, 0, 2), shard_range(4, 1, 2)}) {
    dp.begin_shard();
    shard_backward(bn, int(first), int(last), double(last - first) / 4);
    dp.end_shard();
  }
  dp.finish_step();

  // Each shard alone from the initial state, with the same weight.
  std::vector<std::vector<double>> weight_grads, bias_grads, means, vars;
  for (auto [first, last] : {shard_range(4, 0, 2), shard_range(4, 1, 2)}) {
    BatchNorm2d one(2);
    one.train();
    shard_backward(one, int(first), int(last), 0.5);
    weight_grads.push_back(one.weight.grad().to_vector());
    bias_grads.push_back(one.bias.grad().to_vector());
    means.push_back(one.running_mean.to_vector());
    vars.push_back(one.running_var.to_vector());
  }
  for (int c = 0; c < 2; ++c) {
    EXPECT_EQ(bn.weight.grad().to_vector()[c], float(float(weight_grads[0][c]) + float(weight_grads[1][c]))) << c;
    EXPECT_EQ(bn.bias.grad().to_vector()[c], float(float(bias_grads[0][c]) + float(bias_grads[1][c]))) << c;
    EXPECT_FLOAT_EQ(bn.running_mean.to_vector()[c], (means[0][c] + means[1][c]) / 2) << c;
    EXPECT_FLOAT_EQ(bn.running_var.to_vector()[c], (vars[0][c] + vars[1][c]) / 2) << c;
  }
  EXPECT_EQ(bn.num_batches_tracked.item(), 1.0) << "one step, not one per shard";
  // Per-shard normalisation is another computation than the whole batch's: the running
  // mean of the whole batch would be 0.1 × its mean, which the shards' mean equals, but
  // the variance differs (the shards' spread between them is not in their own).
  BatchNorm2d whole(2);
  whole.train();
  whole.forward(input());
  EXPECT_FLOAT_EQ(bn.running_mean.to_vector()[0], whole.running_mean.to_vector()[0]);
  EXPECT_NE(bn.running_var.to_vector()[0], whole.running_var.to_vector()[0]);
}

TEST(DataParallel, OneShardOnOneProcessTouchesNothing) {
  BatchNorm2d bn(2);
  bn.train();
  DataParallel dp(ProcessGroup::world(), bn.named_parameters(), bn.named_buffers(), 1);
  EXPECT_FALSE(dp.active());
  dp.begin_step();
  dp.begin_shard();
  shard_backward(bn, 0, 4, 1.0);
  const std::vector<double> g = bn.weight.grad().to_vector(), m = bn.running_mean.to_vector();
  dp.end_shard();
  dp.finish_step();
  EXPECT_EQ(bn.weight.grad().to_vector(), g);
  EXPECT_EQ(bn.running_mean.to_vector(), m);
}

TEST(DataParallel, ShardsMustSpreadEvenlyOverTheRanks) {
  BatchNorm2d bn(2);
  EXPECT_THROW(DataParallel(ProcessGroup::world(), bn.named_parameters(), bn.named_buffers(), 0), weft::Error);
}

TEST(StateChecksum, ChangesWithOneBitOfOneBuffer) {
  BatchNorm2d a(3), b(3);
  EXPECT_EQ(state_checksum(a), state_checksum(b));
  float* v = b.running_var.data<float>();
  uint32_t bits;
  std::memcpy(&bits, v + 1, 4);
  bits ^= 1u;
  std::memcpy(v + 1, &bits, 4);
  EXPECT_NE(state_checksum(a), state_checksum(b));
  check_identical_on_all_ranks(ProcessGroup::world(), state_checksum(b), "one process");  // nothing to compare
}

}  // namespace
}  // namespace weft::nn
