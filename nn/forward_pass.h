#pragma once
// One forward (and optionally backward) pass of a ResNet on tensors from safetensors
// files, writing what it computed to another: the work behind `weft nn forward`, used to
// compare weft with PyTorch on identical weights and inputs (bench/resnet_torch_parity.py).
//
// Reads tensor "input" (float32 [N, C, H, W]) from `input`, the weights (torchvision
// names) from `weights`; C is taken from the weights' conv1.weight. Writes "output"
// [N, outputs]; with `grad_output` (tensor "grad_output" [N, outputs]) also "grad_input"
// and "grad.<parameter name>" for every parameter; with `train` batch norm runs in
// training mode and the updated buffers are written as "buffer.<name>".
// With dtype float64 the weights and tensors read are widened and the whole pass runs in
// float64 (an exact-semantics check against PyTorch float64, free of float32 ReLU and
// max-pool tie flips); the files stay float32.
#include <cstdint>
#include <string>

#include "graph/dtype.h"

namespace weft::nn {

struct ForwardPassOptions {
  std::string arch = "resnet18";
  int64_t outputs = 1000;
  std::string weights, input, output, grad_output;  // grad_output may be empty
  bool train = false;
  DType dtype = DType::F32;  // F32 or F64
};

struct ForwardPassSummary {
  int64_t batch = 0, parameters = 0, tensors_written = 0;
  double forward_ms = 0, backward_ms = 0;
};

ForwardPassSummary run_forward_pass(const ForwardPassOptions& options);

}  // namespace weft::nn
