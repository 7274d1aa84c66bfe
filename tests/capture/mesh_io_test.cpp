#include <gtest/gtest.h>

#include "geometry/mesh.h"
#include "geometry/mesh_io.h"
#include "files/text_reader.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::ScratchDir;
using weft::capture::testing::expect_error;

namespace {

TriangleMesh two_triangles() {
  TriangleMesh m;
  m.V.resize(4, 3);
  m.V << 0, 0, 0, 1.25, 0, 0, 1, 1, 0, 0, 1, 0.1;
  m.F.resize(2, 3);
  m.F << 0, 1, 2, 0, 2, 3;
  return m;
}

TEST(MeshIo, ObjParsesCornerFormsNegativeIndicesPolygonsAndCrlf) {
  const std::string text =
      "# comment\r\nmtllib x.mtl\r\nv 0 0 0\r\nv 1 0 0\r\nv 1 1 0\r\nv 0 1 0\r\n"
      "vt 0 0\r\nvt 1 0\r\nvt 1 1\r\nvt 0 1\r\nvn 0 0 1\r\n"
      "usemtl m\r\nf 1/1/1 2/2/1 3/3/1 4/4/1\r\nf -4/-4 -2/-2 -1/-1\r\n";
  const TriangleMesh m = parse_obj(text, "quad.obj");
  ASSERT_EQ(m.num_vertices(), 4);
  ASSERT_EQ(m.num_faces(), 3);  // the quad becomes a fan of 2, plus one triangle
  EXPECT_EQ(m.F.row(0), Eigen::RowVector3i(0, 1, 2));
  EXPECT_EQ(m.F.row(1), Eigen::RowVector3i(0, 2, 3));
  EXPECT_EQ(m.F.row(2), Eigen::RowVector3i(0, 2, 3));
  ASSERT_TRUE(m.has_uv());
  EXPECT_EQ(m.uv_faces.row(2), Eigen::RowVector3i(0, 2, 3));
  // v//vn corners and faces whose normals do not exist (as in ddc.obj) are fine.
  const TriangleMesh n = parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2//1 3//1\n", "n.obj");
  EXPECT_EQ(n.num_faces(), 1);
  EXPECT_FALSE(n.has_uv());
}

TEST(MeshIo, ObjRoundTripKeepsPositionsUvAndColours) {
  ScratchDir dir("obj");
  TriangleMesh m = two_triangles();
  m.colors = Vertices::Constant(4, 3, 0.5);
  m.uv.resize(4, 2);
  m.uv << 0, 0, 1, 0, 1, 1, 0, 1;
  m.uv_faces = m.F;
  write_obj(dir.file("m.obj"), m);
  const TriangleMesh r = read_obj(dir.file("m.obj"));
  EXPECT_EQ(r.V, m.V);  // 17 significant digits: exact
  EXPECT_EQ(r.F, m.F);
  EXPECT_EQ(r.colors, m.colors);
  EXPECT_EQ(r.uv, m.uv);
  EXPECT_EQ(r.uv_faces, m.uv_faces);
}

TEST(MeshIo, PlyRoundTripAsciiAndBinary) {
  ScratchDir dir("ply");
  TriangleMesh m = two_triangles();
  m.colors.resize(4, 3);
  m.colors << 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1;
  for (PlyFormat f : {PlyFormat::ascii, PlyFormat::binary_little_endian}) {
    write_ply(dir.file("m.ply"), m, f);
    const TriangleMesh r = read_ply(dir.file("m.ply"));
    EXPECT_EQ(r.V, m.V);
    EXPECT_EQ(r.F, m.F);
    EXPECT_TRUE(r.colors.isApprox(m.colors));
  }
  // read_mesh/write_mesh dispatch on the extension.
  write_mesh(dir.file("a.PLY"), m);
  EXPECT_EQ(read_mesh(dir.file("a.PLY")).F, m.F);
  expect_error([&] { write_mesh(dir.file("a.stl"), m); }, {"a.stl", "unknown mesh format"});
}

TEST(MeshIo, PlyReadsFloatVerticesQuadsAndSkipsOtherElements) {
  const std::string text =
      "ply\nformat ascii 1.0\ncomment hi\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nproperty float nx\nelement face 1\nproperty list uchar int vertex_index\n"
      "element edge 1\nproperty int a\nproperty int b\nend_header\n"
      "0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1\n4 0 1 2 3\n0 1\n";
  const TriangleMesh m = parse_ply(text, "q.ply");
  EXPECT_EQ(m.num_vertices(), 4);
  EXPECT_EQ(m.num_faces(), 2);
}

TEST(MeshIo, MalformedObjNamesFileAndLine) {
  expect_error([] { parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9999\n", "ddc.obj"); },
               {"ddc.obj:4:", "vertex index 9999 out of range (3 vertices)"});
  expect_error([] { parse_obj("v 0 0 0\nv nan 0 0\n", "m.obj"); }, {"m.obj:2:", "finite number"});
  expect_error([] { parse_obj("v 0 0\n", "m.obj"); }, {"m.obj:1:", "v x y z"});
  expect_error([] { parse_obj("v 0 0 0\nf 1 1\n", "m.obj"); }, {"m.obj:2:", "at least 3"});
  expect_error([] { parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/x 2 3\n", "m.obj"); }, {"m.obj:4:", "texture index"});
  expect_error([] { parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "m.obj"); }, {"m.obj:4:", "index 0"});
  expect_error([] { parse_obj("# nothing\n", "e.obj"); }, {"e.obj", "no vertices"});
  expect_error([] { parse_obj("v 0 0 0\nfoo 1\n", "m.obj"); }, {"m.obj:2:", "unknown OBJ statement"});
  expect_error([] { read_obj("/nonexistent/weft/x.obj"); }, {"x.obj", "cannot open"});
}

TEST(MeshIo, MalformedPlyNamesFileAndPosition) {
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  expect_error([&] { parse_ply(header + "0 0 0\n1 0 0\n", "t.ply"); }, {"t.ply", "unexpected end of file"});
  expect_error([&] { parse_ply(header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "t.ply"); },
               {"t.ply:13:", "vertex index 7 out of range (3 vertices)"});
  expect_error([&] { parse_ply(header + "0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n", "t.ply"); }, {"t.ply:11:", "finite"});
  expect_error([&] { parse_ply(header + "0 0 0 5\n1 0 0\n0 1 0\n3 0 1 2\n", "t.ply"); }, {"t.ply:10:", "expected 3 values"});
  expect_error([] { parse_ply("ply\nformat binary_big_endian 1.0\nend_header\n", "b.ply"); }, {"b.ply:2:", "unsupported"});
  expect_error([] { parse_ply("ply\nformat ascii 1.0\nelement vertex 3\n", "h.ply"); }, {"h.ply", "end_header"});
  // A truncated binary file.
  ScratchDir dir("plybin");
  write_ply(dir.file("b.ply"), two_triangles(), PlyFormat::binary_little_endian);
  const std::string bytes = read_file_bytes(dir.file("b.ply"));
  expect_error([&] { parse_ply(bytes.substr(0, bytes.size() - 5), "b.ply"); }, {"b.ply: byte", "truncated"});
  EXPECT_EQ(parse_ply(bytes, "b.ply").num_faces(), 2);
}

}  // namespace
