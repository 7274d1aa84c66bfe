#pragma once
// Parameter initialisers with PyTorch's formulas (torch.nn.init), drawing from a seeded
// Generator. They write into the tensor in place and record nothing for autograd.
#include "graph/random.h"
#include "graph/tensor.h"

namespace weft::nn {

// Fan-in and fan-out of a weight: [out, in] for linear layers, [out, in, kh, kw] for
// convolutions (receptive field size multiplies both).
int64_t fan_in(const Tensor& weight);
int64_t fan_out(const Tensor& weight);

// N(0, gain / sqrt(fan_out)) with the ReLU gain sqrt(2): torchvision's ResNet convs
// (kaiming_normal_(mode="fan_out", nonlinearity="relu")).
void kaiming_normal_fan_out_relu(Tensor& weight, Generator& gen);

// U(-1/sqrt(fan_in), 1/sqrt(fan_in)): the default of torch.nn.Linear and Conv2d weights
// (kaiming_uniform_ with a = sqrt(5)) and of their biases (with the weight's fan-in).
void uniform_fan_in(Tensor& t, int64_t fan_in, Generator& gen);

}  // namespace weft::nn
