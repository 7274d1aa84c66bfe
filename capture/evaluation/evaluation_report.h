#pragma once
// The report of `weft eval` (docs/EVALUATION.md), written into one folder, every file
// atomically (a temporary renamed over the target):
//   metrics.json             CaptureEvaluation::to_json(): options, summary, per-frame arrays
//   report.html              self-contained and viewable offline: the summary tables,
//                            per-frame plots of each metric (inline SVG), the overlays, notes
//   overlay_<label>_<id>.png the worst and median frames side by side (prediction | ground truth)
#include <string>
#include <vector>

#include "capture/evaluation/capture_evaluation.h"
#include "capture/plots/svg_line_plot.h"

namespace weft::capture {

// Creates `dir` if needed; returns the paths written.
std::vector<std::string> write_evaluation_report(const CaptureEvaluation& evaluation, const std::string& dir);

}  // namespace weft::capture
