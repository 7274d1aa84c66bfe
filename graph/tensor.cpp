#include "graph/tensor.h"

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <iomanip>
#include <ostream>
#include <sstream>

#include "graph/autograd.h"

namespace weft {

Storage::Storage(size_t bytes_) : bytes(bytes_) {
  const size_t rounded = ((bytes_ + 63) / 64) * 64;
  data = std::aligned_alloc(64, rounded == 0 ? 64 : rounded);
  if (!data) fail("Storage: out of memory allocating ", bytes_, " bytes");
}
Storage::~Storage() { std::free(data); }

namespace {

std::shared_ptr<TensorImpl> new_impl(const Shape& shape, DType dtype) {
  for (int64_t d : shape)
    if (d < 0) fail("Tensor: negative size in shape ", shape_str(shape));
  auto impl = std::make_shared<TensorImpl>();
  impl->shape = shape;
  impl->dtype = dtype;
  impl->storage = std::make_shared<Storage>(static_cast<size_t>(shape_numel(shape)) *
                                            dtype_size(dtype));
  return impl;
}

template <class Fn>
void for_each_dtype(DType d, Fn&& fn) {
  switch (d) {
    case DType::F32: fn.template operator()<float>(); break;
    case DType::F64: fn.template operator()<double>(); break;
    case DType::I64: fn.template operator()<int64_t>(); break;
  }
}

}  // namespace

void Tensor::check_defined(const char* what) const {
  if (!impl_) fail("Tensor::", what, ": tensor is undefined");
}

const Shape& Tensor::shape() const {
  check_defined("shape");
  return impl_->shape;
}
DType Tensor::dtype() const {
  check_defined("dtype");
  return impl_->dtype;
}
int64_t Tensor::size(int64_t axis) const {
  return shape()[normalise_axis(axis, shape().size(), "Tensor::size", shape())];
}
void* Tensor::raw_data() const {
  check_defined("raw_data");
  return static_cast<char*>(impl_->storage->data) + impl_->offset * dtype_size(impl_->dtype);
}

Tensor Tensor::empty(const Shape& shape, DType dtype) { return Tensor(new_impl(shape, dtype)); }

Tensor Tensor::zeros(const Shape& shape, DType dtype) {
  Tensor t = empty(shape, dtype);
  std::memset(t.raw_data(), 0, t.nbytes());
  return t;
}
Tensor Tensor::ones(const Shape& shape, DType dtype) { return full(shape, 1.0, dtype); }
Tensor Tensor::full(const Shape& shape, double value, DType dtype) {
  Tensor t = empty(shape, dtype);
  t.fill(value);
  return t;
}
Tensor Tensor::scalar(double value, DType dtype) { return full({}, value, dtype); }

Tensor Tensor::arange(double start, double end, double step, DType dtype) {
  if (step == 0 || !std::isfinite(start) || !std::isfinite(end) || !std::isfinite(step))
    fail("arange: need finite start, end and a non-zero step, got ", start, ", ", end, ", ",
         step);
  const int64_t n = std::max<int64_t>(0, static_cast<int64_t>(std::ceil((end - start) / step)));
  Tensor t = empty({n}, dtype);
  for_each_dtype(dtype, [&]<class T>() {
    T* p = t.data<T>();
    for (int64_t i = 0; i < n; ++i) p[i] = static_cast<T>(start + step * static_cast<double>(i));
  });
  return t;
}

Tensor Tensor::randn(const Shape& shape, Generator& gen, DType dtype, double mean,
                     double stddev) {
  Tensor t = empty(shape, dtype);
  dispatch_float(dtype, "randn", [&]<class T>() {
    T* p = t.data<T>();
    for (int64_t i = 0, n = t.numel(); i < n; ++i) p[i] = static_cast<T>(gen.normal(mean, stddev));
  });
  return t;
}

Tensor Tensor::rand(const Shape& shape, Generator& gen, DType dtype, double lo, double hi) {
  Tensor t = empty(shape, dtype);
  dispatch_float(dtype, "rand", [&]<class T>() {
    T* p = t.data<T>();
    for (int64_t i = 0, n = t.numel(); i < n; ++i) p[i] = static_cast<T>(gen.uniform(lo, hi));
  });
  return t;
}

Tensor Tensor::from_data(const Shape& shape, const std::vector<double>& values, DType dtype) {
  if (static_cast<int64_t>(values.size()) != shape_numel(shape))
    fail("from_data: shape ", shape_str(shape), " needs ", shape_numel(shape), " values, got ",
         values.size());
  Tensor t = empty(shape, dtype);
  for_each_dtype(dtype, [&]<class T>() {
    T* p = t.data<T>();
    for (size_t i = 0; i < values.size(); ++i) p[i] = static_cast<T>(values[i]);
  });
  return t;
}

Tensor Tensor::from_data(const Shape& shape, const std::vector<float>& values) {
  if (static_cast<int64_t>(values.size()) != shape_numel(shape))
    fail("from_data: shape ", shape_str(shape), " needs ", shape_numel(shape), " values, got ",
         values.size());
  Tensor t = empty(shape, DType::F32);
  std::memcpy(t.raw_data(), values.data(), values.size() * sizeof(float));
  return t;
}

Tensor Tensor::from_indices(const Shape& shape, const std::vector<int64_t>& values) {
  if (static_cast<int64_t>(values.size()) != shape_numel(shape))
    fail("from_indices: shape ", shape_str(shape), " needs ", shape_numel(shape),
         " values, got ", values.size());
  Tensor t = empty(shape, DType::I64);
  std::memcpy(t.raw_data(), values.data(), values.size() * sizeof(int64_t));
  return t;
}

double Tensor::item() const {
  if (numel() != 1) fail("item: tensor ", describe(*this), " has ", numel(), " elements, not 1");
  return at(std::vector<int64_t>(shape().size(), 0));
}

namespace {
int64_t flat_index(const Tensor& t, const std::vector<int64_t>& index) {
  const Shape& s = t.shape();
  if (index.size() != s.size())
    fail("Tensor::at: index of rank ", index.size(), " for shape ", shape_str(s));
  int64_t flat = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    if (index[i] < 0 || index[i] >= s[i])
      fail("Tensor::at: index ", index[i], " out of range for axis ", i, " of shape ",
           shape_str(s));
    flat = flat * s[i] + index[i];
  }
  return flat;
}
}  // namespace

double Tensor::at(const std::vector<int64_t>& index) const {
  const int64_t k = flat_index(*this, index);
  double v = 0;
  for_each_dtype(dtype(), [&]<class T>() { v = static_cast<double>(data<T>()[k]); });
  return v;
}

void Tensor::set(const std::vector<int64_t>& index, double value) {
  const int64_t k = flat_index(*this, index);
  for_each_dtype(dtype(), [&]<class T>() { data<T>()[k] = static_cast<T>(value); });
}

std::vector<double> Tensor::to_vector() const {
  std::vector<double> out(static_cast<size_t>(numel()));
  for_each_dtype(dtype(), [&]<class T>() {
    const T* p = data<T>();
    for (size_t i = 0; i < out.size(); ++i) out[i] = static_cast<double>(p[i]);
  });
  return out;
}

std::string describe(const Tensor& t) {
  if (!t.defined()) return "undefined";
  return std::string(dtype_name(t.dtype())) + " " + shape_str(t.shape());
}

std::string Tensor::to_string(int64_t max_elements) const {
  if (!defined()) return "tensor(undefined)";
  std::ostringstream os;
  os << "tensor(";
  const std::vector<double> v = to_vector();
  const Shape& s = shape();
  const int64_t n = static_cast<int64_t>(v.size());
  const bool truncate = n > max_elements;
  // Nested brackets for each axis; elements past max_elements are elided.
  // block[a]: elements spanned by one index of axis a-1, i.e. one bracket at depth a.
  std::vector<int64_t> block = contiguous_strides(s);
  for (size_t a = 0; a < s.size(); ++a) block[a] *= s[a];
  os << std::setprecision(dtype() == DType::F64 ? 10 : 6);
  if (s.empty()) {
    os << (v.empty() ? 0.0 : v[0]);
  } else {
    for (int64_t i = 0; i < n; ++i) {
      if (truncate && i == max_elements / 2) {
        os << "..., ";
        i = n - max_elements / 2;
      }
      for (size_t a = 0; a < s.size(); ++a)
        if (i % block[a] == 0) os << '[';
      os << v[static_cast<size_t>(i)];
      int closes = 0;
      for (size_t a = 0; a < s.size(); ++a)
        if ((i + 1) % block[a] == 0) ++closes;
      for (int c = 0; c < closes; ++c) os << ']';
      if (i + 1 < n) os << ", ";
    }
  }
  os << ", dtype=" << dtype_name(dtype()) << ", shape=" << shape_str(s);
  if (requires_grad()) os << ", requires_grad";
  os << ')';
  return os.str();
}

std::ostream& operator<<(std::ostream& os, const Tensor& t) { return os << t.to_string(); }

Tensor Tensor::clone() const {
  check_defined("clone");
  Tensor t = empty(shape(), dtype());
  std::memcpy(t.raw_data(), raw_data(), nbytes());
  return t;
}

Tensor Tensor::to(DType target) const {
  check_defined("to");
  if (target == dtype()) return clone();
  Tensor t = empty(shape(), target);
  t.copy_from(*this);
  return t;
}

Tensor Tensor::detach() const {
  check_defined("detach");
  auto impl = std::make_shared<TensorImpl>();
  impl->storage = impl_->storage;
  impl->offset = impl_->offset;
  impl->shape = impl_->shape;
  impl->dtype = impl_->dtype;
  return Tensor(impl);
}

Tensor Tensor::view(const Shape& new_shape) const {
  Tensor t = detach();
  t.impl_->shape = infer_reshape(new_shape, numel(), "view", shape());
  return t;
}

Tensor Tensor::slice_view(int64_t axis, int64_t start, int64_t end) const {
  const Shape& s = shape();
  const int a = normalise_axis(axis, s.size(), "slice_view", s);
  if (start < 0 || end > s[a] || start > end)
    fail("slice_view: range [", start, ", ", end, ") out of bounds for axis ", a, " of shape ",
         shape_str(s));
  for (int i = 0; i < a; ++i)
    if (s[i] != 1)
      fail("slice_view: slicing axis ", a, " of shape ", shape_str(s),
           " is not contiguous; use ops::slice, which copies");
  Tensor t = detach();
  t.impl_->shape[a] = end - start;
  t.impl_->offset += start * contiguous_strides(s)[a];
  return t;
}

bool Tensor::shares_storage(const Tensor& other) const {
  return defined() && other.defined() && impl_->storage == other.impl_->storage;
}

void Tensor::copy_from(const Tensor& src) {
  if (src.shape() != shape())
    fail("copy_from: shapes differ: ", describe(*this), " vs ", describe(src));
  if (src.dtype() == dtype()) {
    std::memmove(raw_data(), src.raw_data(), nbytes());
    return;
  }
  for_each_dtype(dtype(), [&]<class D>() {
    D* d = data<D>();
    for_each_dtype(src.dtype(), [&]<class S>() {
      const S* s = src.data<S>();
      for (int64_t i = 0, n = numel(); i < n; ++i) d[i] = static_cast<D>(s[i]);
    });
  });
}

void Tensor::fill(double value) {
  for_each_dtype(dtype(), [&]<class T>() {
    T* p = data<T>();
    const T v = static_cast<T>(value);
    for (int64_t i = 0, n = numel(); i < n; ++i) p[i] = v;
  });
}

bool Tensor::requires_grad() const { return defined() && impl_->requires_grad; }

Tensor& Tensor::set_requires_grad(bool on) {
  check_defined("set_requires_grad");
  if (impl_->grad_fn)
    fail("set_requires_grad: only leaf tensors can be changed; this one was made by op '",
         node_op_name(*impl_->grad_fn), "' (use detach() first)");
  if (on && dtype() == DType::I64) fail("set_requires_grad: int64 tensors are not differentiable");
  impl_->requires_grad = on;
  return *this;
}

bool Tensor::is_leaf() const { return defined() && !impl_->grad_fn; }

Tensor Tensor::grad() const {
  check_defined("grad");
  if (!impl_->grad) return Tensor();
  Tensor g(impl_->grad);
  if (impl_->grad_zero_pending) {
    g.fill(0.0);
    impl_->grad_zero_pending = false;
  }
  return g;
}
void Tensor::zero_grad() {
  check_defined("zero_grad");
  impl_->grad.reset();
  impl_->grad_zero_pending = false;
}
void Tensor::clear_grad() {
  check_defined("clear_grad");
  impl_->grad_zero_pending = impl_->grad != nullptr;
}
void Tensor::set_grad(const Tensor& g) {
  check_defined("set_grad");
  if (g.defined() && (g.shape() != shape() || g.dtype() != dtype()))
    fail("set_grad: gradient ", describe(g), " does not match tensor ", describe(*this));
  impl_->grad = g.defined() ? g.impl_ptr() : nullptr;
  impl_->grad_zero_pending = false;
}
std::shared_ptr<Node> Tensor::grad_fn() const { return defined() ? impl_->grad_fn : nullptr; }

void Tensor::backward(bool retain_graph) const {
  check_defined("backward");
  if (numel() != 1)
    fail("backward: output ", describe(*this),
         " is not a single value; pass the output gradient explicitly");
  run_backward(*this, Tensor::ones(shape(), dtype()), retain_graph);
}

void Tensor::backward(const Tensor& grad_output, bool retain_graph) const {
  check_defined("backward");
  run_backward(*this, grad_output, retain_graph);
}

}  // namespace weft
