// Randomised mutation of small valid files: every parse must either succeed or throw
// weft::Error, never crash, hang or throw anything else. Run under WEFT_SANITIZE=ON to
// catch memory errors as well.
#include <gtest/gtest.h>

#include <functional>
#include <random>

#include "capture/io/camera.h"
#include "capture/character/character.h"
#include "geometry/mesh_io.h"
#include "capture/io/openpose.h"
#include "capture/character/skeletool_io.h"
#include "files/text_reader.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::ScratchDir;

namespace {

std::string mutate(const std::string& s, std::mt19937& rng) {
  std::string out = s;
  const char pool[] = "0123456789-+.eE \t\r\n/#:naif\xff\x00";
  std::uniform_int_distribution<int> kind(0, 5);
  const int edits = 1 + static_cast<int>(rng() % 4);
  for (int e = 0; e < edits && !out.empty(); ++e) {
    const size_t at = rng() % out.size();
    switch (kind(rng)) {
      case 0: out[at] = pool[rng() % (sizeof(pool) - 1)]; break;           // replace a byte
      case 1: out.insert(out.begin() + at, pool[rng() % (sizeof(pool) - 1)]); break;  // insert
      case 2: out.erase(at, 1 + rng() % 8); break;                          // delete a run
      case 3: out.resize(at); break;                                        // truncate
      case 4: out[at] = static_cast<char>(rng() & 0xff); break;             // random byte
      case 5: {                                                             // duplicate a run
        const size_t len = std::min<size_t>(1 + rng() % 40, out.size() - at);
        out.insert(at, out.substr(at, len));
        break;
      }
    }
  }
  return out;
}

// Runs `parse` on `count` mutants of `valid`; counts outcomes.
void fuzz(const std::string& label, const std::string& valid, int count,
          const std::function<void(const std::string&)>& parse) {
  ASSERT_NO_THROW(parse(valid)) << label << ": the unmutated file must parse";
  std::mt19937 rng(12345);
  int ok = 0, errors = 0;
  for (int i = 0; i < count; ++i) {
    const std::string m = mutate(valid, rng);
    try {
      parse(m);
      ++ok;
    } catch (const weft::Error& e) {
      ++errors;
      EXPECT_FALSE(std::string(e.what()).empty());
    } catch (const std::exception& e) {
      ADD_FAILURE() << label << ": mutant " << i << " threw a non-weft exception: " << e.what();
    }
  }
  EXPECT_EQ(ok + errors, count);
  EXPECT_GT(errors, 0) << label << ": no mutant was rejected; the fuzzer is not biting";
}

TriangleMesh small_mesh() {
  TriangleMesh m;
  m.V.resize(5, 3);
  m.V << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 0.5, 1;
  m.F.resize(4, 3);
  m.F << 0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4;
  m.colors = Vertices::Constant(5, 3, 0.5);
  return m;
}

TEST(ParserFuzz, Obj) {
  const std::string obj =
      "# t\r\nv 0 0 0 1 0 0\r\nv 1 0 0 1 0 0\r\nv 1 1 0 1 0 0\r\nv 0 1 0 1 0 0\r\nvt 0 0\r\nvt 1 0\r\nvt 1 1\r\n"
      "vn 0 0 1\r\nf 1/1/1 2/2/1 3/3/1 4/1/1\r\nf -1/-1 -2/-2 -3/-3\r\n";
  fuzz("obj", obj, 400, [](const std::string& t) { parse_obj(t, "f.obj"); });
}

TEST(ParserFuzz, PlyAsciiAndBinary) {
  ScratchDir dir("fuzzply");
  for (PlyFormat f : {PlyFormat::ascii, PlyFormat::binary_little_endian}) {
    write_ply(dir.file("m.ply"), small_mesh(), f);
    const std::string bytes = read_file_bytes(dir.file("m.ply"));
    fuzz(f == PlyFormat::ascii ? "ply ascii" : "ply binary", bytes, 300,
         [](const std::string& t) { parse_ply(t, "f.ply"); });
  }
}

TEST(ParserFuzz, SkeletonSkinMotion) {
  const std::string skel = weft::capture::testing::small_skeleton_text();
  fuzz("skeleton", skel, 400, [](const std::string& t) { parse_skeleton(t, "f.skeleton"); });
  const Skeleton s = parse_skeleton(skel, "s.skeleton");
  const std::string skin =
      "Skeletool character skinning file V1.0\r\nbones:\r\n   root hip knee foot\r\nvertex weights:\r\n"
      "0 1 0.750 2 0.250\r\n1 2 0.51 0 0.51\r\n2 0 2.55001e-0712 3 1\r\n";
  fuzz("skin", skin, 400, [&](const std::string& t) { parse_skin(t, "f.skin", s, -1); });
  fuzz("skin (3 vertices)", skin, 200, [&](const std::string& t) { parse_skin(t, "f.skin", s, 3); });
  const std::string motion = "Skeletool Motion File V1.0\r\n0 0.1 0.2 0.3\r\n1 -0.1 1e-3 2\r\n";
  fuzz("motion", motion, 300, [&](const std::string& t) {
    const Motion m = parse_motion(t, "f.motion", -1);
    if (m.dofs.cols() == s.num_dofs())
      for (int f = 0; f < m.num_frames(); ++f) forward_kinematics(s, m.dofs.row(f).transpose());
  });
}

TEST(ParserFuzz, CamerasCalibrationOpenPose) {
  ScratchDir dir("fuzzcam");
  Camera c;
  c.name = "a";
  c.K << 500, 0, 320, 0, 500, 240, 0, 0, 1;
  c.width = 640;
  c.height = 480;
  write_cameras_yaml(dir.file("c.yaml"), {c});
  const std::string yaml = read_file_bytes(dir.file("c.yaml"));
  fuzz("camera yaml", yaml, 300, [&](const std::string& t) { read_cameras_yaml(dir.write("m.yaml", t)); });
  const std::string calib =
      "Skeletool Camera Calibration File V1.0\nname 0\n  sensor 14 10\n  size 640 480\n  animated 0\n"
      "  intrinsic 500 0 320 0 0 500 240 0 0 0 1 0 0 0 0 1\n  extrinsic 1 0 0 0 0 1 0 0 0 0 1 3000 0 0 0 1\n"
      "  radial 0\n";
  fuzz("calibration", calib, 300, [&](const std::string& t) { read_skeletool_calibration(dir.write("m.calibration", t)); });
  OpenPoseFrame f;
  f.people = {Body25::Constant(1.5)};
  write_openpose_json(dir.file("k.json"), f);
  const std::string json = read_file_bytes(dir.file("k.json"));
  fuzz("openpose", json, 300, [](const std::string& t) { parse_openpose_json(t, "k.json"); });
}

}  // namespace
