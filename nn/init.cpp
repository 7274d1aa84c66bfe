#include "nn/init.h"

#include <cmath>
#include <random>

#include "graph/error.h"

namespace weft::nn {

namespace {
int64_t receptive_field(const Tensor& w) {
  if (w.dim() < 2) fail("init: weight ", describe(w), " needs at least 2 dimensions");
  int64_t r = 1;
  for (int64_t i = 2; i < w.dim(); ++i) r *= w.size(i);
  return r;
}

// One distribution object per tensor (the normal one caches its second value), drawing
// from the generator's engine so the generator's state advances.
void fill_from(Tensor& t, Generator& gen, bool normal, double a, double b) {
  dispatch_float(t.dtype(), "init", [&]<class T>() {
    T* p = t.data<T>();
    const int64_t n = t.numel();
    if (normal) {
      std::normal_distribution<double> dist(a, b);
      for (int64_t i = 0; i < n; ++i) p[i] = static_cast<T>(dist(gen.engine()));
    } else {
      std::uniform_real_distribution<double> dist(a, b);
      for (int64_t i = 0; i < n; ++i) p[i] = static_cast<T>(dist(gen.engine()));
    }
  });
}
}  // namespace

int64_t fan_in(const Tensor& weight) { return weight.size(1) * receptive_field(weight); }
int64_t fan_out(const Tensor& weight) { return weight.size(0) * receptive_field(weight); }

void kaiming_normal_fan_out_relu(Tensor& weight, Generator& gen) {
  const double stddev = std::sqrt(2.0) / std::sqrt(static_cast<double>(fan_out(weight)));
  fill_from(weight, gen, true, 0.0, stddev);
}

void uniform_fan_in(Tensor& t, int64_t fan_in, Generator& gen) {
  if (fan_in <= 0) fail("init: fan-in ", fan_in, " must be positive");
  const double bound = 1.0 / std::sqrt(static_cast<double>(fan_in));
  fill_from(t, gen, false, -bound, bound);
}

}  // namespace weft::nn
