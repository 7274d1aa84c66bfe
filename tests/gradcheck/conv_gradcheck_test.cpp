#include "tests/gradcheck/cases.h"

namespace weft::testing {

// conv2d: x [N,C,H,W], weight [O,C,kh,kw], optional bias [O].
static GradcheckCase conv_case(const std::string& name, Shape x, Shape w, bool bias,
                               std::vector<int64_t> stride, std::vector<int64_t> pad,
                               std::vector<int64_t> dil) {
  std::vector<Shape> shapes{std::move(x), w};
  if (bias) shapes.push_back({w[0]});
  return uniform_case("conv2d", name, shapes,
                      {{"stride", stride}, {"padding", pad}, {"dilation", dil}});
}

WEFT_GRADCHECK_CASES(conv2d) {
  return {
      conv_case("3x3 pad 1 bias", {2, 2, 5, 5}, {3, 2, 3, 3}, true, {1, 1}, {1, 1}, {1, 1}),
      conv_case("3x3 stride 2 odd size", {1, 2, 7, 6}, {2, 2, 3, 3}, true, {2, 2}, {1, 1},
                {1, 1}),
      conv_case("3x3 dilation 2", {1, 2, 7, 7}, {2, 2, 3, 3}, false, {1, 1}, {2, 2}, {2, 2}),
      conv_case("1x1 fast path", {2, 3, 3, 4}, {4, 3, 1, 1}, true, {1, 1}, {0, 0}, {1, 1}),
      conv_case("1x1 stride 2", {2, 3, 5, 5}, {2, 3, 1, 1}, false, {2, 2}, {0, 0}, {1, 1}),
      conv_case("2x3 kernel mixed stride/pad", {1, 2, 6, 5}, {2, 2, 2, 3}, true, {2, 1},
                {0, 1}, {1, 2}),
      conv_case("size-1 dims", {1, 1, 1, 1}, {1, 1, 1, 1}, true, {1, 1}, {0, 0}, {1, 1}),
      conv_case("3x3 on 1x1 padded", {3, 1, 1, 1}, {2, 1, 3, 3}, false, {1, 1}, {1, 1},
                {1, 1}),
  };
}

}  // namespace weft::testing
