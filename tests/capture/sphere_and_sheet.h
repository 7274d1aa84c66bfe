#pragma once
// The evaluation tests' constructed character, in metres: a sphere body and a 0.2 m square
// sheet garment centred at (0, 1, 0.4), no anchors (nothing pinned).
#include <Eigen/Core>

#include "capture/character/character.h"
#include "geometry/mesh.h"
#include "tests/capture/grid_mesh.h"

namespace weft::capture::testing {

// The sphere has `radius` (m) around `centre`, `rings` × `segments` quads.
inline Character sphere_and_sheet(const Eigen::Vector3d& centre, double radius = 0.3, int rings = 24,
                                  int segments = 48) {
  Character ch;
  ch.name = "sphere_and_sheet";
  ch.source = "constructed";
  ch.metres_per_unit = 1.0;
  ch.body.mesh = uv_sphere(centre, radius, rings, segments);
  ch.cloth.emplace();
  ch.cloth->mesh = grid_mesh(Eigen::Vector3d(-0.1, 0.9, 0.4), 0.2, 5, 5);
  return ch;
}

}  // namespace weft::capture::testing
