#pragma once
// weft's one exception type. Messages name the op, file, line or key at fault and
// what was expected; callers catch weft::Error at the command line and print it.
#include <sstream>
#include <stdexcept>
#include <string>

namespace weft {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

namespace detail {
inline void append(std::ostringstream&) {}
template <class T, class... Rest>
void append(std::ostringstream& os, const T& first, const Rest&... rest) {
  os << first;
  append(os, rest...);
}
}  // namespace detail

// Builds a message from its parts: fail("conv2d: weight ", shape_str(w), " ...").
template <class... Parts>
[[noreturn]] void fail(const Parts&... parts) {
  std::ostringstream os;
  detail::append(os, parts...);
  throw Error(os.str());
}

#define WEFT_CHECK(cond, ...)          \
  do {                                 \
    if (!(cond)) ::weft::fail(__VA_ARGS__); \
  } while (0)

}  // namespace weft
