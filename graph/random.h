#pragma once
// Seeded random numbers. Every random creation takes a Generator (or uses the global
// one, seeded by manual_seed) so runs are reproducible; the state serialises to a
// string so checkpoints can resume the exact stream.
#include <cstdint>
#include <random>
#include <string>

namespace weft {

class Generator {
 public:
  explicit Generator(uint64_t seed = 0) : engine_(seed) {}
  double uniform(double lo = 0.0, double hi = 1.0) {
    return std::uniform_real_distribution<double>(lo, hi)(engine_);
  }
  double normal(double mean = 0.0, double stddev = 1.0) {
    return std::normal_distribution<double>(mean, stddev)(engine_);
  }
  int64_t integer(int64_t lo, int64_t hi_inclusive) {
    return std::uniform_int_distribution<int64_t>(lo, hi_inclusive)(engine_);
  }
  std::mt19937_64& engine() { return engine_; }
  std::string state() const;
  void set_state(const std::string& s);

 private:
  std::mt19937_64 engine_;
};

Generator& global_generator();
void manual_seed(uint64_t seed);

}  // namespace weft
