#include "nn/data_parallel.h"

#include <chrono>
#include <cmath>
#include <cstring>

#include "graph/error.h"

namespace weft::nn {

std::pair<int64_t, int64_t> shard_range(int64_t n, int shard, int shards) {
  WEFT_CHECK(shards >= 1 && shard >= 0 && shard < shards, "shard_range: shard ", shard, " of ", shards);
  return {n * shard / shards, n * (shard + 1) / shards};
}

DataParallel::DataParallel(ProcessGroup& group, std::vector<NamedTensor> parameters, std::vector<NamedTensor> buffers,
                           int shards)
    : group_(group), parameters_(std::move(parameters)), buffers_(std::move(buffers)), shards_(shards) {
  WEFT_CHECK(shards_ >= 1 && shards_ % group_.size() == 0, "DataParallel: ", shards_,
             " shards cannot be spread evenly over ", group_.size(), " ranks");
  for (const NamedTensor& p : parameters_) {
    WEFT_CHECK(p.tensor.dtype() == DType::F32, "DataParallel: parameter '", p.name, "' is not float32");
    gradient_elements_ += p.tensor.numel();
  }
  if (!active()) return;
  gradients_.assign(size_t(gradient_elements_) + parameters_.size(), 0.0f);
  int64_t buffer_elements = 0;
  for (const NamedTensor& b : buffers_) buffer_elements += b.tensor.numel();
  buffer_sums_.assign(size_t(buffer_elements), 0.0);
}

void DataParallel::begin_step() {
  if (!active()) return;
  std::fill(gradients_.begin(), gradients_.end(), 0.0f);
  std::fill(buffer_sums_.begin(), buffer_sums_.end(), 0.0);
  snapshot_.clear();
  for (const NamedTensor& b : buffers_) snapshot_.push_back(b.tensor.clone());
}

void DataParallel::begin_shard() {
  if (!active()) return;
  for (size_t i = 0; i < buffers_.size(); ++i) buffers_[i].tensor.copy_from(snapshot_[i]);
}

void DataParallel::end_shard() {
  if (!active()) return;
  float* acc = gradients_.data();
  float* counts = gradients_.data() + gradient_elements_;
  for (size_t i = 0; i < parameters_.size(); ++i) {
    const Tensor& p = parameters_[i].tensor;
    const Tensor g = p.grad();
    if (g.defined()) {
      const float* d = g.data<float>();
      // A plain sum, as the all-reduce's: a product here would be fused into an FMA,
      // which rounds differently from the all-reduce's sum of rounded products.
      for (int64_t k = 0; k < p.numel(); ++k) acc[k] += d[k];
      counts[i] += 1;
    }
    acc += p.numel();
  }
  double* sums = buffer_sums_.data();
  for (const NamedTensor& b : buffers_) {
    const Tensor v = b.tensor.to(DType::F64);
    const double* d = v.data<double>();
    for (int64_t k = 0; k < v.numel(); ++k) sums[k] += d[k];
    sums += v.numel();
  }
}

void DataParallel::finish_step() {
  if (!active()) return;
  const auto t0 = std::chrono::steady_clock::now();
  group_.all_reduce_sum(std::span<float>(gradients_), "gradients");
  group_.all_reduce_sum(std::span<double>(buffer_sums_), "batch-norm statistics");
  all_reduce_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const float* acc = gradients_.data();
  const float* counts = gradients_.data() + gradient_elements_;
  for (size_t i = 0; i < parameters_.size(); ++i) {
    Tensor& p = parameters_[i].tensor;
    const int64_t n = p.numel();
    if (counts[i] > 0) {
      Tensor g = p.grad();
      if (!g.defined()) {
        g = Tensor::zeros(p.shape(), DType::F32);
        p.set_grad(g);
        g = p.grad();
      }
      std::memcpy(g.data<float>(), acc, sizeof(float) * size_t(n));
    } else {
      p.zero_grad();
    }
    acc += n;
  }
  const double* sums = buffer_sums_.data();
  for (const NamedTensor& b : buffers_) {
    const int64_t n = b.tensor.numel();
    std::vector<double> mean(sums, sums + n);
    for (double& m : mean) m /= shards_;
    if (b.tensor.dtype() == DType::I64)  // counters (num_batches_tracked): equal on every shard
      for (double& m : mean) m = std::round(m);
    Tensor t = b.tensor;
    t.copy_from(Tensor::from_data(b.tensor.shape(), mean, DType::F64));
    sums += n;
  }
}

uint64_t state_checksum(const Module& module) {
  uint64_t h = 1469598103934665603ull;
  auto mix = [&](const std::vector<NamedTensor>& tensors) {
    for (const NamedTensor& t : tensors) {
      // Parameters and buffers own contiguous storage; 8 bytes a round (a byte a round
      // is 8× slower on a network's 100 MB), the tail byte by byte.
      const auto* bytes = static_cast<const unsigned char*>(t.tensor.raw_data());
      const size_t n = t.tensor.nbytes();
      size_t i = 0;
      for (; i + 8 <= n; i += 8) {
        uint64_t word;
        std::memcpy(&word, bytes + i, 8);
        h = (h ^ word) * 1099511628211ull;
      }
      for (; i < n; ++i) h = (h ^ bytes[i]) * 1099511628211ull;
    }
  };
  mix(module.named_parameters());
  mix(module.named_buffers());
  return h;
}

void check_identical_on_all_ranks(ProcessGroup& group, uint64_t checksum, const std::string& what) {
  if (!group.distributed()) return;
  uint64_t lo = checksum, hi = checksum;
  group.all_reduce_min(std::span<uint64_t>(&lo, 1), "state checksum");
  group.all_reduce_max(std::span<uint64_t>(&hi, 1), "state checksum");
  if (lo != hi)
    fail(what, ": the ranks' parameters or batch-norm statistics differ (checksums from ", lo, " to ", hi,
         "); data-parallel training has diverged");
}

}  // namespace weft::nn
