#include "capture/training/multiview_losses.h"

#include <tbb/parallel_for.h>

#include "capture/deformation/losses.h"
#include "capture/model/capture_networks.h"
#include "capture/render/silhouette_iou.h"
#include "capture/render/renderer.h"
#include "graph/error.h"
#include "ops/geometry.h"
#include "ops/ops.h"

namespace weft::capture {

namespace {

// Every vertex at least a millimetre-ish in front of the camera (projection refuses
// points behind it; a wild early prediction may put some there: that view is skipped).
Tensor batch_row(const Tensor& t, int64_t b) { return ops::slice(t, 0, b, b + 1); }

}  // namespace

Tensor multiview_landmark_loss(const Tensor& keypoints, const std::vector<int>& frames,
                               const MultiviewSupervision& sup, const std::vector<double>& mask,
                               LandmarkStatistics* stats) {
  WEFT_CHECK(int64_t(frames.size()) == keypoints.size(0), "multiview_landmark_loss: keypoints ",
             shape_str(keypoints.shape()), " for ", frames.size(), " frames");
  std::vector<std::vector<KeypointView>> views(frames.size());
  for (size_t b = 0; b < frames.size(); ++b)
    for (int v = 0; v < sup.views(); ++v) views[b].push_back({sup.camera(frames[b], v), sup.detections(frames[b], v)});
  return landmark_loss_over_views(keypoints, views, mask, stats);
}

Tensor multiview_silhouette_loss(const Tensor& vertices, const Faces& faces, const std::vector<int>& frames,
                                 const MultiviewSupervision& sup) {
  const int64_t B = vertices.size(0);
  WEFT_CHECK(int64_t(frames.size()) == B, "multiview_silhouette_loss: ", B, " samples for ", frames.size(),
             " frames");
  const int views = sup.views();
  struct Pair {
    std::vector<int> rows;
    std::vector<double> rho;
  };
  std::vector<Pair> pairs(B * views);
  std::vector<Vertices> V(B);
  for (int64_t b = 0; b < B; ++b) V[b] = sample_vertices(vertices, b);
  // The silhouette's vertices and their weights: plain geometry, on TBB threads.
  tbb::parallel_for(int64_t(0), int64_t(pairs.size()), [&](int64_t i) {
    const int64_t b = i / views;
    const int v = int(i % views);
    const Camera& cam = sup.silhouette_camera(frames[b], v);
    if (!in_front(cam, V[b])) return;
    const std::vector<int> boundary = boundary_vertices(cam, V[b], faces);
    const std::vector<double> rho =
        silhouette_weights(cam, V[b], vertex_normals(V[b], faces), boundary, sup.distance_transform(frames[b], v));
    for (size_t k = 0; k < boundary.size(); ++k)
      if (rho[k] > 0) pairs[i].rows.push_back(boundary[k]), pairs[i].rho.push_back(rho[k]);
  });
  Tensor total;
  double rho_sum = 0;
  const int S = sup.silhouette_size();
  for (int64_t i = 0; i < int64_t(pairs.size()); ++i) {
    const Pair& p = pairs[i];
    if (p.rows.empty()) continue;
    const int64_t b = i / views;
    const int v = int(i % views);
    const int64_t N = p.rows.size();
    const Tensor index = Tensor::from_indices({1, N}, std::vector<int64_t>(p.rows.begin(), p.rows.end()));
    const Tensor projected =
        ops::project_points(select_vertices(batch_row(vertices, b), index), pinhole(sup.silhouette_camera(frames[b], v)));
    const cv::Mat dt = sup.distance_transform(frames[b], v);
    std::vector<float> pixels(dt.begin<float>(), dt.end<float>());
    const Tensor image = ops::reshape(Tensor::from_data({int64_t(dt.rows) * dt.cols}, pixels), {1, dt.rows, dt.cols});
    const Tensor term = silhouette_loss(projected, image, Tensor::from_data({1, N}, p.rho, DType::F32));
    total = total.defined() ? ops::add(total, term) : term;
    for (double r : p.rho) rho_sum += r;
  }
  if (!total.defined()) return ops::scale(ops::sum(vertices), 0.0);
  return ops::scale(total, 1.0 / (double(S) * S * rho_sum));
}

}  // namespace weft::capture
