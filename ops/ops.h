#pragma once
// The typed C++ API of weft's built-in ops. Each function runs the registered op of the
// same name through the registry (so it is recorded for backward when an input requires
// grad). Elementwise binary ops broadcast like NumPy. Axes may be negative.
#include <vector>

#include "graph/op_registry.h"
#include "graph/tensor.h"

namespace weft::ops {

// --- elementwise, broadcasting (ops/elementwise_binary.cpp) ---
Tensor add(const Tensor& a, const Tensor& b);
Tensor sub(const Tensor& a, const Tensor& b);
Tensor mul(const Tensor& a, const Tensor& b);
Tensor div(const Tensor& a, const Tensor& b);
Tensor scale(const Tensor& x, double s);       // x · s (op "scale")
Tensor add_scalar(const Tensor& x, double s);  // x + s (op "add_scalar")

// --- elementwise unary (ops/elementwise_unary.cpp) ---
Tensor neg(const Tensor& x);
Tensor exp(const Tensor& x);
Tensor log(const Tensor& x);
Tensor sqrt(const Tensor& x);
Tensor pow(const Tensor& x, double exponent);
Tensor abs(const Tensor& x);
Tensor sin(const Tensor& x);
Tensor cos(const Tensor& x);
Tensor clamp(const Tensor& x, double lo, double hi);
// cond != 0 selects a, else b; the three broadcast together; no gradient to cond.
Tensor where(const Tensor& cond, const Tensor& a, const Tensor& b);
Tensor relu(const Tensor& x);
Tensor sigmoid(const Tensor& x);
Tensor tanh(const Tensor& x);
// log(1 + exp(beta·x)) / beta, linear above `threshold` like PyTorch.
Tensor softplus(const Tensor& x, double beta = 1.0, double threshold = 20.0);

// --- reductions (ops/reduce.cpp); empty `axes` reduces over all axes ---
Tensor sum(const Tensor& x, const std::vector<int64_t>& axes = {}, bool keepdim = false);
Tensor mean(const Tensor& x, const std::vector<int64_t>& axes = {}, bool keepdim = false);
Tensor max(const Tensor& x, const std::vector<int64_t>& axes = {}, bool keepdim = false);
Tensor norm(const Tensor& x, const std::vector<int64_t>& axes = {}, bool keepdim = false);  // L2

// --- shape and indexing (ops/shape.cpp, ops/indexing.cpp) ---
Tensor reshape(const Tensor& x, const Shape& shape);  // never copies (shares storage)
Tensor permute(const Tensor& x, const std::vector<int64_t>& dims);  // copies
Tensor transpose(const Tensor& x, int64_t dim0, int64_t dim1);     // copies
// [start, end) with step along `axis`; copies unless the block is contiguous (step 1 and
// every earlier axis of size 1), in which case it shares storage.
Tensor slice(const Tensor& x, int64_t axis, int64_t start, int64_t end, int64_t step = 1);
Tensor concat(const std::vector<Tensor>& xs, int64_t axis);
Tensor stack(const std::vector<Tensor>& xs, int64_t axis);
// index: int64 1-D; picks entries along axis.
Tensor index_select(const Tensor& x, int64_t axis, const Tensor& index);
// index: int64, same rank as x; out[i][j] = x[index[i][j]][j] for axis 0 (PyTorch gather).
Tensor gather(const Tensor& x, int64_t axis, const Tensor& index);
// out = x, then out[index[i][j]][j] += src[i][j] for axis 0 (PyTorch scatter_add).
Tensor scatter_add(const Tensor& x, int64_t axis, const Tensor& index, const Tensor& src);
Tensor stop_gradient(const Tensor& x);  // alias with no gradient (same as detach)

// --- linear algebra (ops/matmul.cpp), Eigen GEMM ---
// [n,k]@[k,m]; [b,n,k]@[b,k,m]; [b,n,k]@[k,m].
Tensor matmul(const Tensor& a, const Tensor& b);
// x [.., in] · wᵀ [out, in] + b [out] (b may be undefined).
Tensor linear(const Tensor& x, const Tensor& w, const Tensor& b = Tensor());

// --- convolution and pooling (ops/conv.cpp, ops/pool.cpp), NCHW ---
struct Conv2dOptions {
  int64_t stride_h = 1, stride_w = 1, pad_h = 0, pad_w = 0, dilation_h = 1, dilation_w = 1;
  // 1: x [N,C,H,W] and the result [N,O,Ho,Wo]. L (8 or 16): both blocked,
  // [N,C/L,H,W,L] and [N,O/L,Ho,Wo,L] (channel c = cb·L + l), the layout oneDNN's
  // kernels compute in (ResNet keeps its activations so; see nn/resnet.h).
  int64_t channel_block = 1;
};
// x [N,C,H,W], w [O,C,kh,kw], bias [O] or undefined. float32 runs on the backend chosen
// in ops/conv_backend.h (oneDNN by default), float64 on weft's own Eigen kernels.
Tensor conv2d(const Tensor& x, const Tensor& w, const Tensor& bias = Tensor(),
              const Conv2dOptions& o = {});
// Inference only (no gradient): relu?(conv2d(x, w) · scale[o] + shift[o] + residual), a
// conv with its batch norm folded in (scale = γ/√(σ²+ε), shift = β − μ·scale). On oneDNN
// with a blocked output the epilogue runs inside the conv's kernel. residual: the
// output's shape, or undefined.
Tensor conv2d_affine(const Tensor& x, const Tensor& w, const Tensor& scale, const Tensor& shift,
                     const Tensor& residual, bool relu, const Conv2dOptions& o = {});
// channel_block L > 1: x is blocked [N, C/L, H, W, L] (see Conv2dOptions::channel_block).
Tensor max_pool2d(const Tensor& x, int64_t kernel, int64_t stride, int64_t padding = 0,
                  int64_t channel_block = 1);
// count_include_pad = true, like PyTorch's default.
Tensor avg_pool2d(const Tensor& x, int64_t kernel, int64_t stride, int64_t padding = 0);
Tensor adaptive_avg_pool2d(const Tensor& x, int64_t out_h, int64_t out_w);
Tensor global_avg_pool2d(const Tensor& x);  // [N,C,H,W] -> [N,C]

// --- normalisation (ops/batch_norm.cpp) ---
// PyTorch semantics: training normalises with the biased batch variance and updates
// running_mean/var in place with `momentum` (running_var from the unbiased variance);
// eval normalises with the running statistics. weight/bias may be undefined.
// Extras computed in batch_norm's own passes over memory:
//   channel_block L > 1: x is blocked, [N, C/L, ..., L] (Conv2dOptions::channel_block);
//   residual (x's shape): added to the result, as a ResNet block's shortcut;
//   relu: max(0, ·) of the result.
// So batch_norm(x, ..., {L, z, true}) is relu(add(batch_norm(x), z)) to the last bit.
struct BatchNormExtras {
  int64_t channel_block = 1;
  Tensor residual;
  bool relu = false;
};
Tensor batch_norm(const Tensor& x, const Tensor& weight, const Tensor& bias,
                  Tensor running_mean, Tensor running_var, bool training,
                  double momentum = 0.1, double eps = 1e-5, const BatchNormExtras& extras = {});

// --- losses (ops/loss.cpp), mean over all elements ---
Tensor mse_loss(const Tensor& pred, const Tensor& target);
Tensor l1_loss(const Tensor& pred, const Tensor& target);
Tensor smooth_l1_loss(const Tensor& pred, const Tensor& target, double beta = 1.0);

}  // namespace weft::ops
