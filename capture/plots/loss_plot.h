#pragma once
// The loss curves of a training run as a PNG (RUN/losses.png): the rows of its
// RUN/losses.csv (capture/training/loss_log.h) drawn with OpenCV.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace weft::capture {

// One logged step of a training run.
struct LossRow {
  int64_t step = 0;                      // global step, 1-based, strictly increasing
  std::string stage;                     // "pose", "warmup", "physics" (no commas)
  std::map<std::string, double> terms;   // e.g. {"total": .., "landmarks": .., "silhouette": ..}
};

// Draws the loss curves into a PNG (OpenCV only), written atomically: one panel per
// term ("total" first), x = step shared by all panels, y = log10 of the value. Raw
// values are a thin light line, a centred moving average of log10 (within each stage) a
// bold one; stages are named in a bar on top, shaded alternately and separated by dashed
// lines. Values <= 0 are skipped and nan/inf are marked in red at the bottom of the
// panel; both are counted in the panel's caption, next to the last smoothed value and
// the minimum. Errors: a size under 320x240, a failed write.
void plot_losses(const std::vector<LossRow>& rows, const std::string& png_path,
                 const std::string& title = "weft train", int width = 1200, int height = 800);

}  // namespace weft::capture
