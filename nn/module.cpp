#include "nn/module.h"

#include <unordered_set>

#include "graph/error.h"

namespace weft::nn {

void Module::train(bool on) {
  training_ = on;
  for (auto& [name, child] : children_) child->train(on);
}

void Module::check_new_name(const std::string& name) const {
  if (name.empty() || name.find('.') != std::string::npos)
    fail(type_name_, ": invalid member name '", name, "' (non-empty, no dots)");
  for (const auto& p : parameters_)
    if (p.name == name) fail(type_name_, ": '", name, "' is already a parameter");
  for (const auto& b : buffers_)
    if (b.name == name) fail(type_name_, ": '", name, "' is already a buffer");
  for (const auto& c : children_)
    if (c.first == name) fail(type_name_, ": '", name, "' is already a child module");
}

Tensor Module::register_parameter(const std::string& name, Tensor t) {
  check_new_name(name);
  if (!t.defined()) fail(type_name_, ": parameter '", name, "' is undefined");
  if (t.dtype() == DType::I64) fail(type_name_, ": parameter '", name, "' cannot be int64");
  t.set_requires_grad(true);
  parameters_.push_back({name, t});
  return t;
}

Tensor Module::register_buffer(const std::string& name, Tensor t) {
  check_new_name(name);
  if (!t.defined()) fail(type_name_, ": buffer '", name, "' is undefined");
  buffers_.push_back({name, t});
  return t;
}

void Module::collect(const std::string& prefix, bool parameters,
                     std::vector<NamedTensor>& out) const {
  for (const NamedTensor& e : parameters ? parameters_ : buffers_)
    out.push_back({prefix + e.name, e.tensor});
  for (const auto& [name, child] : children_) child->collect(prefix + name + ".", parameters, out);
}

std::vector<NamedTensor> Module::named_parameters() const {
  std::vector<NamedTensor> out;
  collect("", true, out);
  return out;
}

std::vector<NamedTensor> Module::named_buffers() const {
  std::vector<NamedTensor> out;
  collect("", false, out);
  return out;
}

std::vector<Tensor> Module::parameters() const {
  std::vector<Tensor> out;
  for (NamedTensor& p : named_parameters()) out.push_back(std::move(p.tensor));
  return out;
}

int64_t Module::num_parameters() const {
  int64_t n = 0;
  for (const NamedTensor& p : named_parameters()) n += p.tensor.numel();
  return n;
}

TensorMap Module::state_dict() const {
  TensorMap out;
  for (NamedTensor& p : named_parameters()) out.emplace(std::move(p.name), std::move(p.tensor));
  for (NamedTensor& b : named_buffers()) out.emplace(std::move(b.name), std::move(b.tensor));
  return out;
}

void Module::check_state_dict(const TensorMap& state, const std::string& source,
                              bool strict) const {
  const TensorMap mine = state_dict();
  for (const auto& [name, t] : mine) {
    auto it = state.find(name);
    if (it == state.end()) fail(source, ": missing tensor '", name, "' of the ", type_name_);
    const Tensor& src = it->second;
    if (src.dtype() != t.dtype() || src.shape() != t.shape())
      fail(source, ": tensor '", name, "' is ", describe(src), ", the ", type_name_,
           " expects ", describe(t));
  }
  if (strict)
    for (const auto& [name, t] : state)
      if (!mine.count(name))
        fail(source, ": unexpected tensor '", name, "' (the ", type_name_, " has no such "
             "parameter or buffer)");
}

void Module::load_state_dict(const TensorMap& state, const std::string& source, bool strict) {
  check_state_dict(state, source, strict);
  const TensorMap mine = state_dict();
  for (const auto& [name, t] : mine) {
    Tensor dst = t;
    dst.copy_from(state.at(name));
  }
}

void Module::zero_grad() {
  for (NamedTensor& p : named_parameters()) p.tensor.zero_grad();
}

void Sequential::push_back(std::shared_ptr<Module> m) {
  register_module(std::to_string(children().size()), std::move(m));
}

Tensor Sequential::forward(const Tensor& x) {
  Tensor y = x;
  for (const auto& [name, child] : children()) y = child->forward(y);
  return y;
}

}  // namespace weft::nn
