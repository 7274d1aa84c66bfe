#pragma once
// Axis ticks for every plot weft draws (capture/plots/: the loss curves of a training run,
// the per-frame plots of an evaluation report).
#include <vector>

namespace weft::capture {

// 1, 2 or 5 times a power of ten, about range / max_ticks (1 for an empty range).
double nice_step(double range, int max_ticks);

// Multiples of nice_step (at least min_step) in [lo, hi].
std::vector<double> linear_ticks(double lo, double hi, int max_ticks, double min_step = 0);

// Tick positions (log10 of values) on a log axis over [lo, hi] drawn `px_per_decade`
// pixels per decade: the mantissas 1, then 2 and 5, then 3, 4 6 8, 7 9, group by group
// while the ticks stay >= 18 px apart and at most max_ticks; whole decades (every d-th)
// when even the 1s are too many; linear ticks of the values for a range too narrow.
std::vector<double> log_ticks(double lo, double hi, int max_ticks, double px_per_decade);

}  // namespace weft::capture
