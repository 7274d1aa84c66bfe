#include "graph/autograd.h"

#include <algorithm>
#include <cstring>

#include <chrono>
#include <unordered_map>
#include <unordered_set>

#include "graph/op_registry.h"
#include "graph/profiler.h"

namespace weft {

namespace {
thread_local bool t_grad_enabled = true;
}

bool grad_enabled() { return t_grad_enabled; }
NoGradGuard::NoGradGuard() : previous_(t_grad_enabled) { t_grad_enabled = false; }
NoGradGuard::~NoGradGuard() { t_grad_enabled = previous_; }

const char* node_op_name(const Node& n) { return n.op ? n.op->name.c_str() : "?"; }

void accumulate_into(Tensor& dst, const Tensor& src) {
  if (dst.shape() != src.shape() || dst.dtype() != src.dtype())
    fail("accumulate_into: ", describe(dst), " += ", describe(src));
  dispatch_float(dst.dtype(), "accumulate_into", [&]<class T>() {
    T* d = dst.data<T>();
    const T* s = src.data<T>();
    const int64_t n = dst.numel();
#pragma omp parallel for if (n > (1 << 16))
    for (int64_t i = 0; i < n; ++i) d[i] += s[i];
  });
}

namespace {

void copy_into(Tensor& dst, const Tensor& src) {
  if (dst.shape() != src.shape() || dst.dtype() != src.dtype())
    fail("accumulate_into: ", describe(dst), " = ", describe(src));
  const int64_t bytes = src.numel() * static_cast<int64_t>(dtype_size(src.dtype()));
  char* d = static_cast<char*>(dst.raw_data());
  const char* s = static_cast<const char*>(src.raw_data());
  constexpr int64_t kChunk = 1 << 20;
  const int64_t chunks = (bytes + kChunk - 1) / kChunk;
#pragma omp parallel for if (chunks > 1)
  for (int64_t c = 0; c < chunks; ++c)
    std::memcpy(d + c * kChunk, s + c * kChunk, std::min(kChunk, bytes - c * kChunk));
}

struct PendingGrad {
  Tensor value;
  bool owned = false;  // may be modified in place
};

// A gradient nobody else holds (a fresh op output, in its own whole storage) becomes the
// leaf's gradient as it is; anything shared is copied, so later accumulation into the
// leaf's gradient cannot change a tensor someone else sees.
bool exclusively_owned(const Tensor& g) {
  const std::shared_ptr<TensorImpl>& impl = g.impl_ptr();
  return impl.use_count() == 1 && impl->storage.use_count() == 1 && impl->offset == 0 &&
         !impl->grad_fn &&
         impl->storage->bytes == static_cast<size_t>(g.numel()) * dtype_size(g.dtype());
}

// Sums the gradients reaching one tensor. A gradient nobody else holds is summed into in
// place (a + b in either order is the same float); a shared one is copied first.
void add_pending(PendingGrad& p, Tensor&& g) {
  if (!p.value.defined()) {
    p.owned = exclusively_owned(g);
    p.value = std::move(g);
    return;
  }
  if (!p.owned) {
    if (exclusively_owned(g)) {
      accumulate_into(g, p.value);
      p.value = std::move(g);
      p.owned = true;
      return;
    }
    p.value = p.value.clone();
    p.owned = true;
  }
  accumulate_into(p.value, g);
}

void accumulate_leaf(TensorImpl& leaf, Tensor&& g) {
  if (!leaf.grad) {
    leaf.grad = exclusively_owned(g) ? g.impl_ptr() : g.clone().impl_ptr();
    g = Tensor();
    return;
  }
  Tensor acc(leaf.grad);
  if (leaf.grad_zero_pending) {  // cleared by Tensor::clear_grad: overwrite
    leaf.grad_zero_pending = false;
    // A fresh gradient nobody else holds becomes the buffer (no pass at all) when the old
    // buffer has no other view; the gradient tensor stays the same object.
    if (exclusively_owned(g) && leaf.grad->storage.use_count() == 1 && leaf.grad->offset == 0) {
      leaf.grad->storage = g.impl_ptr()->storage;
      g = Tensor();
      return;
    }
    copy_into(acc, g);
    return;
  }
  accumulate_into(acc, g);
}

// Nodes reachable from `root`, each after every node that consumes its output.
std::vector<std::shared_ptr<Node>> reverse_topological(const std::shared_ptr<Node>& root) {
  std::vector<std::shared_ptr<Node>> post_order;
  std::unordered_set<Node*> seen{root.get()};
  std::vector<std::pair<std::shared_ptr<Node>, size_t>> stack{{root, 0}};
  while (!stack.empty()) {
    auto& top = stack.back();
    if (top.second < top.first->inputs.size()) {
      std::shared_ptr<Node> child = top.first->inputs[top.second++].grad_fn();
      if (child && seen.insert(child.get()).second) stack.emplace_back(std::move(child), 0);
    } else {
      post_order.push_back(std::move(top.first));
      stack.pop_back();
    }
  }
  return {post_order.rbegin(), post_order.rend()};
}

}  // namespace

void run_backward(const Tensor& root, const Tensor& grad_root, bool retain_graph) {
  if (!root.requires_grad())
    fail("backward: the tensor does not require grad (no input of its graph has "
         "requires_grad set, or it was computed under no_grad)");
  if (!grad_root.defined() || grad_root.shape() != root.shape() ||
      grad_root.dtype() != root.dtype())
    fail("backward: output gradient ", describe(grad_root), " does not match output ",
         describe(root));
  if (root.is_leaf()) {
    accumulate_leaf(*root.impl(), Tensor(grad_root));
    return;
  }
  const std::vector<std::shared_ptr<Node>> order = reverse_topological(root.grad_fn());
  std::unordered_map<Node*, PendingGrad> pending;
  pending[root.grad_fn().get()].value = grad_root;

  NoGradGuard no_grad;
  for (const std::shared_ptr<Node>& node : order) {
    auto it = pending.find(node.get());
    if (it == pending.end()) continue;
    const Tensor g = std::move(it->second.value);
    pending.erase(it);
    if (node->released)
      fail("backward: the graph through op '", node_op_name(*node),
           "' was freed by an earlier backward; pass retain_graph=true to that call");
    const BackwardContext ctx{node->inputs, node->output, g,
                              node->attrs,  node->saved,  node->needs_grad};
    const bool profiled = profiling_enabled();
    const auto start = profiled ? std::chrono::steady_clock::now() : std::chrono::steady_clock::time_point{};
    std::vector<Tensor> grads = node->op->backward(ctx);
    if (profiled)
      record_op_time(node->op->name, true,
                     std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    if (grads.size() != node->inputs.size())
      fail("backward of op '", node->op->name, "' returned ", grads.size(),
           " gradients for ", node->inputs.size(), " inputs");
    for (size_t i = 0; i < grads.size(); ++i) {
      if (!node->needs_grad[i] || !grads[i].defined()) continue;
      const Tensor& input = node->inputs[i];
      if (grads[i].shape() != input.shape() || grads[i].dtype() != input.dtype())
        fail("backward of op '", node->op->name, "' returned ", describe(grads[i]),
             " for input ", i, " of ", describe(input));
      const auto acc_start =
          profiled ? std::chrono::steady_clock::now() : std::chrono::steady_clock::time_point{};
      if (auto producer = input.grad_fn())
        add_pending(pending[producer.get()], std::move(grads[i]));
      else
        accumulate_leaf(*input.impl(), std::move(grads[i]));
      if (profiled)
        record_op_time("(gradient accumulation)", true,
                       std::chrono::duration<double, std::milli>(
                           std::chrono::steady_clock::now() - acc_start).count());
    }
    if (!retain_graph) {
      // Free what this node kept for its backward; the graph cannot be run again.
      node->inputs.clear();
      node->saved.clear();
      node->output = Tensor();
      node->released = true;
    }
  }
}

}  // namespace weft
