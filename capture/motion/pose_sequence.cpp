#include "capture/motion/pose_sequence.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <numeric>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "graph/atomic_file.h"
#include "geometry/mesh_io.h"
#include "capture/io/png_file.h"
#include "graph/error.h"

namespace weft::capture {

namespace {
std::string frame_name(const std::string& dir, const std::string& stem, int frame, const char* ext) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "_%04d", frame);
  return (std::filesystem::path(dir) / (stem + buf + ext)).string();
}

// A file-name-safe version of a camera name.
std::string safe(const std::string& s) {
  std::string out = s;
  for (char& c : out)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
  return out.empty() ? std::string("camera") : out;
}
}  // namespace

Camera resize_camera(const Camera& c, int width, int height) {
  if (width <= 0 || height <= 0) fail("image size ", width, "x", height, " must be positive");
  Camera out = c;
  const double sx = static_cast<double>(width) / c.width, sy = static_cast<double>(height) / c.height;
  out.K.row(0) *= sx;
  out.K.row(1) *= sy;
  out.width = width;
  out.height = height;
  return out;
}

cv::Mat render_overlay(const Camera& cam, const std::vector<const TriangleMesh*>& meshes,
                       const std::vector<const Vertices*>& posed, const std::vector<cv::Scalar>& colors) {
  cv::Mat image(cam.height, cam.width, CV_8UC3, cv::Scalar(128, 128, 128));
  struct Tri { double depth; int mesh, face; };
  std::vector<Tri> tris;
  std::vector<Points2> uv(meshes.size());
  std::vector<Eigen::VectorXd> depth(meshes.size());
  for (size_t m = 0; m < meshes.size(); ++m) {
    const Vertices& V = *posed[m];
    uv[m] = project_points(cam, V);
    depth[m] = ((V * cam.R.transpose()).rowwise() + cam.t.transpose()).col(2);
    const Faces& F = meshes[m]->F;
    for (int f = 0; f < F.rows(); ++f) {
      const double d = (depth[m](F(f, 0)) + depth[m](F(f, 1)) + depth[m](F(f, 2))) / 3.0;
      if (depth[m](F(f, 0)) > 0 && depth[m](F(f, 1)) > 0 && depth[m](F(f, 2)) > 0)
        tris.push_back({d, static_cast<int>(m), f});
    }
  }
  std::stable_sort(tris.begin(), tris.end(), [](const Tri& a, const Tri& b) { return a.depth > b.depth; });
  const Eigen::Vector3d center = cam.center();
  constexpr int shift = 4;  // sub-pixel precision for cv::fillConvexPoly
  for (const Tri& t : tris) {
    const Vertices& V = *posed[t.mesh];
    const Faces& F = meshes[t.mesh]->F;
    cv::Point pts[3];
    bool inside = true;
    for (int k = 0; k < 3; ++k) {
      const double x = uv[t.mesh](F(t.face, k), 0), y = uv[t.mesh](F(t.face, k), 1);
      if (!std::isfinite(x) || !std::isfinite(y) || std::abs(x) > 1e6 || std::abs(y) > 1e6) inside = false;
      pts[k] = cv::Point(static_cast<int>(std::lround(x * (1 << shift))), static_cast<int>(std::lround(y * (1 << shift))));
    }
    if (!inside) continue;
    const Eigen::Vector3d a = V.row(F(t.face, 0)), b = V.row(F(t.face, 1)), c = V.row(F(t.face, 2));
    Eigen::Vector3d n = (b - a).cross(c - a);
    const Eigen::Vector3d view = (center - (a + b + c) / 3.0).normalized();
    const double len = n.norm();
    const double shade = len > 0 ? 0.35 + 0.65 * std::abs(n.dot(view) / len) : 0.35;
    const cv::Scalar col = colors[t.mesh] * shade;
    cv::fillConvexPoly(image, pts, 3, col, cv::LINE_AA, shift);
  }
  return image;
}

PoseSequenceSummary pose_sequence(const Character& ch, const Motion& motion, const PoseSequenceOptions& o) {
  const int last = o.last_frame < 0 ? motion.num_frames() : o.last_frame;
  if (o.first_frame < 0 || o.first_frame >= last || last > motion.num_frames())
    fail("frames ", o.first_frame, ":", last, " are not a non-empty range within the motion's ",
         motion.num_frames(), " frames");
  if (motion.dofs.cols() != ch.skeleton.num_dofs())
    fail("the motion has ", motion.dofs.cols(), " dofs per frame, the character's skeleton ", ch.skeleton.num_dofs());
  std::error_code ec;
  std::filesystem::create_directories(o.out_dir, ec);
  if (ec) fail(o.out_dir, ": cannot create output folder: ", ec.message());
  for (const Camera& c : o.cameras) validate_camera(c, "cameras");

  PoseSequenceSummary s;
  using clock = std::chrono::steady_clock;
  const int total = last - o.first_frame;
  TriangleMesh body_out = ch.body.mesh, cloth_out;
  if (ch.cloth) cloth_out = ch.cloth->mesh;
  for (int f = o.first_frame; f < last; ++f) {
    const auto t0 = clock::now();
    const PosedCharacter posed = pose_character(ch, motion.dofs.row(f).transpose(), o.method);
    if (!posed.body.allFinite() || (ch.cloth && !posed.cloth.allFinite()))
      fail("frame ", f, ": posing produced non-finite vertex positions (check the motion's values)");
    const auto t1 = clock::now();
    body_out.V = posed.body;
    write_obj(frame_name(o.out_dir, "body", f, ".obj"), body_out);
    ++s.meshes_written;
    if (ch.cloth) {
      cloth_out.V = posed.cloth;
      write_obj(frame_name(o.out_dir, "cloth", f, ".obj"), cloth_out);
      ++s.meshes_written;
    }
    for (const Camera& cam : o.cameras) {
      std::vector<const TriangleMesh*> meshes{&ch.body.mesh};
      std::vector<const Vertices*> verts{&posed.body};
      std::vector<cv::Scalar> colors{cv::Scalar(225, 205, 180)};
      if (ch.cloth) {
        meshes.push_back(&ch.cloth->mesh);
        verts.push_back(&posed.cloth);
        colors.push_back(cv::Scalar(80, 150, 235));
      }
      const cv::Mat image = render_overlay(cam, meshes, verts, colors);
      write_png_atomically(frame_name(o.out_dir, "overlay_" + safe(cam.name), f, ".png"), image);
      ++s.images_written;
    }
    const auto t2 = clock::now();
    s.seconds_posing += std::chrono::duration<double>(t1 - t0).count();
    s.seconds_writing += std::chrono::duration<double>(t2 - t1).count();
    ++s.frames;
    if (o.progress) o.progress(s.frames, total);
  }
  return s;
}

}  // namespace weft::capture
