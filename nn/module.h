#pragma once
// Module: a node of a network tree that owns named parameters (leaf tensors that require
// grad), named buffers (state that is saved but not trained, e.g. batch-norm running
// statistics) and named child modules. Names compose with dots in registration order,
// exactly as PyTorch names them ("layer1.0.downsample.1.running_var"), so a state dict
// written by torchvision loads here and vice versa.
//
// Parameters and buffers are held by handle: load_state_dict and the optimisers write
// into their storage in place, so handles taken earlier (by an optimiser, say) stay valid.
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "graph/tensor.h"
#include "nn/safetensors.h"

namespace weft::nn {

struct NamedTensor {
  std::string name;
  Tensor tensor;
};

class Module {
 public:
  explicit Module(std::string type_name) : type_name_(std::move(type_name)) {}
  virtual ~Module() = default;
  Module(const Module&) = delete;
  Module& operator=(const Module&) = delete;

  virtual Tensor forward(const Tensor& x) = 0;
  Tensor operator()(const Tensor& x) { return forward(x); }

  const std::string& type_name() const { return type_name_; }

  // Training mode (batch norm uses batch statistics and updates its running ones) or
  // evaluation mode; applies to the whole subtree.
  void train(bool on = true);
  void eval() { train(false); }
  bool is_training() const { return training_; }

  // Recursive, dotted names; per module its own entries first, then its children's.
  std::vector<NamedTensor> named_parameters() const;
  std::vector<NamedTensor> named_buffers() const;
  std::vector<Tensor> parameters() const;
  int64_t num_parameters() const;  // total elements

  // Parameters and buffers by name, aliasing the module's storage (torch's state_dict()).
  TensorMap state_dict() const;
  // Copies `state` into the parameters and buffers in place. Everything is checked first
  // (every key present with the right dtype and shape; with `strict`, no unexpected
  // keys), so on error nothing has changed. `source` (e.g. the file) prefixes errors.
  void load_state_dict(const TensorMap& state, const std::string& source, bool strict = true);
  // The checks of load_state_dict alone.
  void check_state_dict(const TensorMap& state, const std::string& source,
                        bool strict = true) const;

  void zero_grad();  // drops every parameter's gradient

  const std::vector<std::pair<std::string, std::shared_ptr<Module>>>& children() const {
    return children_;
  }

 protected:
  // Registers `t` as a parameter (marks it requires_grad) and returns the handle.
  Tensor register_parameter(const std::string& name, Tensor t);
  Tensor register_buffer(const std::string& name, Tensor t);
  template <class M>
  std::shared_ptr<M> register_module(const std::string& name, std::shared_ptr<M> m) {
    check_new_name(name);
    children_.emplace_back(name, m);
    return m;
  }

 private:
  void check_new_name(const std::string& name) const;
  void collect(const std::string& prefix, bool parameters, std::vector<NamedTensor>& out) const;

  std::string type_name_;
  bool training_ = true;
  std::vector<NamedTensor> parameters_;
  std::vector<NamedTensor> buffers_;
  std::vector<std::pair<std::string, std::shared_ptr<Module>>> children_;
};

// Runs its children in order; they are named "0", "1", ... like torch.nn.Sequential.
class Sequential : public Module {
 public:
  Sequential() : Module("Sequential") {}
  void push_back(std::shared_ptr<Module> m);
  size_t size() const { return children().size(); }
  Module& operator[](size_t i) const { return *children().at(i).second; }
  Tensor forward(const Tensor& x) override;
};

}  // namespace weft::nn
