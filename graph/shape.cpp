#include "graph/shape.h"

#include <algorithm>
#include <sstream>

#include "graph/error.h"

namespace weft {

std::string shape_str(const Shape& s) {
  std::ostringstream os;
  os << '[';
  for (size_t i = 0; i < s.size(); ++i) os << (i ? ", " : "") << s[i];
  os << ']';
  return os.str();
}

int64_t shape_numel(const Shape& s) {
  int64_t n = 1;
  for (int64_t d : s) n *= d;
  return n;
}

std::vector<int64_t> contiguous_strides(const Shape& s) {
  std::vector<int64_t> st(s.size());
  int64_t acc = 1;
  for (size_t i = s.size(); i-- > 0;) {
    st[i] = acc;
    acc *= s[i];
  }
  return st;
}

Shape broadcast_shapes(const Shape& a, const Shape& b, const char* op) {
  const size_t rank = std::max(a.size(), b.size());
  Shape out(rank);
  for (size_t i = 0; i < rank; ++i) {
    const int64_t da = i < rank - a.size() ? 1 : a[i - (rank - a.size())];
    const int64_t db = i < rank - b.size() ? 1 : b[i - (rank - b.size())];
    if (da != db && da != 1 && db != 1)
      fail(op, ": shapes ", shape_str(a), " and ", shape_str(b), " cannot be broadcast");
    out[i] = da == 1 ? db : da;
  }
  return out;
}

int normalise_axis(int64_t axis, size_t rank, const char* op, const Shape& shape) {
  const int64_t r = static_cast<int64_t>(rank);
  if (axis < -r || axis >= r)
    fail(op, ": axis ", axis, " is out of range for shape ", shape_str(shape));
  return static_cast<int>(axis < 0 ? axis + r : axis);
}

std::vector<int> normalise_axes(const std::vector<int64_t>& axes, size_t rank, const char* op,
                                const Shape& shape) {
  std::vector<int> out;
  if (axes.empty()) {
    for (size_t i = 0; i < rank; ++i) out.push_back(static_cast<int>(i));
    return out;
  }
  for (int64_t a : axes) out.push_back(normalise_axis(a, rank, op, shape));
  std::sort(out.begin(), out.end());
  if (std::adjacent_find(out.begin(), out.end()) != out.end())
    fail(op, ": repeated axis for shape ", shape_str(shape));
  return out;
}

Shape infer_reshape(const Shape& requested, int64_t numel, const char* op, const Shape& from) {
  Shape out = requested;
  int infer = -1;
  int64_t known = 1;
  for (size_t i = 0; i < out.size(); ++i) {
    if (out[i] == -1) {
      if (infer >= 0) fail(op, ": more than one -1 in ", shape_str(requested));
      infer = static_cast<int>(i);
    } else if (out[i] < 0) {
      fail(op, ": negative size in ", shape_str(requested));
    } else {
      known *= out[i];
    }
  }
  if (infer >= 0) {
    if (known == 0 || numel % known != 0)
      fail(op, ": cannot reshape ", shape_str(from), " into ", shape_str(requested));
    out[infer] = numel / known;
  }
  if (shape_numel(out) != numel)
    fail(op, ": cannot reshape ", shape_str(from), " (", numel, " elements) into ",
         shape_str(requested));
  return out;
}

}  // namespace weft
