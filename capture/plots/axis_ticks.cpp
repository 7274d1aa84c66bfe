#include "capture/plots/axis_ticks.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>

namespace weft::capture {

double nice_step(double range, int max_ticks) {
  if (!(range > 0)) return 1;
  const double raw = range / std::max(1, max_ticks);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double r = raw / mag;
  return (r <= 1 ? 1 : r <= 2 ? 2 : r <= 5 ? 5 : 10) * mag;
}

std::vector<double> linear_ticks(double lo, double hi, int max_ticks, double min_step) {
  const double step = std::max(min_step, nice_step(hi - lo, max_ticks));
  std::vector<double> t;
  for (double k = std::ceil(lo / step); k * step <= hi + 1e-9 * step; k += 1) t.push_back(k * step);
  return t;
}

std::vector<double> log_ticks(double lo, double hi, int max_ticks, double px_per_decade) {
  auto in_range = [&](std::initializer_list<int> ms) {
    std::vector<double> t;
    for (int e = static_cast<int>(std::floor(lo)) - 1; e <= static_cast<int>(std::ceil(hi)); ++e)
      for (int m : ms) {
        const double l = e + std::log10(m);
        if (l >= lo && l <= hi) t.push_back(l);
      }
    return t;
  };
  std::vector<double> ticks = in_range({1});
  if (static_cast<int>(ticks.size()) > max_ticks) {
    const double d = std::max(1.0, std::round(nice_step(hi - lo, max_ticks)));
    ticks.clear();
    for (double k = std::ceil(lo / d); k * d <= hi; k += 1) ticks.push_back(k * d);
    return ticks;
  }
  for (const auto& group : {in_range({2, 5}), in_range({3}), in_range({4, 6, 8}), in_range({7, 9})}) {
    std::vector<double> more = ticks;
    more.insert(more.end(), group.begin(), group.end());
    std::sort(more.begin(), more.end());
    bool spaced = static_cast<int>(more.size()) <= max_ticks;
    for (size_t i = 1; i < more.size() && spaced; ++i) spaced = (more[i] - more[i - 1]) * px_per_decade >= 18;
    if (!spaced) break;
    ticks = std::move(more);
  }
  if (ticks.size() >= 2) return ticks;
  std::vector<double> lin = linear_ticks(std::pow(10.0, lo), std::pow(10.0, hi), max_ticks);
  for (double& v : lin) v = std::log10(v);
  return lin;
}

}  // namespace weft::capture
