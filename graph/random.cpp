#include "graph/random.h"

#include <sstream>

#include "graph/error.h"

namespace weft {

std::string Generator::state() const {
  std::ostringstream os;
  os << engine_;
  return os.str();
}

void Generator::set_state(const std::string& s) {
  std::istringstream is(s);
  std::mt19937_64 e;
  is >> e;
  if (is.fail()) fail("Generator::set_state: not a generator state string");
  engine_ = e;
}

Generator& global_generator() {
  static Generator g(0x5eed);
  return g;
}

void manual_seed(uint64_t seed) { global_generator() = Generator(seed); }

}  // namespace weft
