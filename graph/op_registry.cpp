#include "graph/op_registry.h"

#include <chrono>

#include "graph/autograd.h"
#include "graph/profiler.h"

namespace weft {

OpRegistry& OpRegistry::instance() {
  static OpRegistry registry;
  return registry;
}

const OpDef& OpRegistry::add(OpDef def) {
  if (def.name.empty()) fail("OpRegistry::add: an op needs a name");
  if (!def.forward) fail("OpRegistry::add: op '", def.name, "' has no forward");
  if (def.differentiable && !def.backward)
    fail("OpRegistry::add: op '", def.name, "' is differentiable but has no backward");
  if (ops_.count(def.name)) fail("OpRegistry::add: op '", def.name, "' is registered twice");
  auto owned = std::make_unique<OpDef>(std::move(def));
  const OpDef& ref = *owned;
  ops_[ref.name] = std::move(owned);
  return ref;
}

const OpDef* OpRegistry::find(const std::string& name) const {
  auto it = ops_.find(name);
  return it == ops_.end() ? nullptr : it->second.get();
}

const OpDef& OpRegistry::get(const std::string& name) const {
  if (const OpDef* d = find(name)) return *d;
  fail("unknown op '", name, "' (", ops_.size(), " ops are registered; `weft ops` lists them)");
}

std::vector<const OpDef*> OpRegistry::all() const {
  std::vector<const OpDef*> out;
  for (auto& [name, def] : ops_) out.push_back(def.get());
  return out;
}

Tensor apply(const OpDef& op, std::vector<Tensor> inputs, const Attrs& attrs) {
  if (inputs.empty()) fail(op.name, ": no inputs");
  if (op.num_inputs >= 0 && static_cast<int>(inputs.size()) != op.num_inputs)
    fail(op.name, ": expected ", op.num_inputs, " inputs, got ", inputs.size());
  bool any_requires_grad = false;
  for (size_t i = 0; i < inputs.size(); ++i) {
    if (!inputs[i].defined()) fail(op.name, ": input ", i, " is undefined");
    if (!op.allow_empty && inputs[i].numel() == 0)
      fail(op.name, ": input ", i, " is empty (", describe(inputs[i]), ")");
    any_requires_grad |= inputs[i].requires_grad();
  }
  const bool record = op.differentiable && any_requires_grad && grad_enabled();

  std::vector<Tensor> saved;
  Tensor out;
  {
    NoGradGuard no_grad;
    if (profiling_enabled()) {
      const auto start = std::chrono::steady_clock::now();
      out = op.forward(ForwardContext{inputs, attrs, saved});
      record_op_time(op.name, false,
                     std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    } else {
      out = op.forward(ForwardContext{inputs, attrs, saved});
    }
  }
  if (!out.defined()) fail(op.name, ": forward returned no tensor");
  for (const Tensor& in : inputs)
    if (out.impl() == in.impl()) out = out.detach();  // an output is always a new tensor
  if (!record) return out;

  auto node = std::make_shared<Node>();
  node->op = &op;
  node->attrs = attrs;
  node->needs_grad.resize(inputs.size());
  for (size_t i = 0; i < inputs.size(); ++i) node->needs_grad[i] = inputs[i].requires_grad();
  node->inputs = std::move(inputs);
  node->saved = std::move(saved);
  node->output_shape = out.shape();
  node->output_dtype = out.dtype();
  if (op.saves_output) node->output = out.detach();
  out.impl()->requires_grad = true;
  out.impl()->grad_fn = std::move(node);
  return out;
}

Tensor apply(const std::string& op, std::vector<Tensor> inputs, const Attrs& attrs) {
  return apply(OpRegistry::instance().get(op), std::move(inputs), attrs);
}

Tensor apply_opaque(const std::string& name, const std::vector<Tensor>& inputs,
                    const std::function<Tensor(const std::vector<Tensor>&)>& fn) {
  std::vector<Tensor> values;
  for (size_t i = 0; i < inputs.size(); ++i) {
    if (!inputs[i].defined()) fail(name, ": input ", i, " is undefined");
    values.push_back(inputs[i].detach());
  }
  NoGradGuard no_grad;
  Tensor out = fn(values);
  if (!out.defined()) fail(name, ": opaque computation returned no tensor");
  return out.detach();
}

}  // namespace weft
