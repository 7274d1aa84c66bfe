#pragma once
// Data parallelism over the shards of a global batch (PyTorch DDP's scheme, with the
// gradient accumulation of several shards per process folded in).
//
// A training step's global batch of B samples is cut into S contiguous shards, shard j
// holding samples [⌊j·B/S⌋, ⌊(j+1)·B/S⌋) (shard_range). The S shards are spread over the
// ranks of a ProcessGroup, S/N consecutive shards per rank. Each shard runs its own
// forward and backward (batch norm normalises with the shard's statistics, as DDP's
// default does) of its loss weighted by its share of the batch, and the step's gradient is
//   g = Σ_j ∇(w_j L_j),   w_j = n_j / B   (n_j: shard j's samples; L_j: its loss),
// summed in float32 over the process's shards in order, then over the ranks with one
// MPI all-reduce (in buckets). Every rank then holds the same g and its optimiser takes
// the same step, so the parameters stay identical on all ranks. The batch-norm running
// statistics (the module's buffers) start every shard from the step's values and end as
// the mean over the S shards of each shard's update, so they too are identical on all
// ranks and a checkpoint written by rank 0 is the state of every rank.
//
// The computation depends on S, not on how the shards are spread: S = 2 on one process
// (two shards in turn) and S = 2 on two ranks give the same parameters after every step,
// to the rounding of the float32 sums (none at all for two shards: a + b = b + a). With S
// = 1 on one process nothing is touched: the plain training step.
#include <cstdint>
#include <utility>
#include <vector>

#include "nn/module.h"
#include "nn/process_group.h"

namespace weft::nn {

// Samples [first, last) of shard `shard` of `shards` of a batch of `n`.
std::pair<int64_t, int64_t> shard_range(int64_t n, int shard, int shards);

class DataParallel {
 public:
  // `parameters`: what the optimiser steps (float32; their gradients are averaged);
  // `buffers`: state updated by the forward pass in training mode (batch-norm running
  // statistics; averaged over the shards). `shards` (S) must be a multiple of the
  // group's size; each rank runs shards [rank·S/N, (rank+1)·S/N).
  DataParallel(ProcessGroup& group, std::vector<NamedTensor> parameters, std::vector<NamedTensor> buffers, int shards);

  int shards() const { return shards_; }
  int local_shards() const { return shards_ / group_.size(); }
  int first_local_shard() const { return group_.rank() * local_shards(); }
  // True when a step is more than one plain forward and backward.
  bool active() const { return shards_ > 1; }

  // Call once per step, then for each local shard begin_shard(), its forward and the
  // backward of w_j L_j (gradients zeroed first), end_shard(); then finish_step() before
  // the optimiser's step.
  void begin_step();
  void begin_shard();
  void end_shard();
  // Sums the gradients over the ranks and writes them to the parameters (a parameter no
  // shard gave a gradient keeps none); averages the buffers. Seconds spent in the
  // all-reduces are added to all_reduce_seconds().
  void finish_step();

  double all_reduce_seconds() const { return all_reduce_seconds_; }
  int64_t gradient_elements() const { return gradient_elements_; }

 private:
  ProcessGroup& group_;
  std::vector<NamedTensor> parameters_, buffers_;
  int shards_;
  int64_t gradient_elements_ = 0;
  std::vector<float> gradients_;      // Σ_j ∇(w_j L_j), then one count per parameter of shards that had a gradient
  std::vector<Tensor> snapshot_;      // the buffers at the step's start
  std::vector<double> buffer_sums_;   // Σ over shards of each buffer's value after its shard
  double all_reduce_seconds_ = 0;
};

// FNV-1a (over 8-byte words) of every parameter and buffer of `module`, in name order: equal
// on two processes exactly when their states are bit-identical.
uint64_t state_checksum(const Module& module);

// Throws a weft::Error naming `what` when the ranks' checksums differ.
void check_identical_on_all_ranks(ProcessGroup& group, uint64_t checksum, const std::string& what);

}  // namespace weft::nn
