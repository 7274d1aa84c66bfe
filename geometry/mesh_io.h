#pragma once
// Reading and writing triangle meshes as OBJ and PLY.
//
// OBJ in: `v x y z [r g b]`, `vt u v`, `vn`, `f` with v, v/vt, v//vn or v/vt/vn corners,
// negative (relative) indices, polygons triangulated as fans, `#` comments, any line
// ends (ddc.obj has CRLF); other statements (o, g, s, usemtl, mtllib, l) are ignored.
// PLY in: ascii and binary_little_endian; vertex x y z [red green blue], face lists
// (vertex_indices or vertex_index), other elements and properties skipped.
// Writes are atomic (temporary file + rename). Errors name the file and the line (OBJ,
// ASCII PLY) or byte offset (binary PLY) and what was expected.
#include <string>

#include "geometry/mesh.h"

namespace weft {

TriangleMesh read_obj(const std::string& path);
TriangleMesh parse_obj(std::string text, const std::string& name);
void write_obj(const std::string& path, const TriangleMesh& mesh);

enum class PlyFormat { ascii, binary_little_endian };
TriangleMesh read_ply(const std::string& path);
TriangleMesh parse_ply(std::string bytes, const std::string& name);
void write_ply(const std::string& path, const TriangleMesh& mesh,
               PlyFormat format = PlyFormat::binary_little_endian);

// By extension (.obj or .ply, case-insensitive); anything else is an error.
TriangleMesh read_mesh(const std::string& path);
void write_mesh(const std::string& path, const TriangleMesh& mesh);

}  // namespace weft
