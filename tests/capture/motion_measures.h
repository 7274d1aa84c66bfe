#pragma once
// Measures of a generated motion shared by the motion tests.
#include <algorithm>

#include "capture/motion/bvh.h"

namespace weft::capture::testing {

// Largest |second difference| / dt² over all channels: an acceleration estimate. For a
// C1 motion it stays bounded as dt shrinks; a kink (velocity jump Δv) makes it ≈ Δv/dt.
inline double max_acceleration(const BvhMotion& m) {
  const double dt = m.frame_time_s;
  double a = 0;
  for (int f = 1; f + 1 < m.num_frames(); ++f)
    a = std::max(a, (m.frames.row(f + 1) - 2 * m.frames.row(f) + m.frames.row(f - 1)).cwiseAbs().maxCoeff() / (dt * dt));
  return a;
}

}  // namespace weft::capture::testing
