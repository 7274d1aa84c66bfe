#pragma once
// What the command-line benchmarks that measure poses share: the angle of a direction from
// the vertical, and a main() that turns an error into its message and exit status 1.
#include <Eigen/Core>

#include <cmath>
#include <cstdio>
#include <exception>
#include <numbers>

namespace weft::bench {

// The angle of v from the vertical (+y), degrees.
inline double angle_from_vertical_deg(const Eigen::Vector3d& v) {
  return std::atan2(Eigen::Vector2d(v.x(), v.z()).norm(), v.y()) * 180 / std::numbers::pi;
}

// run(argc, argv), or "name: message" on stderr and 1 when it throws.
template <class Run>
int run_tool(const char* name, Run run, int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", name, e.what());
    return 1;
  }
}

}  // namespace weft::bench
