#pragma once
// The paper's temporal Gaussian filter (testing, ../shared/DESIGN.md): each frame's network
// outputs replaced by a Gaussian-weighted mean over a window of 2·radius + 1 frames.
#include <Eigen/Core>
#include <vector>

namespace weft::capture {

// rows: frames in time order; ids: their frame ids. The window does not cross a gap
// (ids not consecutive: frames that are not neighbours in time are not averaged), and
// the weights exp(−k²/(2σ²)) are renormalised where the window is cut by a gap or an end.
// sigma ≤ 0 or radius 0 returns the rows unchanged.
Eigen::MatrixXd gaussian_filter_frames(const Eigen::MatrixXd& rows, const std::vector<int>& ids, double sigma,
                                       int radius);

}  // namespace weft::capture
