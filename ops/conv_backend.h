#pragma once
// Which kernels run conv2d in float32: the one place the choice is made.
//
//   eigen   im2col + Eigen GEMM (ops/conv.cpp); also the only float64 path
//   onednn  oneDNN's convolution primitives (ops/conv_onednn.cpp), the kernels PyTorch
//           itself uses on CPU; the default
//   onednn-winograd
//           oneDNN, with its Winograd F(4×4, 3×3) kernels for 3×3 stride-1 convs whose
//           output has at least 16×16 pixels (where they are faster: docs/BENCHMARKS.md,
//           "conv2d backends"); opt-in, as those kernels are less accurate than PyTorch's
//           own float32 run (the accuracy bar of the default)
//
// The environment variable WEFT_CONV_BACKEND (eigen | onednn) sets the initial choice;
// set_conv_backend changes it for the whole process (it is not per thread). Both give the
// same results to float32 rounding; tests/ops/conv_backend_test.cpp holds them to a
// float64 reference and to finite differences.
#include <cstdint>
#include <string>

namespace weft {

enum class ConvBackend { eigen, onednn, onednn_winograd };

ConvBackend conv_backend();
void set_conv_backend(ConvBackend backend);
const char* conv_backend_name(ConvBackend backend);
// "eigen", "onednn" or "onednn-winograd"; anything else fails naming `where` (a flag, a
// variable) and the accepted values.
ConvBackend parse_conv_backend(const std::string& name, const std::string& where);

// The channel block networks should keep their activations in (ops::Conv2dOptions::
// channel_block): 16 for oneDNN (either), whose kernels compute in that layout (no reorder of
// activations per call), 1 (NCHW) for the Eigen kernels.
int64_t preferred_channel_block();

}  // namespace weft
