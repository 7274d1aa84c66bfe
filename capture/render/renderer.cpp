#include "capture/render/renderer.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string>

#include "graph/error.h"

namespace weft::capture {

namespace {

// Projected vertices are snapped to 1/256 pixel so that edge functions are exact integers:
// two triangles sharing an edge then agree on every sample along it.
constexpr int kSubpixelBits = 8;
constexpr int64_t kOne = int64_t{1} << kSubpixelBits;
// Coordinates beyond 2²¹ pixels would overflow the 64-bit edge functions (2 · 2³⁰ · 2³⁰).
constexpr double kMaxPixel = double(1 << 21);
// Output rows per band: the unit of parallel work. Small enough for 2 threads to balance
// a person in part of the frame, large enough that binning stays cheap.
constexpr int kBandRows = 8;

// A triangle ready to rasterise, in sample coordinates (pixels × supersample).
struct ScreenTriangle {
  int64_t x[3], y[3];  // corners, fixed point (1/256 sample)
  double inv_z[3];     // 1 / camera depth of each corner
  double inv_area;     // 1 / doubled signed area (fixed point²), the area being > 0
  int x0, x1, y0, y1;  // range of covered samples (inclusive), clipped to the image
  int mesh, face;
  int corner[3];  // the face corner (0..2) each entry came from; two swap to make the area > 0
};

// What shading needs of one input mesh.
struct ShadingMesh {
  const RenderMesh* in = nullptr;
  const Vertices* V = nullptr;
  Vertices normals;       // unit vertex normals (world)
  Vertices face_normals;  // for vertices whose neighbouring faces cancel
  Vertices bgr;           // ColorSource::vertex: BGR 0..255 per vertex
};

struct Light {
  Eigen::Vector3d toward;  // unit vector from the surface toward the light (world)
  double intensity;
};

// Per-thread rasterisation buffers of one band, reused across bands.
struct BandBuffers {
  std::vector<double> inv_z;  // 0: empty
  std::vector<int> triangle;  // index into the screen triangles, −1: empty
  std::vector<float> b1, b2;  // perspective-correct barycentrics of corners 1 and 2
};

std::string mesh_name(size_t index, const RenderMesh& m) {
  return "render: mesh " + std::to_string(index) + " (part " + std::to_string(m.part) + ")";
}

void check_options(const RenderOptions& o) {
  if (o.supersample < 1 || o.supersample > 7 || o.supersample % 2 == 0)
    fail("render: supersample must be odd, 1..7 (its centre sample is the pixel centre), got ",
         o.supersample);
  if (!std::isfinite(o.near) || !(o.near > 0))
    fail("render: near must be positive and finite, got ", o.near);
  const Lighting& l = o.lighting;
  const std::initializer_list<std::pair<const char*, double>> terms = {
      {"ambient", l.ambient}, {"headlight", l.headlight}, {"exposure", l.exposure}};
  for (const auto& [name, value] : terms)
    if (!std::isfinite(value) || value < 0)
      fail("render: lighting ", name, " must be finite and ≥ 0, got ", value);
  for (size_t k = 0; k < l.lights.size(); ++k) {
    const DirectionalLight& d = l.lights[k];
    if (!d.direction.allFinite() || d.direction.norm() < 1e-12)
      fail("render: light ", k, " needs a finite, nonzero direction");
    if (!std::isfinite(d.intensity) || d.intensity < 0)
      fail("render: light ", k, " intensity must be finite and ≥ 0, got ", d.intensity);
  }
}

void check_mesh(size_t index, const RenderMesh& m) {
  const std::string what = mesh_name(index, m);
  if (!m.mesh) fail(what, ": no TriangleMesh (null pointer)");
  const TriangleMesh& mesh = *m.mesh;
  const Vertices& V = m.vertices ? *m.vertices : mesh.V;
  if (V.rows() != mesh.V.rows())
    fail(what, ": ", V.rows(), " posed vertices for a mesh of ", mesh.V.rows(), " vertices");
  if (m.part < 1 || m.part > 255)
    fail(what, ": part id must be within 1..255 (0 is the background)");
  const Eigen::Index n = V.rows();
  for (Eigen::Index i = 0; i < n; ++i)
    if (!V.row(i).allFinite())
      fail(what, ": vertex ", i, " is not finite (", V(i, 0), ", ", V(i, 1), ", ", V(i, 2), ")");
  const Faces& F = mesh.F;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (F(f, k) < 0 || F(f, k) >= n)
        fail(what, ": face ", f, " refers to vertex ", F(f, k), ", outside 0..", n - 1);
  switch (m.source) {
    case ColorSource::flat:
      for (int c = 0; c < 3; ++c)
        if (!std::isfinite(m.color[c])) fail(what, ": flat colour is not finite");
      break;
    case ColorSource::vertex:
      if (mesh.colors.rows() != n)
        fail(what, ": per-vertex colours requested but the mesh has ", mesh.colors.rows(),
             " colours for ", n, " vertices");
      if (!mesh.colors.allFinite()) fail(what, ": per-vertex colours are not finite");
      break;
    case ColorSource::texture: {
      if (m.texture.empty())
        fail(what, ": texture colours requested but the texture image is empty");
      if (m.texture.type() != CV_8UC3)
        fail(what, ": texture must be CV_8UC3 (BGR), got ", cv::typeToString(m.texture.type()));
      if (mesh.uv_faces.rows() != F.rows() || mesh.uv.rows() == 0)
        fail(what, ": texture colours requested but the mesh has no texture coordinates (uv ",
             mesh.uv.rows(), " rows, uv_faces ", mesh.uv_faces.rows(), " for ", F.rows(),
             " faces)");
      if (!mesh.uv.allFinite()) fail(what, ": texture coordinates are not finite");
      const Eigen::Index t = mesh.uv.rows();
      for (Eigen::Index f = 0; f < F.rows(); ++f)
        for (int k = 0; k < 3; ++k)
          if (mesh.uv_faces(f, k) < 0 || mesh.uv_faces(f, k) >= t)
            fail(what, ": uv face ", f, " refers to texture coordinate ", mesh.uv_faces(f, k),
                 ", outside 0..", t - 1);
      break;
    }
  }
}

// A vertex in sample space, or not drawable.
struct ScreenVertex {
  int64_t x, y;
  double inv_z;
  bool ok;
};

// The lens model r_d = r (1 + k1 r² + k2 r⁴ + k3 r⁶) stops growing with r beyond some
// radius and folds far-off points back into the image; such points are not drawable.
bool radially_monotonic(const Camera& c, double r2) {
  const double k1 = c.dist(0), k2 = c.dist(1), k3 = c.dist(4);
  return 1 + r2 * (3 * k1 + r2 * (5 * k2 + r2 * 7 * k3)) > 0;
}

std::vector<ScreenVertex> project_to_samples(const Camera& camera, const Vertices& V, int s,
                                             double near) {
  // Sample (sx, sy) of pixel (x, y) sits at pixel coordinates x + (sx − (s−1)/2)/s, so a
  // pixel coordinate u maps to the sample coordinate s·u + (s−1)/2.
  const double offset = 0.5 * (s - 1);
  std::vector<ScreenVertex> out(V.rows());
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    const Eigen::Vector3d X = V.row(i).transpose();
    const Eigen::Vector3d c = camera.R * X + camera.t;
    ScreenVertex& o = out[i];
    o.ok = false;
    if (!(c.z() > near)) continue;
    const double a = c.x() / c.z(), b = c.y() / c.z();
    if (!radially_monotonic(camera, a * a + b * b)) continue;
    const Eigen::Vector2d p = camera.project(X);
    const double u = s * p.x() + offset, v = s * p.y() + offset;
    if (!(std::abs(u) < kMaxPixel) || !(std::abs(v) < kMaxPixel)) continue;
    o.x = std::llround(u * kOne);
    o.y = std::llround(v * kOne);
    o.inv_z = 1.0 / c.z();
    o.ok = true;
  }
  return out;
}

// Rounds a fixed-point coordinate up / down to a whole sample (arithmetic shifts floor).
int64_t ceil_sample(int64_t a) { return -((-a) >> kSubpixelBits); }
int64_t floor_sample(int64_t a) { return a >> kSubpixelBits; }

void setup_triangles(const std::vector<ScreenVertex>& sv, const Faces& F, int mesh, int width,
                     int height, std::vector<ScreenTriangle>& out) {
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const ScreenVertex* v[3] = {&sv[F(f, 0)], &sv[F(f, 1)], &sv[F(f, 2)]};
    if (!v[0]->ok || !v[1]->ok || !v[2]->ok) continue;
    ScreenTriangle t;
    int order[3] = {0, 1, 2};
    int64_t area2 =
        (v[1]->x - v[0]->x) * (v[2]->y - v[0]->y) - (v[1]->y - v[0]->y) * (v[2]->x - v[0]->x);
    if (area2 == 0) continue;  // no sample can lie strictly inside
    if (area2 < 0) {
      std::swap(order[1], order[2]);
      area2 = -area2;
    }
    for (int k = 0; k < 3; ++k) {
      t.x[k] = v[order[k]]->x;
      t.y[k] = v[order[k]]->y;
      t.inv_z[k] = v[order[k]]->inv_z;
      t.corner[k] = order[k];
    }
    const int64_t x0 = std::max<int64_t>(0, ceil_sample(std::min({t.x[0], t.x[1], t.x[2]})));
    const int64_t x1 =
        std::min<int64_t>(width - 1, floor_sample(std::max({t.x[0], t.x[1], t.x[2]})));
    const int64_t y0 = std::max<int64_t>(0, ceil_sample(std::min({t.y[0], t.y[1], t.y[2]})));
    const int64_t y1 =
        std::min<int64_t>(height - 1, floor_sample(std::max({t.y[0], t.y[1], t.y[2]})));
    if (x0 > x1 || y0 > y1) continue;  // off screen, or between sample centres
    t.x0 = static_cast<int>(x0);
    t.x1 = static_cast<int>(x1);
    t.y0 = static_cast<int>(y0);
    t.y1 = static_cast<int>(y1);
    t.inv_area = 1.0 / static_cast<double>(area2);
    t.mesh = mesh;
    t.face = static_cast<int>(f);
    out.push_back(t);
  }
}

// Z-buffers the triangles `list` into the band of sample rows [row0, row1) of an image
// `width` samples wide. Coverage: a sample centre strictly inside, or on an edge that
// the top-left rule gives to this triangle. Nearer (larger 1/z) wins; ties keep the
// earlier triangle, and the list is in input order, so the result is deterministic.
void rasterise_band(const std::vector<ScreenTriangle>& tris, const std::vector<int>& list, int row0,
                    int row1, int width, BandBuffers& buf) {
  const size_t n = static_cast<size_t>(row1 - row0) * width;
  buf.inv_z.assign(n, 0.0);
  buf.triangle.assign(n, -1);
  buf.b1.resize(n);
  buf.b2.resize(n);
  for (int id : list) {
    const ScreenTriangle& t = tris[id];
    // Edge k runs from corner k+1 to corner k+2; its function is the doubled area of
    // (corner k+1, corner k+2, p): positive inside, the numerator of corner k's barycentric.
    int64_t dx[3], dy[3], bias[3];
    for (int k = 0; k < 3; ++k) {
      const int i = (k + 1) % 3, j = (k + 2) % 3;
      dx[k] = t.x[j] - t.x[i];
      dy[k] = t.y[j] - t.y[i];
      // Top-left rule: a sample exactly on an edge belongs to the triangle for which the
      // edge direction satisfies this test; the neighbour traverses it reversed and fails.
      const bool owns = dy[k] > 0 || (dy[k] == 0 && dx[k] < 0);
      bias[k] = owns ? 0 : -1;
    }
    const int y_begin = std::max(t.y0, row0), y_end = std::min(t.y1, row1 - 1);
    for (int y = y_begin; y <= y_end; ++y) {
      const int64_t px = int64_t{t.x0} * kOne, py = int64_t{y} * kOne;
      int64_t w[3];
      for (int k = 0; k < 3; ++k) {
        const int i = (k + 1) % 3;
        w[k] = dx[k] * (py - t.y[i]) - dy[k] * (px - t.x[i]);
      }
      const int64_t step0 = -dy[0] * kOne, step1 = -dy[1] * kOne, step2 = -dy[2] * kOne;
      const size_t row = static_cast<size_t>(y - row0) * width;
      for (int x = t.x0; x <= t.x1; ++x, w[0] += step0, w[1] += step1, w[2] += step2) {
        if (((w[0] + bias[0]) | (w[1] + bias[1]) | (w[2] + bias[2])) < 0) continue;
        // Screen-space barycentrics weighted by 1/z give the perspective-correct ones.
        const double q0 = static_cast<double>(w[0]) * t.inv_area * t.inv_z[0];
        const double q1 = static_cast<double>(w[1]) * t.inv_area * t.inv_z[1];
        const double q2 = static_cast<double>(w[2]) * t.inv_area * t.inv_z[2];
        const double inv_z = q0 + q1 + q2;
        const size_t idx = row + x;
        if (inv_z > buf.inv_z[idx]) {
          buf.inv_z[idx] = inv_z;
          buf.triangle[idx] = id;
          buf.b1[idx] = static_cast<float>(q1 / inv_z);
          buf.b2[idx] = static_cast<float>(q2 / inv_z);
        }
      }
    }
  }
}

// Bilinear lookup of a BGR texture at OBJ coordinates (v up), clamped at the border.
Eigen::Vector3d sample_texture(const cv::Mat& tex, double u, double v) {
  const double x = std::clamp(u * tex.cols - 0.5, 0.0, tex.cols - 1.0);
  const double y = std::clamp((1.0 - v) * tex.rows - 0.5, 0.0, tex.rows - 1.0);
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const int x1 = std::min(x0 + 1, tex.cols - 1), y1 = std::min(y0 + 1, tex.rows - 1);
  const double fx = x - x0, fy = y - y0;
  const cv::Vec3b* r0 = tex.ptr<cv::Vec3b>(y0);
  const cv::Vec3b* r1 = tex.ptr<cv::Vec3b>(y1);
  Eigen::Vector3d out;
  for (int c = 0; c < 3; ++c) {
    const double top = r0[x0][c] + fx * (r0[x1][c] - r0[x0][c]);
    const double bottom = r1[x0][c] + fx * (r1[x1][c] - r1[x0][c]);
    out(c) = top + fy * (bottom - top);
  }
  return out;
}

class Shader {
 public:
  Shader(const Camera& camera, const std::vector<ShadingMesh>& meshes,
         const std::vector<ScreenTriangle>& tris, const Lighting& lighting)
      : meshes_(meshes),
        tris_(tris),
        center_(camera.center()),
        ambient_(lighting.ambient),
        exposure_(lighting.exposure) {
    // The headlight travels along the optical axis (camera +z in world coordinates).
    const Eigen::Vector3d axis = camera.R.row(2).transpose();
    if (lighting.headlight > 0) lights_.push_back({-axis.normalized(), lighting.headlight});
    for (const DirectionalLight& d : lighting.lights)
      if (d.intensity > 0) lights_.push_back({-d.direction.normalized(), d.intensity});
  }

  // BGR colour (0..255, clamped) of triangle `id` at perspective-correct barycentrics
  // (1 − b1 − b2, b1, b2) of its ScreenTriangle corners.
  Eigen::Vector3d shade(int id, double b1, double b2) const {
    const ScreenTriangle& t = tris_[id];
    const ShadingMesh& m = meshes_[t.mesh];
    double w[3];
    w[t.corner[0]] = 1.0 - b1 - b2;
    w[t.corner[1]] = b1;
    w[t.corner[2]] = b2;
    const Faces& F = m.in->mesh->F;
    const int i0 = F(t.face, 0), i1 = F(t.face, 1), i2 = F(t.face, 2);
    const Vertices& V = *m.V;
    const Eigen::Vector3d p = w[0] * V.row(i0) + w[1] * V.row(i1) + w[2] * V.row(i2);
    Eigen::Vector3d n =
        w[0] * m.normals.row(i0) + w[1] * m.normals.row(i1) + w[2] * m.normals.row(i2);
    const double len = n.norm();
    n = len > 1e-12 ? Eigen::Vector3d(n / len) : Eigen::Vector3d(m.face_normals.row(t.face));
    if (n.dot(center_ - p) < 0) n = -n;  // the side we see; cloth is two-sided
    double light = ambient_;
    for (const Light& l : lights_) light += l.intensity * std::max(0.0, n.dot(l.toward));
    Eigen::Vector3d albedo;
    switch (m.in->source) {
      case ColorSource::flat:
        albedo = Eigen::Vector3d(m.in->color[0], m.in->color[1], m.in->color[2]);
        break;
      case ColorSource::vertex:
        albedo = w[0] * m.bgr.row(i0) + w[1] * m.bgr.row(i1) + w[2] * m.bgr.row(i2);
        break;
      case ColorSource::texture: {
        const TriangleMesh& mesh = *m.in->mesh;
        const Eigen::Vector2d uv = w[0] * mesh.uv.row(mesh.uv_faces(t.face, 0)) +
                                   w[1] * mesh.uv.row(mesh.uv_faces(t.face, 1)) +
                                   w[2] * mesh.uv.row(mesh.uv_faces(t.face, 2));
        albedo = sample_texture(m.in->texture, uv.x(), uv.y());
        break;
      }
    }
    return (albedo * (light * exposure_)).cwiseMax(0.0).cwiseMin(255.0);
  }

 private:
  const std::vector<ShadingMesh>& meshes_;
  const std::vector<ScreenTriangle>& tris_;
  Eigen::Vector3d center_;
  double ambient_, exposure_;
  std::vector<Light> lights_;
};

}  // namespace

RenderResult render(const Camera& camera, const std::vector<RenderMesh>& meshes,
                    const RenderOptions& options) {
  validate_camera(camera, "render");
  check_options(options);
  for (size_t i = 0; i < meshes.size(); ++i) check_mesh(i, meshes[i]);

  const int s = options.supersample;
  const int W = camera.width, H = camera.height;
  const int Ws = W * s, Hs = H * s;

  std::vector<ShadingMesh> shading(meshes.size());
  std::vector<ScreenTriangle> tris;
  for (size_t m = 0; m < meshes.size(); ++m) {
    const RenderMesh& in = meshes[m];
    ShadingMesh& sm = shading[m];
    sm.in = &in;
    sm.V = in.vertices ? in.vertices : &in.mesh->V;
    sm.normals = vertex_normals(*sm.V, in.mesh->F);
    sm.face_normals = face_normals(*sm.V, in.mesh->F);
    if (in.source == ColorSource::vertex) sm.bgr = 255.0 * in.mesh->colors.rowwise().reverse();
    const std::vector<ScreenVertex> sv = project_to_samples(camera, *sm.V, s, options.near);
    setup_triangles(sv, in.mesh->F, static_cast<int>(m), Ws, Hs, tris);
  }

  // Bin triangles by the bands their sample rows touch, in input order.
  const int band_samples = kBandRows * s;
  const int num_bands = (H + kBandRows - 1) / kBandRows;
  std::vector<std::vector<int>> bins(num_bands);
  for (size_t id = 0; id < tris.size(); ++id)
    for (int b = tris[id].y0 / band_samples; b <= tris[id].y1 / band_samples; ++b)
      bins[b].push_back(static_cast<int>(id));

  RenderResult r;
  r.rgb.create(H, W, CV_8UC3);
  r.mask.create(H, W, CV_8UC1);
  r.parts.create(H, W, CV_8UC1);
  r.depth.create(H, W, CV_32FC1);
  // A solid background needs no image of its own, only its colour.
  const cv::Scalar& colour = options.background.color;
  const cv::Vec3b solid(cv::saturate_cast<uchar>(colour[0]), cv::saturate_cast<uchar>(colour[1]),
                        cv::saturate_cast<uchar>(colour[2]));
  const cv::Mat background = options.background.kind == BackgroundKind::solid
                                 ? cv::Mat()
                                 : background_image(options.background, W, H);
  const Shader shader(camera, shading, tris, options.lighting);
  const int centre = (s - 1) / 2;
  const double inv_samples = 1.0 / (s * s);
  auto to_bgr = [](const Eigen::Vector3d& c) {
    return cv::Vec3b(cv::saturate_cast<uchar>(c(0)), cv::saturate_cast<uchar>(c(1)),
                     cv::saturate_cast<uchar>(c(2)));
  };

  tbb::enumerable_thread_specific<BandBuffers> buffers;
  tbb::parallel_for(
      tbb::blocked_range<int>(0, num_bands), [&](const tbb::blocked_range<int>& range) {
        BandBuffers& buf = buffers.local();
        for (int band = range.begin(); band != range.end(); ++band) {
          const int row0 = band * band_samples, row1 = std::min(row0 + band_samples, Hs);
          rasterise_band(tris, bins[band], row0, row1, Ws, buf);
          for (int y = row0 / s; y < row1 / s; ++y) {
            const cv::Vec3b* bg = background.empty() ? nullptr : background.ptr<cv::Vec3b>(y);
            cv::Vec3b* rgb = r.rgb.ptr<cv::Vec3b>(y);
            uchar* mask = r.mask.ptr<uchar>(y);
            uchar* parts = r.parts.ptr<uchar>(y);
            float* depth = r.depth.ptr<float>(y);
            const size_t centre_row = static_cast<size_t>(y * s + centre - row0) * Ws + centre;
            for (int x = 0; x < W; ++x) {
              // The centre sample is the pixel centre: it alone decides mask, parts and depth.
              const size_t c = centre_row + static_cast<size_t>(x) * s;
              const int id = buf.triangle[c];
              mask[x] = id < 0 ? 0 : 255;
              parts[x] = id < 0 ? 0 : static_cast<uchar>(meshes[tris[id].mesh].part);
              depth[x] = id < 0 ? 0.0f : static_cast<float>(1.0 / buf.inv_z[c]);
              const cv::Vec3b back = bg ? bg[x] : solid;
              if (s == 1) {
                rgb[x] = id < 0 ? back : to_bgr(shader.shade(id, buf.b1[c], buf.b2[c]));
                continue;
              }
              Eigen::Vector3d sum = Eigen::Vector3d::Zero();
              for (int sy = 0; sy < s; ++sy) {
                const size_t row =
                    static_cast<size_t>(y * s + sy - row0) * Ws + static_cast<size_t>(x) * s;
                for (int sx = 0; sx < s; ++sx) {
                  const int sid = buf.triangle[row + sx];
                  sum += sid < 0 ? Eigen::Vector3d(back[0], back[1], back[2])
                                 : shader.shade(sid, buf.b1[row + sx], buf.b2[row + sx]);
                }
              }
              rgb[x] = to_bgr(sum * inv_samples);
            }
          }
        }
      });
  return r;
}

cv::Mat background_image(const Background& b, int width, int height) {
  if (width <= 0 || height <= 0)
    fail("background: image size ", width, "x", height, " must be positive");
  switch (b.kind) {
    case BackgroundKind::solid:
      return cv::Mat(height, width, CV_8UC3, b.color);
    case BackgroundKind::image: {
      if (b.image.empty()) fail("background: kind 'image' but the background image is empty");
      if (b.image.type() != CV_8UC3 && b.image.type() != CV_8UC1)
        fail("background: image must be CV_8UC3 (BGR) or CV_8UC1, got ",
             cv::typeToString(b.image.type()));
      cv::Mat bgr = b.image;
      if (bgr.type() == CV_8UC1) cv::cvtColor(b.image, bgr, cv::COLOR_GRAY2BGR);
      if (bgr.cols == width && bgr.rows == height) return bgr.clone();
      cv::Mat out;
      const bool shrink = bgr.cols > width && bgr.rows > height;
      cv::resize(bgr, out, cv::Size(width, height), 0, 0,
                 shrink ? cv::INTER_AREA : cv::INTER_LINEAR);
      return out;
    }
    case BackgroundKind::clutter:
      return cluttered_background(width, height, b.seed);
  }
  fail("background: unknown kind ", static_cast<int>(b.kind));
}

cv::Mat cluttered_background(int width, int height, uint64_t seed) {
  if (width <= 0 || height <= 0)
    fail("cluttered_background: image size ", width, "x", height, " must be positive");
  // cv::RNG treats state 0 specially; mixing the seed keeps every seed distinct.
  cv::RNG rng(seed * 0x9E3779B97F4A7C15ull + 0x632BE59BD9B4E019ull);
  // Every draw is its own statement: the order of evaluation of function arguments is
  // unspecified, and the image must not depend on the compiler.
  auto uniform = [&](int lo, int hi) { return hi > lo ? rng.uniform(lo, hi) : lo; };
  auto colour = [&] {
    const int b = uniform(0, 256);
    const int g = uniform(0, 256);
    const int r = uniform(0, 256);
    return cv::Scalar(b, g, r);
  };
  auto point = [&] {
    const int x = uniform(-width / 8, width + width / 8);
    const int y = uniform(-height / 8, height + height / 8);
    return cv::Point(x, y);
  };
  cv::Mat img(height, width, CV_8UC3);
  // A vertical gradient between two colours: a wall and a floor.
  const cv::Scalar top = colour();
  const cv::Scalar bottom = colour();
  for (int y = 0; y < height; ++y) {
    const double t = height > 1 ? double(y) / (height - 1) : 0.0;
    img.row(y).setTo(top * (1 - t) + bottom * t);
  }
  // Low-frequency colour noise, so that no region is flat.
  cv::Mat coarse(std::max(2, height / 48), std::max(2, width / 48), CV_8UC3), noise;
  rng.fill(coarse, cv::RNG::UNIFORM, cv::Scalar::all(0), cv::Scalar::all(256));
  cv::resize(coarse, noise, img.size(), 0, 0, cv::INTER_CUBIC);
  cv::addWeighted(img, 0.6, noise, 0.4, 0, img);
  // Clutter: furniture-sized boxes and blobs, poles and cables, and striped or
  // checkered patches for high-frequency texture. Sizes scale with the frame.
  const int size = std::min(width, height);
  const int count = 24 + width * height / 40000;
  for (int k = 0; k < count; ++k) {
    const cv::Scalar c = colour();
    const cv::Point p = point();
    const int extent = std::max(2, uniform(size / 20, size / 3 + 2));
    const int kind = uniform(0, 4);
    if (kind == 0) {
      const int h = uniform(extent / 3, extent + 1);
      const bool outline = uniform(0, 3) == 0;
      const int thickness = outline ? uniform(1, 6) : cv::FILLED;
      cv::rectangle(img, p, p + cv::Point(extent, h), c, thickness, cv::LINE_AA);
    } else if (kind == 1) {
      const int minor = uniform(extent / 6, extent / 2 + 1);
      const int angle = uniform(0, 180);
      cv::ellipse(img, p, cv::Size(extent / 2, minor), angle, 0, 360, c, cv::FILLED, cv::LINE_AA);
    } else if (kind == 2) {
      const cv::Point q = point();
      const int thickness = uniform(1, std::max(2, size / 60));
      cv::line(img, p, q, c, thickness, cv::LINE_AA);
    } else {  // stripes or checks in a box
      const int cell = std::max(2, uniform(size / 80, size / 30 + 3));
      const cv::Scalar c2 = colour();
      const bool checks = uniform(0, 2) == 1;
      const cv::Rect box = cv::Rect(p, cv::Size(extent, extent)) & cv::Rect(0, 0, width, height);
      for (int y = box.y; y < box.y + box.height; y += cell)
        for (int x = box.x; x < box.x + box.width; x += cell) {
          const int i = (x - box.x) / cell, j = (y - box.y) / cell;
          const bool odd = (checks ? i + j : i) % 2 == 1;
          cv::rectangle(img, cv::Rect(x, y, cell, cell) & box, odd ? c : c2, cv::FILLED);
        }
    }
  }
  cv::GaussianBlur(img, img, cv::Size(3, 3), 0.8);
  return img;
}

cv::Mat distance_transform(const cv::Mat& mask) {
  if (mask.empty() || mask.type() != CV_8UC1)
    fail("distance_transform: expected a non-empty CV_8UC1 mask, got ",
         mask.empty() ? std::string("an empty image") : cv::typeToString(mask.type()));
  if (cv::countNonZero(mask) == 0)
    return cv::Mat(mask.size(), CV_32FC1,
                   cv::Scalar(std::hypot(double(mask.cols), double(mask.rows))));
  // cv::distanceTransform measures to the nearest zero pixel: make the person zero.
  const cv::Mat outside = mask == 0;
  cv::Mat dt;
  cv::distanceTransform(outside, dt, cv::DIST_L2, cv::DIST_MASK_PRECISE, CV_32F);
  return dt;
}

double mask_iou(const cv::Mat& a, const cv::Mat& b) {
  if (a.type() != CV_8UC1 || b.type() != CV_8UC1 || a.size() != b.size())
    fail("mask_iou: expected two CV_8UC1 masks of one size, got ", cv::typeToString(a.type()), " ",
         a.cols, "x", a.rows, " and ", cv::typeToString(b.type()), " ", b.cols, "x", b.rows);
  const cv::Mat fa = a != 0, fb = b != 0;
  const int inter = cv::countNonZero(fa & fb), uni = cv::countNonZero(fa | fb);
  return uni == 0 ? 1.0 : double(inter) / uni;
}

}  // namespace weft::capture
