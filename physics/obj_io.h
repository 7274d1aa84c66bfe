#pragma once
// Minimal Wavefront OBJ reading and writing for triangle meshes: `v x y z` and `f` lines
// (polygons are fan-triangulated; `i/t/n` forms and negative indices are accepted); other
// records are ignored. Writing is atomic: a temporary file renamed into place.
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

namespace weft::physics {

struct TriangleMesh {
  Eigen::MatrixX3d vertices;  // metres
  std::vector<std::array<int, 3>> faces;  // 0-based
};

// Throws weft::Error naming the file and line on malformed input or a missing file.
TriangleMesh read_obj(const std::string& path);

// Writes positions (3n vector) and faces; throws on I/O failure.
void write_obj(const std::string& path, const Eigen::VectorXd& positions,
               const std::vector<std::array<int, 3>>& faces);

}  // namespace weft::physics
