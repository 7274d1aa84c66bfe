// The synthetic studio's renderer against things computed without it: silhouettes filled
// with OpenCV from cv::projectPoints, analytic depths and texture lookups of planes,
// distances to a disk.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <Eigen/Geometry>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

#include "capture/render/renderer.h"
#include "tests/capture/box_mesh.h"
#include "tests/capture/opencv_silhouette.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::expect_error;
using weft::capture::testing::centre_sampled_silhouette;
using weft::capture::testing::opencv_silhouette;

namespace {

TriangleMesh sphere(double radius, const Eigen::Vector3d& c, int rings, int segments) {
  return uv_sphere(c, radius, rings, segments);
}

// An axis-aligned box with half extents h around c.
TriangleMesh box(const Eigen::Vector3d& c, const Eigen::Vector3d& h) {
  return weft::capture::testing::box_mesh(c - h, c + h);
}

// A quad p0 p1 p2 p3 (in order around it) with uv (0,1) (1,1) (1,0) (0,0): p0 is the
// texture's top-left corner.
TriangleMesh quad(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
                  const Eigen::Vector3d& p3) {
  TriangleMesh m;
  m.V.resize(4, 3);
  m.V << p0.transpose(), p1.transpose(), p2.transpose(), p3.transpose();
  m.F.resize(2, 3);
  m.F << 0, 1, 2, 0, 2, 3;
  m.uv.resize(4, 2);
  m.uv << 0, 1, 1, 1, 1, 0, 0, 0;
  m.uv_faces = m.F;
  return m;
}

// A studio-like camera with real lens distortion, looking at the origin from 3 m (mm).
Camera distorted_camera() {
  Camera c;
  c.name = "distorted";
  c.K << 820, 0, 331.7, 0, 815, 236.2, 0, 0, 1;
  c.dist << -0.18, 0.06, 0.0012, -0.0018, 0.004;
  c.R = Eigen::AngleAxisd(0.35, Eigen::Vector3d(0.1, 1, 0.2).normalized()).toRotationMatrix();
  c.t << 40, -25, 3000;
  c.width = 640;
  c.height = 480;
  return c;
}

// A pinhole camera at the origin looking down +z (image x right, y down).
Camera pinhole_camera(double f, int width, int height) {
  Camera c;
  c.name = "pinhole";
  c.K << f, 0, width / 2.0, 0, f, height / 2.0, 0, 0, 1;
  c.width = width;
  c.height = height;
  return c;
}

// Lighting that leaves the albedo unchanged.
RenderOptions unlit() {
  RenderOptions o;
  o.lighting.ambient = 1.0;
  o.lighting.headlight = 0.0;
  return o;
}

RenderMesh flat(const TriangleMesh& m, int part, cv::Scalar color) {
  RenderMesh r;
  r.mesh = &m;
  r.part = part;
  r.color = color;
  return r;
}

double max_abs_diff(const cv::Mat& a, const cv::Mat& b) { return cv::norm(a, b, cv::NORM_INF); }

// ---------------------------------------------------------------- silhouettes

TEST(Renderer, MaskMatchesAnIndependentlyFilledSilhouette) {
  const Camera cam = distorted_camera();
  // A sphere partly in front of a box, with lens distortion of several pixels.
  const TriangleMesh ball = sphere(420, Eigen::Vector3d(-150, 60, -100), 96, 192);
  const TriangleMesh crate = box(Eigen::Vector3d(420, -200, 300), Eigen::Vector3d(380, 500, 250));
  for (int ss : {1, 3}) {
    RenderOptions o;
    o.supersample = ss;
    const RenderResult r =
        render(cam, {flat(ball, 1, {90, 120, 200}), flat(crate, 2, {200, 90, 40})}, o);
    const cv::Mat expected = opencv_silhouette(cam, {&ball, &crate});
    const int area = cv::countNonZero(expected);
    ASSERT_GT(area, 0.1 * cam.width * cam.height);
    ASSERT_LT(area, 0.9 * cam.width * cam.height);
    EXPECT_GE(mask_iou(r.mask, expected), 0.99) << "supersample " << ss;
    // fillConvexPoly also fills pixels an edge merely touches, so its silhouette holds the
    // renderer's, about half a pixel wider; comparing centre-sampled coverage instead, the
    // two may differ only where a pixel centre is within rounding of an edge. A half-pixel
    // shift of the image would change about one pixel per outline pixel.
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(expected.clone(), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
    size_t outline = 0;
    for (const auto& c : contours) outline += c.size();
    ASSERT_GT(outline, 1000u);
    EXPECT_LT(cv::countNonZero(r.mask & ~expected), static_cast<int>(outline / 100))
        << "supersample " << ss;
    cv::Mat differ;
    cv::bitwise_xor(r.mask, centre_sampled_silhouette(cam, {&ball, &crate}), differ);
    EXPECT_LT(cv::countNonZero(differ), static_cast<int>(outline / 100)) << "supersample " << ss;
    // Masks stay binary, and mask, parts and depth agree.
    EXPECT_EQ(cv::countNonZero((r.mask != 0) & (r.mask != 255)), 0);
    EXPECT_EQ(cv::countNonZero((r.mask != 0) != (r.parts != 0)), 0);
    EXPECT_EQ(cv::countNonZero((r.mask != 0) != (r.depth > 0)), 0);
    EXPECT_GT(cv::countNonZero(r.parts == 1), 0);
    EXPECT_GT(cv::countNonZero(r.parts == 2), 0);
  }
}

TEST(Renderer, PixelCentresAreAtIntegerCoordinates) {
  // f = 100 at z = 1: a world x of 0.103 lands on u = 10.3 + cx with cx = 0 here.
  Camera cam = pinhole_camera(100, 40, 20);
  cam.K(0, 2) = 0;
  cam.K(1, 2) = 0;
  // u ∈ [10.3, 20.3], v ∈ [5.6, 9.2]: pixel centres (x, y) inside are x 11..20, y 6..9.
  const TriangleMesh q =
      quad({0.103, 0.056, 1}, {0.203, 0.056, 1}, {0.203, 0.092, 1}, {0.103, 0.092, 1});
  const RenderResult r = render(cam, {flat(q, 1, {255, 255, 255})});
  cv::Mat expected = cv::Mat::zeros(20, 40, CV_8UC1);
  expected(cv::Range(6, 10), cv::Range(11, 21)).setTo(255);
  EXPECT_EQ(cv::countNonZero(r.mask != expected), 0) << r.mask;
}

TEST(Renderer, MeshesHaveNoCracksOrOverlaps) {
  // A fan of 37 thin triangles around a centre that sits exactly on a pixel centre, with
  // an edge running exactly along pixel row 32: rendered one triangle at a time, every
  // pixel centre inside the fan is covered exactly once, shared edges and vertex included.
  Camera cam = pinhole_camera(100, 64, 64);
  TriangleMesh fan;
  const int n = 37;
  fan.V.resize(n + 1, 3);
  fan.V.row(0) << 0, 0, 1;
  for (int k = 0; k < n; ++k)
    fan.V.row(k + 1) << 0.25 * std::cos(2 * M_PI * k / n), 0.25 * std::sin(2 * M_PI * k / n), 1;
  fan.F.resize(n, 3);
  for (int k = 0; k < n; ++k) fan.F.row(k) << 0, k + 1, (k + 1) % n + 1;
  cv::Mat count = cv::Mat::zeros(64, 64, CV_8UC1), owner = cv::Mat::zeros(64, 64, CV_8UC1);
  for (int k = 0; k < n; ++k) {
    TriangleMesh single;
    single.V = fan.V;
    single.F = fan.F.row(k);
    const cv::Mat mask = render(cam, {flat(single, 1, {255, 255, 255})}).mask;
    cv::add(count, mask / 255, count);
    owner.setTo(cv::Scalar(k + 1), mask);
  }
  const RenderResult whole = render(cam, {flat(fan, 1, {255, 255, 255})});
  EXPECT_EQ(cv::countNonZero(whole.mask != (count > 0)), 0);
  EXPECT_EQ(cv::countNonZero(count > 1), 0) << count;
  // No cracks: everything well inside the rim (radius 25 px) is covered.
  cv::Mat inner = cv::Mat::zeros(64, 64, CV_8UC1);
  cv::circle(inner, cv::Point(32, 32), 22, cv::Scalar(255), cv::FILLED);
  EXPECT_EQ(cv::countNonZero(inner & (count == 0)), 0) << count;
  EXPECT_EQ(count.at<uchar>(32, 32), 1);  // the shared vertex
  // Each pixel away from the edges belongs to the triangle whose sector holds it.
  int checked = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const double a = std::atan2(y - 32.0, x - 32.0), r = std::hypot(x - 32.0, y - 32.0);
      if (r < 2 || r > 22) continue;
      const double sector = std::fmod(a / (2 * M_PI) * n + n, n);
      if (std::abs(sector - std::round(sector)) < 0.05) continue;  // on a shared edge
      ASSERT_EQ(owner.at<uchar>(y, x), static_cast<int>(sector) + 1) << x << "," << y;
      ++checked;
    }
  EXPECT_GT(checked, 1000);
}

// ---------------------------------------------------------------- z-buffer and depth

TEST(Renderer, NearerSurfaceWinsRegardlessOfDrawOrder) {
  const Camera cam = pinhole_camera(500, 320, 240);
  // Near quad at z = 4: u ∈ [60, 185]; far quad at z = 6: u ∈ [60, 260]; both v ∈ [~70, ~170].
  const TriangleMesh near = quad({-0.8, -0.4, 4}, {0.2, -0.4, 4}, {0.2, 0.4, 4}, {-0.8, 0.4, 4});
  const TriangleMesh far = quad({-1.2, -0.6, 6}, {1.2, -0.6, 6}, {1.2, 0.6, 6}, {-1.2, 0.6, 6});
  const cv::Scalar red(0, 0, 255), blue(255, 0, 0);
  const RenderResult a = render(cam, {flat(near, 1, red), flat(far, 2, blue)}, unlit());
  const RenderResult b = render(cam, {flat(far, 2, blue), flat(near, 1, red)}, unlit());
  for (const RenderResult* r : {&a, &b}) {
    EXPECT_EQ(r->parts.at<uchar>(120, 120), 1);
    EXPECT_EQ(r->rgb.at<cv::Vec3b>(120, 120), cv::Vec3b(0, 0, 255));
    EXPECT_FLOAT_EQ(r->depth.at<float>(120, 120), 4.0f);
    EXPECT_EQ(r->parts.at<uchar>(120, 220), 2);
    EXPECT_EQ(r->rgb.at<cv::Vec3b>(120, 220), cv::Vec3b(255, 0, 0));
    EXPECT_FLOAT_EQ(r->depth.at<float>(120, 220), 6.0f);
    EXPECT_EQ(r->parts.at<uchar>(20, 20), 0);
    EXPECT_EQ(r->depth.at<float>(20, 20), 0.0f);
    EXPECT_EQ(r->rgb.at<cv::Vec3b>(20, 20), cv::Vec3b(64, 177, 0));  // green screen
  }
  EXPECT_EQ(max_abs_diff(a.rgb, b.rgb), 0);
  EXPECT_EQ(max_abs_diff(a.parts, b.parts), 0);
}

TEST(Renderer, DepthOfATiltedPlaneIsPerspectiveCorrect) {
  // The plane z = 6 + 3x (x ∈ [−1, 1]) as two triangles: depth runs from 3 to 9 across it,
  // so interpolating z (not 1/z) in the image would be off by up to ~40 %.
  const Camera cam = pinhole_camera(250, 320, 240);
  const TriangleMesh plane = quad({-1, -1, 3}, {1, -1, 9}, {1, 1, 9}, {-1, 1, 3});
  const RenderResult r = render(cam, {flat(plane, 1, {255, 255, 255})});
  int checked = 0;
  for (int y = 5; y < 240; y += 7)
    for (int x = 3; x < 320; x += 5) {
      // Ray through the pixel centre: X = z·d with d = ((x − cx)/f, (y − cy)/f, 1).
      const double dx = (x - cam.K(0, 2)) / 250.0, dy = (y - cam.K(1, 2)) / 250.0;
      const double z = 6 / (1 - 3 * dx);
      const bool inside = z > 0 && std::abs(z * dx) < 1 - 1e-3 && std::abs(z * dy) < 1 - 1e-3;
      const bool outside = z <= 0 || std::abs(z * dx) > 1 + 1e-3 || std::abs(z * dy) > 1 + 1e-3;
      if (inside) {
        ASSERT_EQ(r.mask.at<uchar>(y, x), 255) << x << "," << y;
        // Vertices snap to 1/256 pixel: a few 1e-5 of relative error.
        ASSERT_NEAR(r.depth.at<float>(y, x), z, 1e-4 * z) << x << "," << y;
        ++checked;
      } else if (outside) {
        ASSERT_EQ(r.mask.at<uchar>(y, x), 0) << x << "," << y;
      }
    }
  EXPECT_GT(checked, 300);
}

// ---------------------------------------------------------------- distance transform

TEST(Renderer, DistanceTransformGrowsAwayFromTheMask) {
  cv::Mat disk = cv::Mat::zeros(160, 200, CV_8UC1);
  const cv::Point centre(100, 80);
  const int radius = 40;
  cv::circle(disk, centre, radius, cv::Scalar(255), cv::FILLED);
  const cv::Mat dt = distance_transform(disk);
  ASSERT_EQ(dt.type(), CV_32FC1);
  ASSERT_EQ(dt.size(), disk.size());
  EXPECT_EQ(cv::countNonZero((disk != 0) & (dt != 0)), 0);
  EXPECT_EQ(cv::countNonZero((disk == 0) & (dt < 1)), 0);  // a background pixel is ≥ 1 px away
  for (int y = 0; y < 160; y += 9)
    for (int x = 0; x < 200; x += 7) {
      const double r = std::hypot(x - centre.x, y - centre.y);
      if (r <= radius + 1) continue;
      EXPECT_NEAR(dt.at<float>(y, x), r - radius, 1.0) << x << "," << y;
    }
  // Without foreground: the image diagonal everywhere.
  const cv::Mat none = distance_transform(cv::Mat::zeros(30, 40, CV_8UC1));
  double lo, hi;
  cv::minMaxLoc(none, &lo, &hi);
  EXPECT_FLOAT_EQ(lo, 50.0f);
  EXPECT_FLOAT_EQ(hi, 50.0f);
  expect_error([] { distance_transform(cv::Mat::zeros(4, 4, CV_32FC1)); },
               {"distance_transform", "CV_8UC1"});
}

// ---------------------------------------------------------------- colour

TEST(Renderer, TexturedQuadShowsTheTexture) {
  // Quadrants red, green / blue, white (top / bottom rows of the image) with a yellow
  // block in the middle.
  cv::Mat tex(64, 64, CV_8UC3);
  tex(cv::Rect(0, 0, 32, 32)).setTo(cv::Scalar(0, 0, 255));
  tex(cv::Rect(32, 0, 32, 32)).setTo(cv::Scalar(0, 255, 0));
  tex(cv::Rect(0, 32, 32, 32)).setTo(cv::Scalar(255, 0, 0));
  tex(cv::Rect(32, 32, 32, 32)).setTo(cv::Scalar(255, 255, 255));
  tex(cv::Rect(24, 24, 16, 16)).setTo(cv::Scalar(0, 255, 255));
  // Facing the camera at z = 5 with f = 500: u, v ∈ [60, 260] × [20, 220]; image y down,
  // so p0 = (−1, −1) is the top-left corner.
  const Camera cam = pinhole_camera(500, 320, 240);
  const TriangleMesh q = quad({-1, -1, 5}, {1, -1, 5}, {1, 1, 5}, {-1, 1, 5});
  RenderMesh m = flat(q, 1, {});
  m.source = ColorSource::texture;
  m.texture = tex;
  const RenderResult r = render(cam, {m}, unlit());
  EXPECT_EQ(r.rgb.at<cv::Vec3b>(120, 160), cv::Vec3b(0, 255, 255));  // the centre
  EXPECT_EQ(r.rgb.at<cv::Vec3b>(50, 90), cv::Vec3b(0, 0, 255));      // top-left
  EXPECT_EQ(r.rgb.at<cv::Vec3b>(50, 230), cv::Vec3b(0, 255, 0));     // top-right
  EXPECT_EQ(r.rgb.at<cv::Vec3b>(190, 90), cv::Vec3b(255, 0, 0));     // bottom-left
  EXPECT_EQ(r.rgb.at<cv::Vec3b>(190, 230), cv::Vec3b(255, 255, 255));
}

TEST(Renderer, TextureOnATiltedQuadIsPerspectiveCorrect) {
  // 16 columns of distinct colours on the plane z = 6 + 3x: the world point at the centre
  // of column k must show column k's colour; interpolating uv linearly in the image
  // would shift the middle columns by several columns.
  cv::Mat tex(8, 128, CV_8UC3);
  auto column_colour = [](int k) { return cv::Vec3b(k * 16, 255 - k * 16, (k * 37 + 50) % 256); };
  for (int k = 0; k < 16; ++k) tex(cv::Rect(8 * k, 0, 8, 8)).setTo(cv::Scalar(column_colour(k)));
  const Camera cam = pinhole_camera(250, 320, 240);
  const TriangleMesh q = quad({-1, -1, 3}, {1, -1, 9}, {1, 1, 9}, {-1, 1, 3});
  RenderMesh m = flat(q, 1, {});
  m.source = ColorSource::texture;
  m.texture = tex;
  const RenderResult r = render(cam, {m}, unlit());
  for (int k = 0; k < 16; ++k) {
    const double x = -1 + 2 * (k + 0.5) / 16;
    const Eigen::Vector2d p = cam.project({x, 0.3, 6 + 3 * x});
    const int px = static_cast<int>(std::lround(p.x())), py = static_cast<int>(std::lround(p.y()));
    EXPECT_EQ(r.rgb.at<cv::Vec3b>(py, px), column_colour(k)) << "column " << k;
  }
}

// Colours after shading are rounded once; allow that rounding.
void expect_colour(const cv::Vec3b& got, const cv::Vec3b& want) {
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], 1) << "got " << got << ", want " << want;
}

TEST(Renderer, VertexColoursLightingAndBackFaces) {
  const Camera cam = pinhole_camera(500, 320, 240);
  TriangleMesh q = quad({-1, -1, 5}, {1, -1, 5}, {1, 1, 5}, {-1, 1, 5});
  q.colors = Eigen::RowVector3d(0.2, 0.4, 0.8).replicate(4, 1);  // RGB
  RenderMesh m = flat(q, 1, {});
  m.source = ColorSource::vertex;
  // Unlit: the vertex colour in BGR.
  expect_colour(render(cam, {m}, unlit()).rgb.at<cv::Vec3b>(120, 160), {204, 102, 51});
  // Headlight only, facing the camera: full colour; exposure scales it.
  RenderOptions o;
  o.lighting.ambient = 0;
  o.lighting.headlight = 1;
  expect_colour(render(cam, {m}, o).rgb.at<cv::Vec3b>(120, 160), {204, 102, 51});
  o.lighting.exposure = 0.5;
  expect_colour(render(cam, {m}, o).rgb.at<cv::Vec3b>(120, 160), {102, 51, 26});
  o.lighting.exposure = 2;  // clamped
  expect_colour(render(cam, {m}, o).rgb.at<cv::Vec3b>(120, 160), {255, 204, 102});
  // The same quad seen from behind (reversed winding) is drawn and lit the same:
  // two-sided, with the normal flipped toward the camera.
  TriangleMesh back = q;
  back.F << 0, 2, 1, 0, 3, 2;
  o.lighting.exposure = 1;
  expect_colour(render(cam, {flat(back, 1, {100, 150, 200})}, o).rgb.at<cv::Vec3b>(120, 160),
                {100, 150, 200});
  // A world light at 60° from the normal gives half its intensity: Lambert.
  o.lighting.headlight = 0;
  o.lighting.lights = {{Eigen::Vector3d(std::sin(M_PI / 3), 0, std::cos(M_PI / 3)), 1.0}};
  expect_colour(render(cam, {flat(q, 1, {100, 150, 200})}, o).rgb.at<cv::Vec3b>(120, 160),
                {50, 75, 100});
  // A light from behind the surface adds nothing.
  o.lighting.ambient = 0.2;
  o.lighting.lights = {{Eigen::Vector3d(0, 0, -1), 1.0}};
  expect_colour(render(cam, {flat(q, 1, {100, 150, 200})}, o).rgb.at<cv::Vec3b>(120, 160),
                {20, 30, 40});
}

TEST(Renderer, SupersamplingSmoothsEdgesButKeepsMasksBinary) {
  const Camera cam = distorted_camera();
  const TriangleMesh ball = sphere(600, Eigen::Vector3d(0, 0, 0), 48, 96);
  RenderOptions o;
  o.background.color = cv::Scalar(0, 0, 0);
  const RenderResult one = render(cam, {flat(ball, 1, {255, 255, 255})}, o);
  o.supersample = 3;
  const RenderResult three = render(cam, {flat(ball, 1, {255, 255, 255})}, o);
  EXPECT_GE(mask_iou(one.mask, three.mask), 0.999);
  EXPECT_EQ(cv::countNonZero((three.mask != 0) & (three.mask != 255)), 0);
  // Along the outline, antialiased pixels are between the background and the surface.
  cv::Mat grey_one, grey_three;
  cv::cvtColor(one.rgb, grey_one, cv::COLOR_BGR2GRAY);
  cv::cvtColor(three.rgb, grey_three, cv::COLOR_BGR2GRAY);
  const int partial_one = cv::countNonZero((grey_one > 0) & (one.mask == 0));
  const int partial_three = cv::countNonZero((grey_three > 0) & (three.mask == 0));
  EXPECT_EQ(partial_one, 0);
  EXPECT_GT(partial_three, 200);
}

// ---------------------------------------------------------------- backgrounds

TEST(Renderer, Backgrounds) {
  const Camera cam = pinhole_camera(100, 96, 64);
  RenderOptions o;
  o.background.color = cv::Scalar(1, 2, 3);
  EXPECT_EQ(render(cam, {}, o).rgb.at<cv::Vec3b>(10, 10), cv::Vec3b(1, 2, 3));
  // An image is resized to the frame.
  cv::Mat image(32, 48, CV_8UC3, cv::Scalar(10, 20, 30));
  image(cv::Rect(24, 0, 24, 32)).setTo(cv::Scalar(200, 100, 50));
  o.background.kind = BackgroundKind::image;
  o.background.image = image;
  const RenderResult r = render(cam, {}, o);
  EXPECT_EQ(r.rgb.at<cv::Vec3b>(30, 10), cv::Vec3b(10, 20, 30));
  EXPECT_EQ(r.rgb.at<cv::Vec3b>(30, 80), cv::Vec3b(200, 100, 50));
  EXPECT_EQ(cv::countNonZero(r.mask), 0);
  // Clutter: textured (not flat), the same for a seed, different across seeds.
  const cv::Mat a = cluttered_background(320, 240, 7), b = cluttered_background(320, 240, 7);
  const cv::Mat c = cluttered_background(320, 240, 8);
  EXPECT_EQ(max_abs_diff(a, b), 0);
  EXPECT_GT(cv::norm(a, c, cv::NORM_L1) / a.total(), 20.0);
  cv::Scalar mean, stddev;
  cv::meanStdDev(a, mean, stddev);
  for (int k = 0; k < 3; ++k) EXPECT_GT(stddev[k], 15.0);
  o.background.kind = BackgroundKind::clutter;
  o.background.seed = 7;
  EXPECT_EQ(max_abs_diff(render(pinhole_camera(100, 320, 240), {}, o).rgb, a), 0);
}

// ---------------------------------------------------------------- determinism

TEST(Renderer, DeterministicAndIndependentOfTheThreadCount) {
  const Camera cam = distorted_camera();
  const TriangleMesh ball = sphere(420, Eigen::Vector3d(-150, 60, -100), 64, 128);
  const TriangleMesh crate = box(Eigen::Vector3d(420, -200, 300), Eigen::Vector3d(380, 500, 250));
  cv::Mat tex(64, 64, CV_8UC3);
  cv::randu(tex, cv::Scalar::all(0), cv::Scalar::all(256));
  RenderMesh textured = flat(ball, 1, {});
  textured.source = ColorSource::texture;
  textured.texture = tex;
  RenderOptions o;
  o.supersample = 3;
  o.background.kind = BackgroundKind::clutter;
  o.background.seed = 3;
  o.lighting.lights = {{Eigen::Vector3d(1, 1, 1), 0.4}};
  const std::vector<RenderMesh> scene{textured, flat(crate, 2, {30, 60, 90})};
  const RenderResult a = render(cam, scene, o), b = render(cam, scene, o);
  const RenderResult single = [&] {
    tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    return render(cam, scene, o);
  }();
  for (const RenderResult* r : {&b, &single}) {
    EXPECT_EQ(max_abs_diff(a.rgb, r->rgb), 0);
    EXPECT_EQ(max_abs_diff(a.mask, r->mask), 0);
    EXPECT_EQ(max_abs_diff(a.parts, r->parts), 0);
    EXPECT_EQ(max_abs_diff(a.depth, r->depth), 0);
  }
  EXPECT_GT(cv::countNonZero(a.mask), 10000);
}

// ---------------------------------------------------------------- bad input

TEST(Renderer, BadInputThrowsWithAClearMessage) {
  const Camera cam = pinhole_camera(500, 320, 240);
  const TriangleMesh q = quad({-1, -1, 5}, {1, -1, 5}, {1, 1, 5}, {-1, 1, 5});
  const RenderMesh ok = flat(q, 1, {255, 255, 255});
  EXPECT_NO_THROW(render(cam, {ok}));

  Camera bad = cam;
  bad.K(0, 0) = 0;
  expect_error([&] { render(bad, {ok}); }, {"render", "focal"});
  bad = cam;
  bad.width = 0;
  expect_error([&] { render(bad, {ok}); }, {"render", "image size"});

  RenderMesh m = ok;
  m.mesh = nullptr;
  expect_error([&] { render(cam, {ok, m}); }, {"mesh 1", "null"});

  Vertices short_v = q.V.topRows(3);
  m = ok;
  m.vertices = &short_v;
  expect_error([&] { render(cam, {m}); }, {"mesh 0", "3 posed vertices", "4 vertices"});

  Vertices nan_v = q.V;
  nan_v(2, 1) = std::nan("");
  m.vertices = &nan_v;
  expect_error([&] { render(cam, {m}); }, {"mesh 0", "vertex 2", "not finite"});

  TriangleMesh bad_faces = q;
  bad_faces.F(1, 2) = 7;
  expect_error([&] { render(cam, {flat(bad_faces, 1, {})}); }, {"face 1", "vertex 7", "0..3"});

  expect_error([&] { render(cam, {flat(q, 0, {})}); }, {"part", "1..255"});
  expect_error([&] { render(cam, {flat(q, 256, {})}); }, {"part", "1..255"});

  m = ok;
  m.source = ColorSource::vertex;
  expect_error([&] { render(cam, {m}); }, {"per-vertex colours", "0 colours for 4 vertices"});

  m.source = ColorSource::texture;
  expect_error([&] { render(cam, {m}); }, {"texture", "empty"});
  m.texture = cv::Mat(4, 4, CV_32FC3, cv::Scalar::all(0));
  expect_error([&] { render(cam, {m}); }, {"texture", "CV_8UC3", "CV_32FC3"});
  TriangleMesh no_uv = q;
  no_uv.uv.resize(0, 2);
  no_uv.uv_faces.resize(0, 3);
  m.mesh = &no_uv;
  m.texture = cv::Mat(4, 4, CV_8UC3, cv::Scalar::all(0));
  expect_error([&] { render(cam, {m}); }, {"no texture coordinates"});
  TriangleMesh bad_uv = q;
  bad_uv.uv_faces(0, 1) = 9;
  m.mesh = &bad_uv;
  expect_error([&] { render(cam, {m}); }, {"uv face 0", "texture coordinate 9"});

  RenderOptions o;
  o.supersample = 2;
  expect_error([&] { render(cam, {ok}, o); }, {"supersample", "odd"});
  o = {};
  o.lighting.exposure = -1;
  expect_error([&] { render(cam, {ok}, o); }, {"exposure"});
  o = {};
  o.lighting.lights = {{Eigen::Vector3d::Zero(), 1.0}};
  expect_error([&] { render(cam, {ok}, o); }, {"light 0", "direction"});
  o = {};
  o.near = 0;
  expect_error([&] { render(cam, {ok}, o); }, {"near"});
  o = {};
  o.background.kind = BackgroundKind::image;
  expect_error([&] { render(cam, {ok}, o); }, {"background", "empty"});
  o.background.image = cv::Mat(4, 4, CV_16UC3, cv::Scalar::all(0));
  expect_error([&] { render(cam, {ok}, o); }, {"background", "CV_16UC3"});
  expect_error([] { mask_iou(cv::Mat::zeros(4, 4, CV_8UC1), cv::Mat::zeros(4, 5, CV_8UC1)); },
               {"mask_iou"});
}

TEST(Renderer, SkipsTrianglesBehindTheCamera) {
  // A triangle crossing the camera plane is skipped (not drawn inverted); one fully in
  // front next to it is drawn.
  const Camera cam = pinhole_camera(100, 64, 64);
  TriangleMesh m;
  m.V.resize(6, 3);
  m.V << -1, -1, 2, 1, -1, 2, 0, 1, -1,  // crosses z = 0
      -0.2, -0.2, 3, 0.2, -0.2, 3, 0, 0.2, 3;
  m.F.resize(2, 3);
  m.F << 0, 1, 2, 3, 4, 5;
  const RenderResult r = render(cam, {flat(m, 1, {255, 255, 255})});
  TriangleMesh front = m;
  front.F = m.F.bottomRows(1);
  EXPECT_EQ(cv::countNonZero(r.mask != render(cam, {flat(front, 1, {255, 255, 255})}).mask), 0);
  EXPECT_GT(cv::countNonZero(r.mask), 50);
}

}  // namespace
