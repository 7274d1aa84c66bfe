#pragma once
// The op registry: every op is registered once by name with a forward and, when it is
// differentiable, a backward; both handle float32 and float64. `apply` runs an op and,
// when gradients are wanted, records a Node in the define-by-run graph.
//
// Adding an op (see docs/ENGINE.md):
//   WEFT_REGISTER_OP(my_op) {
//     OpDef d;  d.name = "my_op";  d.num_inputs = 1;  d.doc = "...";
//     d.forward  = [](const ForwardContext& c) -> Tensor {...};
//     d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {...};
//     return d;
//   }
// plus one WEFT_GRADCHECK_CASE in tests/gradcheck/ (the suite fails without it).
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "graph/attrs.h"
#include "graph/tensor.h"

namespace weft {

struct ForwardContext {
  const std::vector<Tensor>& inputs;
  const Attrs& attrs;
  // Extra tensors the backward needs (e.g. max-pool argmax, batch-norm inverse std).
  std::vector<Tensor>& saved;
  const Tensor& in(size_t i) const { return inputs[i]; }
};

struct BackwardContext {
  const std::vector<Tensor>& inputs;  // the forward's inputs (values)
  const Tensor& output;               // the forward's output (only if saves_output)
  const Tensor& grad_output;          // dLoss/dOutput, same shape as the output
  const Attrs& attrs;
  const std::vector<Tensor>& saved;
  const std::vector<bool>& needs_grad;  // per input: compute its gradient?
  const Tensor& in(size_t i) const { return inputs[i]; }
};

using ForwardFn = std::function<Tensor(const ForwardContext&)>;
// Returns one gradient per input, each the input's shape and dtype, or undefined where
// needs_grad is false or the input is not differentiable (e.g. int64 indices).
using BackwardFn = std::function<std::vector<Tensor>(const BackwardContext&)>;

struct OpDef {
  std::string name;
  std::string doc;        // one line for `weft ops`
  int num_inputs = -1;    // -1: variadic (at least one)
  bool differentiable = true;
  bool saves_output = false;  // backward reads ctx.output
  bool allow_empty = false;   // accept inputs with zero elements
  ForwardFn forward;
  BackwardFn backward;
};

class OpRegistry {
 public:
  static OpRegistry& instance();
  // Registers an op; a second registration of one name is an error.
  const OpDef& add(OpDef def);
  const OpDef& get(const std::string& name) const;  // error lists near names
  const OpDef* find(const std::string& name) const;
  std::vector<const OpDef*> all() const;  // sorted by name

 private:
  std::map<std::string, std::unique_ptr<OpDef>> ops_;
};

// Runs a registered op on its inputs and records it for backward if needed.
Tensor apply(const OpDef& op, std::vector<Tensor> inputs, const Attrs& attrs = {});
Tensor apply(const std::string& op, std::vector<Tensor> inputs, const Attrs& attrs = {});

// An opaque computation: `fn` maps input values to an output and no gradient flows
// back to the inputs (the output never requires grad). The cloth simulator is one.
Tensor apply_opaque(const std::string& name, const std::vector<Tensor>& inputs,
                    const std::function<Tensor(const std::vector<Tensor>&)>& fn);

namespace detail {
struct OpRegistrar {
  explicit OpRegistrar(OpDef (*make)()) { OpRegistry::instance().add(make()); }
};
}  // namespace detail

#define WEFT_REGISTER_OP(ident)                                               \
  static ::weft::OpDef weft_make_op_##ident();                                \
  static const ::weft::detail::OpRegistrar weft_op_registrar_##ident(         \
      &weft_make_op_##ident);                                                 \
  static ::weft::OpDef weft_make_op_##ident()

}  // namespace weft
