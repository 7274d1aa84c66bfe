#pragma once
// The define-by-run graph: each op application that needs gradients leaves a Node on
// its output; backward walks the nodes in reverse topological order.
#include <memory>
#include <vector>

#include "graph/attrs.h"
#include "graph/tensor.h"

namespace weft {

struct OpDef;

struct Node {
  const OpDef* op = nullptr;
  Attrs attrs;
  std::vector<Tensor> inputs;   // values and graph edges of the inputs
  std::vector<Tensor> saved;    // extra tensors kept by the forward
  Tensor output;                // detached alias of the output, if the op saves it
  std::vector<bool> needs_grad; // per input
  Shape output_shape;
  DType output_dtype = DType::F32;
  bool released = false;        // buffers freed by a backward without retain_graph
};

const char* node_op_name(const Node& n);

// Gradient mode: when off, ops record nothing (inference, optimiser updates, the
// backward pass itself). Thread-local.
bool grad_enabled();
class NoGradGuard {
 public:
  NoGradGuard();
  ~NoGradGuard();
  NoGradGuard(const NoGradGuard&) = delete;
  NoGradGuard& operator=(const NoGradGuard&) = delete;

 private:
  bool previous_;
};

void run_backward(const Tensor& root, const Tensor& grad_root, bool retain_graph);

// dst += src elementwise (same shape and dtype), without recording.
void accumulate_into(Tensor& dst, const Tensor& src);

}  // namespace weft
