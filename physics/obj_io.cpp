#include "physics/obj_io.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "graph/atomic_file.h"
#include "graph/error.h"

namespace weft::physics {

TriangleMesh read_obj(const std::string& path) {
  std::ifstream in(path);
  WEFT_CHECK(in.good(), path, ": cannot open OBJ file");
  std::vector<Eigen::Vector3d> v;
  TriangleMesh mesh;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string tag;
    if (!(ls >> tag)) continue;
    if (tag == "v") {
      Eigen::Vector3d p;
      WEFT_CHECK(static_cast<bool>(ls >> p[0] >> p[1] >> p[2]) && p.allFinite(), path, ":",
                 line_no, ": expected 'v x y z' with three finite numbers");
      v.push_back(p);
    } else if (tag == "f") {
      std::vector<int> ids;
      std::string tok;
      while (ls >> tok) {
        int id = 0;
        try {
          id = std::stoi(tok.substr(0, tok.find('/')));
        } catch (const std::exception&) {
          fail(path, ":", line_no, ": bad face index '", tok, "'");
        }
        id = id < 0 ? static_cast<int>(v.size()) + id : id - 1;
        WEFT_CHECK(id >= 0 && id < static_cast<int>(v.size()), path, ":", line_no,
                   ": face index ", tok, " refers to a vertex not defined before it");
        ids.push_back(id);
      }
      WEFT_CHECK(ids.size() >= 3, path, ":", line_no, ": a face needs at least 3 vertices");
      for (size_t k = 1; k + 1 < ids.size(); ++k) mesh.faces.push_back({ids[0], ids[k], ids[k + 1]});
    }
  }
  WEFT_CHECK(!v.empty(), path, ": no vertices");
  mesh.vertices.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (size_t i = 0; i < v.size(); ++i) mesh.vertices.row(static_cast<Eigen::Index>(i)) = v[i].transpose();
  return mesh;
}

void write_obj(const std::string& path, const Eigen::VectorXd& x,
               const std::vector<std::array<int, 3>>& faces) {
  std::string s;
  s.reserve(static_cast<size_t>(x.size()) * 12 + faces.size() * 20);
  char buf[128];
  for (Eigen::Index i = 0; i + 2 < x.size(); i += 3) {
    std::snprintf(buf, sizeof(buf), "v %.9g %.9g %.9g\n", x[i], x[i + 1], x[i + 2]);
    s += buf;
  }
  for (const auto& f : faces) {
    std::snprintf(buf, sizeof(buf), "f %d %d %d\n", f[0] + 1, f[1] + 1, f[2] + 1);
    s += buf;
  }
  write_text_atomically(path, s);
}

}  // namespace weft::physics
