#pragma once
// Random numbers that are the same on every platform and standard library, for the
// synthetic studio's files (camera paths, keypoint noise): one seed must give identical
// bytes everywhere, which std::normal_distribution and friends do not promise.
// SplitMix64 (Steele, Lea, Flood 2014) for the bits, 53-bit uniforms, Box–Muller normals.
#include <cmath>
#include <cstdint>

namespace weft::capture {

// SplitMix64's finaliser: a bijective mix of 64 bits (every input bit affects every
// output bit).
inline uint64_t splitmix64_mix(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// One seed from three numbers (e.g. dataset seed, view, frame): distinct triples give
// unrelated streams, and the order matters (mix_seed(s, 1, 2) ≠ mix_seed(s, 2, 1)).
inline uint64_t mix_seed(uint64_t a, uint64_t b, uint64_t c) {
  constexpr uint64_t golden = 0x9E3779B97F4A7C15ull;
  uint64_t h = splitmix64_mix(a + golden);
  h = splitmix64_mix(h ^ (b + 2 * golden));
  return splitmix64_mix(h ^ (c + 3 * golden));
}

class PortableRandom {
 public:
  explicit PortableRandom(uint64_t seed) : state_(seed) {}

  uint64_t next_u64() {
    state_ += 0x9E3779B97F4A7C15ull;
    return splitmix64_mix(state_);
  }
  // Uniform in [0, 1), 53 random bits.
  double uniform() { return static_cast<double>(next_u64() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // Standard normal by Box–Muller (one of the pair; the draw count per call is fixed at
  // two, so streams stay aligned whatever the values).
  double gaussian() {
    const double u1 = 1.0 - uniform();  // (0, 1]: log is finite
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }

 private:
  uint64_t state_;
};

}  // namespace weft::capture
