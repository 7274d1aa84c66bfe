// Synthetic studio renderer speed: milliseconds per rendered view (shaded RGB, mask,
// parts, depth) of
//   ddc:      the ddc body (5,514 vertices, 11,024 triangles, textured with ddc.png) in its
//             bind pose, seen from the front, green screen; read through
//             configs/characters/ddc.yaml when ../shared/data/ddc exists, skipped otherwise;
//   ddc+clutter: the same over a cluttered background generated per view (seeded);
//   sphere:   a 10,080-triangle sphere with per-vertex colours, green screen;
// at each image size and thread count; the person's height fills ~80 % of the frame.
// Also the distance transform of the ddc (or sphere) mask. Wall time: medians over the
// repeats after a warm-up; CPU time: the process's (all threads), mean per view.
//
//   bench_render [--repeats 15] [--sizes 512,1024] [--threads 1,2] [--supersample 1] [--out DIR]
// --out also writes each scene's last view (rgb, mask, parts, distance transform) as PNG.
#include <sys/resource.h>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "capture/character/character.h"
#include "capture/render/renderer.h"
#include "graph/threads.h"

namespace {

using namespace weft;
using namespace weft::capture;
using Clock = std::chrono::steady_clock;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// CPU seconds of the whole process (all threads) so far: on this loaded, shared machine
// the wall time includes waiting for a core, the CPU time does not.
double process_cpu_seconds() {
  rusage u;
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

std::string loadavg() {
  std::ifstream f("/proc/loadavg");
  std::string a, b, c;
  f >> a >> b >> c;
  return a + " " + b + " " + c;
}

std::vector<int> int_list(const std::string& s) {
  std::vector<int> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) out.push_back(std::atoi(item.c_str()));
  return out;
}

// A latitude–longitude sphere of radius 1 m (in mm) with smoothly varying colours:
// 71 rings × 72 segments, two triangles per cell except at the poles: 10,080 triangles.
TriangleMesh sphere_mesh() {
  TriangleMesh m = uv_sphere(Eigen::Vector3d::Zero(), 1000, 71, 72);
  m.uv.resize(0, 2);
  m.uv_faces.resize(0, 3);
  m.colors.resize(m.V.rows(), 3);
  for (int k = 0; k < m.V.rows(); ++k) {
    const int i = k / 73, j = k % 73;
    const double theta = M_PI * i / 71, phi = 2 * M_PI * j / 72;
    m.colors.row(k) << 0.5 + 0.4 * std::cos(phi), 0.5 + 0.4 * std::sin(theta), 0.6;
  }
  return m;
}

// A view from +z (ddc's face; y up) of the vertices' bounding box: its height fills 80 %
// of a square image of `size` pixels from 3 heights away.
Camera front_camera(const Vertices& V, int size) {
  const Eigen::RowVector3d lo = V.colwise().minCoeff(), hi = V.colwise().maxCoeff();
  const Eigen::Vector3d centre = (0.5 * (lo + hi)).transpose();
  const double height = hi.y() - lo.y(), distance = 3 * height;
  Camera c;
  c.name = "front";
  const double f = 0.8 * size * distance / height;
  c.K << f, 0, 0.5 * (size - 1), 0, f, 0.5 * (size - 1), 0, 0, 1;
  c.R << 1, 0, 0, 0, -1, 0, 0, 0, -1;  // camera x = world x, y = −world y (down), z = −world z
  c.t = -c.R * (centre + Eigen::Vector3d(0, 0, distance));
  c.width = c.height = size;
  return c;
}

struct Scene {
  std::string name;
  std::vector<RenderMesh> meshes;
  Background background;
  const Vertices* frame = nullptr;  // what the camera frames
  int triangles = 0;
};

}  // namespace

int main(int argc, char** argv) {
  int repeats = 15, supersample = 1;
  std::string out_dir;
  std::vector<int> sizes{512, 1024}, threads{1, 2};
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i], v = argv[i + 1];
    if (a == "--repeats")
      repeats = std::max(1, std::atoi(v.c_str()));
    else if (a == "--sizes")
      sizes = int_list(v);
    else if (a == "--threads")
      threads = int_list(v);
    else if (a == "--supersample")
      supersample = std::atoi(v.c_str());
    else if (a == "--out")
      out_dir = v;
    else {
      std::fprintf(stderr,
                   "unknown option %s\nusage: bench_render [--repeats 15] [--sizes 512,1024] "
                   "[--threads 1,2] [--supersample 1] [--out DIR]\n",
                   a.c_str());
      return 2;
    }
  }

  std::vector<Scene> scenes;
  const std::string ddc_dir = WEFT_BENCH_SOURCE_DIR "/../shared/data/ddc";
  Character ddc;
  cv::Mat ddc_texture;
  if (std::filesystem::exists(ddc_dir + "/ddc.skeleton")) {
    ddc = load_character(WEFT_BENCH_SOURCE_DIR "/configs/characters/ddc.yaml");
    ddc_texture = cv::imread(ddc_dir + "/ddc.png", cv::IMREAD_COLOR);
    RenderMesh body;
    body.mesh = &ddc.body.mesh;
    if (!ddc_texture.empty() && ddc.body.mesh.has_uv()) {
      body.source = ColorSource::texture;
      body.texture = ddc_texture;
    }
    Scene green{"ddc", {body}, {}, &ddc.body.mesh.V, ddc.body.mesh.num_faces()};
    Scene clutter = green;
    clutter.name = "ddc+clutter";
    clutter.background.kind = BackgroundKind::clutter;
    clutter.background.seed = 1;
    scenes.push_back(green);
    scenes.push_back(clutter);
  } else {
    std::printf("ddc data not found at %s: sphere only\n", ddc_dir.c_str());
  }
  const TriangleMesh ball = sphere_mesh();
  RenderMesh ball_mesh;
  ball_mesh.mesh = &ball;
  ball_mesh.source = ColorSource::vertex;
  scenes.push_back({"sphere", {ball_mesh}, {}, &ball.V, ball.num_faces()});

  const std::string load_before = loadavg();
  std::printf("%-12s %5s %9s %9s %7s | %9s %8s | %10s\n", "scene", "tris", "size", "covered",
              "threads", "ms/view", "views/s", "cpu ms/view");
  for (int size : sizes)
    for (const Scene& s : scenes) {
      const Camera cam = front_camera(*s.frame, size);
      RenderOptions o;
      o.background = s.background;
      o.supersample = supersample;
      for (int t : threads) {
        set_num_threads(t);
        cv::setNumThreads(t);  // OpenCV's own pool: the clutter background's resize and blur
        RenderResult r;
        for (int w = 0; w < 3; ++w) r = render(cam, s.meshes, o);  // warm-up: pages, TBB workers
        std::vector<double> ms;
        const double cpu0 = process_cpu_seconds();
        for (int k = 0; k < repeats; ++k) {
          const auto t0 = Clock::now();
          r = render(cam, s.meshes, o);
          ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
        }
        const double cpu_ms = 1000 * (process_cpu_seconds() - cpu0) / repeats;
        const double m = median(ms);
        if (!out_dir.empty()) {
          std::filesystem::create_directories(out_dir);
          const std::string stem = out_dir + "/" + s.name + "_" + std::to_string(size);
          cv::Mat dt;
          cv::normalize(distance_transform(r.mask), dt, 0, 255, cv::NORM_MINMAX, CV_8U);
          cv::imwrite(stem + "_rgb.png", r.rgb);
          cv::imwrite(stem + "_mask.png", r.mask);
          cv::imwrite(stem + "_parts.png", r.parts * 100);
          cv::imwrite(stem + "_dt.png", dt);
        }
        std::printf("%-12s %5d %4dx%-4d %8.1f%% %7d | %9.2f %8.1f | %10.2f\n", s.name.c_str(),
                    s.triangles, size, size,
                    100.0 * cv::countNonZero(r.mask) / (double(size) * size), t, m, 1000 / m,
                    cpu_ms);
      }
    }
  // The distance transform of the first scene's mask (not part of render()).
  for (int size : sizes) {
    const Camera cam = front_camera(*scenes.front().frame, size);
    const cv::Mat mask = render(cam, scenes.front().meshes).mask;
    std::vector<double> ms;
    for (int k = 0; k < repeats; ++k) {
      const auto t0 = Clock::now();
      const cv::Mat dt = distance_transform(mask);
      ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    }
    std::printf("distance_transform %4dx%-4d (%s mask): %.2f ms\n", size, size,
                scenes.front().name.c_str(), median(ms));
  }
  std::printf(
      "supersample %d, median of %d after 3 warm-up renders; load average %s (before) %s (after)\n",
      supersample, repeats, load_before.c_str(), loadavg().c_str());
  return 0;
}
