#pragma once
// The synthetic studio's CPU renderer: a z-buffered triangle rasteriser that draws posed
// meshes into one camera and returns shaded RGB, the foreground mask, a part-id image and
// camera depth; plus the distance-transform image the silhouette loss reads.
//
// Conventions
// - Pixels: OpenCV's. Camera::project() maps a point onto pixel coordinates (u, v) and
//   the pixel in column x, row y has its centre at (u, v) = (x, y), so it covers
//   [x − ½, x + ½) × [y − ½, y + ½). A pixel is covered when its centre is inside a
//   projected triangle; samples on a shared edge belong to exactly one of the two
//   triangles (a top-left rule on 1/256-pixel fixed-point coordinates), so meshes have
//   no cracks and no double-drawn pixels. This is the convention of cv::projectPoints
//   and cv::fillPoly.
// - Projection: vertices go through the full camera model (lens distortion included);
//   triangles are straight-edged in pixel space, so under distortion a triangle's edges
//   are chords of the true curved image (fine for meshes tessellated far below the scale
//   of the distortion). Depth and attributes are interpolated perspective-correctly:
//   1/z and attribute/z are linear in the image. A triangle is skipped when any vertex
//   is at depth ≤ RenderOptions::near, lies where the lens model folds back on itself
//   (d r_distorted / d r ≤ 0), or projects more than 2²¹ pixels from the origin.
// - Both faces of every triangle are drawn (cloth is two-sided); the interpolated vertex
//   normal is flipped toward the camera before shading.
// - Colours: images are 8-bit BGR (OpenCV); TriangleMesh::colors are RGB in [0, 1];
//   textures are BGR images indexed by OBJ texture coordinates (v = 0 is the bottom row),
//   sampled bilinearly with texel centres at (i + ½)/size, clamped at the border.
// - Depth: camera z (the world's units, e.g. mm for ddc) at the pixel centre; 0 where
//   no surface is drawn.
// Rows of the image are split into bands rasterised in parallel on TBB threads; each
// band owns its rows, so the result does not depend on the thread count.
#include <opencv2/core.hpp>

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "capture/io/camera.h"
#include "geometry/mesh.h"

namespace weft::capture {

// Where a mesh's surface colour comes from.
enum class ColorSource {
  flat,     // RenderMesh::color everywhere
  vertex,   // TriangleMesh::colors, interpolated
  texture,  // RenderMesh::texture at the interpolated TriangleMesh::uv
};

// One mesh to draw: the topology and optional uv/colours of `mesh`, placed at `vertices`.
struct RenderMesh {
  const TriangleMesh* mesh = nullptr;
  const Vertices* vertices = nullptr;  // posed positions, N×3 (world units); null: mesh->V
  int part = 1;                        // written to RenderResult::parts, 1..255 (1 body, 2 cloth)
  ColorSource source = ColorSource::flat;
  cv::Scalar color = cv::Scalar(180, 205, 225);  // BGR, 0..255 (ColorSource::flat)
  cv::Mat texture;                               // CV_8UC3 BGR (ColorSource::texture)
};

// A light infinitely far away: every surface point receives it from the same direction.
struct DirectionalLight {
  Eigen::Vector3d direction = Eigen::Vector3d(0, 0, 1);  // world; the way the light travels
  double intensity = 0.5;
};

// Lambert shading: colour = albedo · exposure · (ambient + Σ intensity · max(0, n·(−dir))),
// clamped to 255. The headlight travels along the camera's optical axis, so each view
// of a studio rig sees its subject front-lit; `lights` are fixed in the world.
struct Lighting {
  double ambient = 0.35;
  double headlight = 0.65;  // 0 switches it off
  std::vector<DirectionalLight> lights;
  double exposure = 1.0;  // global brightness factor ("in the wild" lighting changes)
};

enum class BackgroundKind {
  solid,    // Background::color
  image,    // Background::image, resized to the frame
  clutter,  // cluttered_background(width, height, seed)
};

struct Background {
  BackgroundKind kind = BackgroundKind::solid;
  cv::Scalar color = cv::Scalar(64, 177, 0);  // BGR; chroma-key green, RGB (0, 177, 64)
  cv::Mat image;                              // CV_8UC3 or CV_8UC1 (BackgroundKind::image)
  uint64_t seed = 0;                          // BackgroundKind::clutter
};

struct RenderOptions {
  Lighting lighting;
  Background background;
  // Antialiasing of `rgb` only: s×s samples per pixel (s odd, 1..7) averaged with a box
  // filter. The mask, parts and depth come from the centre sample, which is exactly the
  // pixel centre, so they stay binary and match an s = 1 render up to fixed-point rounding.
  int supersample = 1;
  double near = 1e-3;  // world units: vertices closer to the camera plane skip their triangle
};

struct RenderResult {
  cv::Mat rgb;    // CV_8UC3 BGR
  cv::Mat mask;   // CV_8UC1: 255 foreground, 0 background
  cv::Mat parts;  // CV_8UC1: RenderMesh::part of the visible surface, 0 background
  cv::Mat depth;  // CV_32FC1: camera z of the visible surface (world units), 0 background
};

// Draws `meshes` into `camera` (its image size). Throws weft::Error naming the mesh and
// what is wrong for an invalid camera, mismatched sizes, out-of-range indices, non-finite
// vertices or uv, a missing colour source, or invalid options.
RenderResult render(const Camera& camera, const std::vector<RenderMesh>& meshes,
                    const RenderOptions& options = {});

// The background of a frame, CV_8UC3 width×height: solid, the resized image, or clutter.
cv::Mat background_image(const Background& background, int width, int height);

// A cluttered, textured scene for "in the wild" frames: a colour gradient under random
// rectangles, ellipses, lines and low-frequency noise. The same seed gives the same image
// (OpenCV's own RNG and drawing, no platform-dependent distributions).
cv::Mat cluttered_background(int width, int height, uint64_t seed);

// Per pixel, the Euclidean distance (pixels) to the nearest foreground pixel of `mask`
// (CV_8UC1, nonzero = foreground): 0 on the foreground, growing away from the person, as
// capture/deformation/losses.h's silhouette loss expects; CV_32FC1, exact (cv::distanceTransform,
// DIST_L2, DIST_MASK_PRECISE). A mask without foreground gives the image diagonal
// everywhere, an upper bound of any distance within the frame.
cv::Mat distance_transform(const cv::Mat& mask);

// Intersection over union of two masks of one size (nonzero = foreground); 1 when both
// are empty.
double mask_iou(const cv::Mat& a, const cv::Mat& b);

}  // namespace weft::capture
