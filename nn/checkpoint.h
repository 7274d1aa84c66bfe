#pragma once
// Weights and training checkpoints as safetensors files.
//
// Weights: the model's state dict under torchvision's names ("conv1.weight", ...), so a
// file converted from a torchvision model loads directly.
//
// Training checkpoint: "model.<name>" for the model, "optimizer.<parameter>.<slot>" for
// the optimiser state (see Optimizer::state), and in __metadata__:
//   weft.format = "training-checkpoint-1", weft.step (the number of steps taken),
//   weft.optimizer (its type, e.g. "AdamW"), weft.lr (its current rate, %.17g),
//   weft.rng_state (the Generator state string), plus any caller entries.
// Resuming from it continues bit-identically: same parameters, optimiser moments and
// step counts, learning rate and random stream.
//
// Loading checks the whole file against the model, optimiser and generator before
// changing any of them: on error (naming the file and tensor or key) nothing is loaded.
#include <cstdint>
#include <string>

#include "graph/random.h"
#include "nn/module.h"
#include "nn/optim.h"
#include "nn/safetensors.h"

namespace weft::nn {

void save_weights(const std::string& path, const Module& model, const Metadata& metadata = {});
// strict: the file may hold no tensor the model lacks.
void load_weights(const std::string& path, Module& model, bool strict = true);

struct TrainingCheckpoint {
  int64_t step = 0;
  Metadata metadata;  // all of __metadata__, weft.* included
};

// `optimizer` and `gen` may be null (then nothing of theirs is saved).
void save_checkpoint(const std::string& path, const Module& model, const Optimizer* optimizer,
                     int64_t step, const Generator* gen, const Metadata& extra = {});
// Each of `optimizer` and `gen` that is given must have its state in the file.
TrainingCheckpoint load_checkpoint(const std::string& path, Module& model, Optimizer* optimizer,
                                   Generator* gen);

// The file is a training checkpoint (weft.format "training-checkpoint-1"), not bare weights.
bool is_training_checkpoint(const SafetensorsFile& file);
// The model's tensors of a file read with load_safetensors: a checkpoint's "model.*"
// entries without the prefix (its optimiser state left out), or a weights file's tensors.
TensorMap model_tensors(const SafetensorsFile& file);

}  // namespace weft::nn
