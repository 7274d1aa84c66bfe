#pragma once
// Tensor: a shape, a dtype and contiguous row-major storage (NCHW for images), with
// the autograd state of a define-by-run graph (requires_grad, grad, grad_fn).
//
// Copies and views are explicit:
//   - clone() always copies; detach() never does (it shares storage, drops the graph);
//   - view(shape) and slice_view(...) never copy: they alias the storage and throw
//     when the result would not be contiguous; shares_storage() tells two aliases;
//   - the differentiable ops reshape (never copies) and slice (copies unless the
//     selected block is contiguous) live in ops/ops.h and say the same in their docs.
#include <cstdint>
#include <initializer_list>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include "graph/dtype.h"
#include "graph/random.h"
#include "graph/shape.h"

namespace weft {

struct Node;

// Raw, 64-byte aligned bytes shared by a tensor and its views.
struct Storage {
  explicit Storage(size_t bytes);
  ~Storage();
  Storage(const Storage&) = delete;
  Storage& operator=(const Storage&) = delete;
  void* data = nullptr;
  size_t bytes = 0;
};

struct TensorImpl {
  std::shared_ptr<Storage> storage;
  int64_t offset = 0;  // in elements
  Shape shape;
  DType dtype = DType::F32;
  // autograd
  bool requires_grad = false;
  std::shared_ptr<Node> grad_fn;       // the op that produced this tensor (none for leaves)
  std::shared_ptr<TensorImpl> grad;    // accumulated gradient of a leaf
  // The gradient reads as zero but its buffer has not been cleared yet
  // (Tensor::clear_grad): grad() zeroes it, the next backward overwrites it.
  bool grad_zero_pending = false;
};

class Tensor {
 public:
  Tensor() = default;  // undefined tensor
  explicit Tensor(std::shared_ptr<TensorImpl> impl) : impl_(std::move(impl)) {}

  // --- creation ---
  static Tensor empty(const Shape& shape, DType dtype = DType::F32);  // uninitialised
  static Tensor zeros(const Shape& shape, DType dtype = DType::F32);
  static Tensor ones(const Shape& shape, DType dtype = DType::F32);
  static Tensor full(const Shape& shape, double value, DType dtype = DType::F32);
  static Tensor scalar(double value, DType dtype = DType::F32);  // shape []
  // [start, start+step, ...) up to (excluding) end.
  static Tensor arange(double start, double end, double step = 1.0, DType dtype = DType::F32);
  static Tensor randn(const Shape& shape, Generator& gen, DType dtype = DType::F32,
                      double mean = 0.0, double stddev = 1.0);
  static Tensor rand(const Shape& shape, Generator& gen, DType dtype = DType::F32,
                     double lo = 0.0, double hi = 1.0);
  // Copies `values` (row-major, exactly numel of them) into a new tensor.
  static Tensor from_data(const Shape& shape, const std::vector<double>& values,
                          DType dtype = DType::F32);
  static Tensor from_data(const Shape& shape, const std::vector<float>& values);
  static Tensor from_indices(const Shape& shape, const std::vector<int64_t>& values);

  // --- properties ---
  bool defined() const { return impl_ != nullptr; }
  const Shape& shape() const;
  int64_t dim() const { return static_cast<int64_t>(shape().size()); }
  int64_t size(int64_t axis) const;  // negative axes count from the end
  int64_t numel() const { return shape_numel(shape()); }
  DType dtype() const;
  size_t nbytes() const { return static_cast<size_t>(numel()) * dtype_size(dtype()); }

  // Typed pointer to the first element; throws if T is not the tensor's dtype.
  template <class T> T* data();
  template <class T> const T* data() const;
  void* raw_data() const;

  // --- element access (any dtype, converted through double) ---
  double item() const;  // the single element of a one-element tensor
  double at(const std::vector<int64_t>& index) const;
  void set(const std::vector<int64_t>& index, double value);
  std::vector<double> to_vector() const;  // all elements, row-major

  std::string to_string(int64_t max_elements = 64) const;

  // --- copies and views ---
  Tensor clone() const;                 // new storage, no graph
  Tensor to(DType dtype) const;         // converting copy (a clone if the same dtype)
  Tensor detach() const;                // same storage, no graph
  Tensor view(const Shape& shape) const;  // same storage, -1 inferred, no graph
  // Rows [start, end) of axis `axis` as an alias; throws unless the block is contiguous
  // (axis 0, or every axis before it has size 1).
  Tensor slice_view(int64_t axis, int64_t start, int64_t end) const;
  bool shares_storage(const Tensor& other) const;
  void copy_from(const Tensor& src);    // in place, same shape, converts dtype
  void fill(double value);              // in place

  // --- autograd ---
  bool requires_grad() const;
  Tensor& set_requires_grad(bool on = true);  // only on leaves
  bool is_leaf() const;
  Tensor grad() const;                  // undefined until a backward reaches this leaf
  void zero_grad();                     // drops the accumulated gradient
  // Sets the accumulated gradient to zero without a pass over it: the buffer is zeroed
  // when grad() is next read, or replaced (not added to) by the next backward, which then
  // hands over its freshly computed gradient, or copies it in when the old buffer is
  // shared with a view. Read gradients through grad() after a backward: a raw pointer
  // into the buffer from before may be stale.
  void clear_grad();
  void set_grad(const Tensor& g);
  std::shared_ptr<Node> grad_fn() const;
  // Reverse-mode from this tensor: a one-element tensor seeds 1, any other needs an
  // explicit gradient of the same shape. Leaf gradients accumulate.
  void backward(bool retain_graph = false) const;
  void backward(const Tensor& grad_output, bool retain_graph = false) const;

  TensorImpl* impl() const { return impl_.get(); }
  const std::shared_ptr<TensorImpl>& impl_ptr() const { return impl_; }

 private:
  void check_defined(const char* what) const;
  std::shared_ptr<TensorImpl> impl_;
};

std::ostream& operator<<(std::ostream& os, const Tensor& t);

// Two tensors with one shape and dtype: "add: float32 [2, 3] vs float64 [2, 3]".
std::string describe(const Tensor& t);  // "float32 [2, 3]"

template <class T>
T* Tensor::data() {
  check_defined("data");
  if (dtype_of<T>() != impl_->dtype)
    fail("Tensor::data: tensor is ", dtype_name(impl_->dtype), ", asked for ",
         dtype_name(dtype_of<T>()));
  return static_cast<T*>(impl_->storage->data) + impl_->offset;
}
template <class T>
const T* Tensor::data() const {
  return const_cast<Tensor*>(this)->data<T>();
}

}  // namespace weft
