#include "capture/model/view_landmark_loss.h"

#include "capture/deformation/losses.h"
#include "capture/model/capture_networks.h"
#include "graph/error.h"
#include "ops/geometry.h"
#include "ops/ops.h"

namespace weft::capture {

namespace {
Tensor batch_row(const Tensor& t, int64_t b) { return ops::slice(t, 0, b, b + 1); }
}  // namespace

Tensor landmark_loss_over_views(const Tensor& keypoints, const std::vector<std::vector<KeypointView>>& views,
                                const std::vector<double>& mask, LandmarkStatistics* stats) {
  const int64_t B = keypoints.size(0);
  WEFT_CHECK(int64_t(views.size()) == B && keypoints.dim() == 3 && keypoints.size(1) == kBody25Count &&
                 mask.size() == size_t(kBody25Count),
             "landmark_loss_over_views: keypoints ", shape_str(keypoints.shape()), " for ", views.size(),
             " samples' views and a mask of ", mask.size());
  std::vector<Tensor> projected;
  std::vector<double> detections, confidence;
  double error_sum = 0;
  int error_count = 0;
  for (int64_t b = 0; b < B; ++b) {
    const Vertices K = sample_vertices(keypoints, b);
    for (const KeypointView& view : views[b]) {
      const Camera& cam = view.camera;
      if (!in_front(cam, K)) continue;
      const Body25& d = view.detections;
      const double w = 1.0 / cam.width;
      projected.push_back(ops::scale(ops::project_points(batch_row(keypoints, b), pinhole(cam)), w));
      for (int m = 0; m < kBody25Count; ++m) {
        detections.push_back(d(m, 0) * w);
        detections.push_back(d(m, 1) * w);
        confidence.push_back(d(m, 2) * mask[m]);
        if (stats && d(m, 2) >= 0.1 && mask[m] > 0) {
          error_sum += (cam.project(K.row(m).transpose()) - d.row(m).head<2>().transpose()).norm();
          ++error_count;
        }
      }
    }
  }
  if (stats) *stats = {error_count ? error_sum / error_count : 0.0, error_count};
  if (projected.empty()) return ops::scale(ops::sum(keypoints), 0.0);
  const int64_t n = projected.size();
  double confidence_sum = 0;
  for (double c : confidence) confidence_sum += c;
  if (confidence_sum <= 0) return ops::scale(ops::sum(keypoints), 0.0);
  const Tensor p = ops::concat(projected, 0);
  // landmark_loss sums over keypoints and averages over its n rows: make it the mean over detections.
  const DType dt = keypoints.dtype();
  return ops::scale(landmark_loss(p, Tensor::from_data({n, kBody25Count, 2}, detections, dt),
                                  Tensor::from_data({n, kBody25Count}, confidence, dt)),
                    double(n) / confidence_sum);
}

}  // namespace weft::capture
