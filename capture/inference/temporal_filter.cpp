#include "capture/inference/temporal_filter.h"

#include <cmath>

#include "graph/error.h"

namespace weft::capture {

Eigen::MatrixXd gaussian_filter_frames(const Eigen::MatrixXd& rows, const std::vector<int>& ids, double sigma,
                                       int radius) {
  WEFT_CHECK(rows.rows() == Eigen::Index(ids.size()), "gaussian_filter_frames: ", rows.rows(), " rows for ",
             ids.size(), " frame ids");
  if (!(sigma > 0) || radius <= 0) return rows;
  const int n = int(ids.size());
  // first[i]: the first frame of i's run of consecutive ids.
  std::vector<int> first(size_t(n), 0), last(size_t(n), n - 1);
  for (int i = 1; i < n; ++i) first[size_t(i)] = ids[size_t(i)] == ids[size_t(i - 1)] + 1 ? first[size_t(i - 1)] : i;
  for (int i = n - 2; i >= 0; --i) last[size_t(i)] = ids[size_t(i + 1)] == ids[size_t(i)] + 1 ? last[size_t(i + 1)] : i;
  Eigen::MatrixXd out(rows.rows(), rows.cols());
  for (int i = 0; i < n; ++i) {
    double total = 0;
    out.row(i).setZero();
    for (int k = -radius; k <= radius; ++k) {
      const int j = i + k;
      if (j < first[size_t(i)] || j > last[size_t(i)]) continue;
      const double w = std::exp(-0.5 * k * k / (sigma * sigma));
      out.row(i) += w * rows.row(j);
      total += w;
    }
    out.row(i) /= total;
  }
  return out;
}

}  // namespace weft::capture
