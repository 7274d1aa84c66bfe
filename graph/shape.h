#pragma once
// Shapes and the arithmetic on them: element counts, strides, broadcasting, axes.
#include <cstdint>
#include <string>
#include <vector>

namespace weft {

using Shape = std::vector<int64_t>;

std::string shape_str(const Shape& s);           // "[2, 3, 4]"
int64_t shape_numel(const Shape& s);             // product; 1 for a scalar []
std::vector<int64_t> contiguous_strides(const Shape& s);  // row-major, in elements

// NumPy broadcasting of two shapes; `op` names the caller in the error.
Shape broadcast_shapes(const Shape& a, const Shape& b, const char* op);

// Maps a possibly negative axis into [0, rank); error names op and shape.
int normalise_axis(int64_t axis, size_t rank, const char* op, const Shape& shape);

// Sorted, unique, normalised axes; an empty list means "all axes".
std::vector<int> normalise_axes(const std::vector<int64_t>& axes, size_t rank, const char* op,
                                const Shape& shape);

// Resolves one -1 entry in a requested reshape for `numel` elements.
Shape infer_reshape(const Shape& requested, int64_t numel, const char* op, const Shape& from);

}  // namespace weft
