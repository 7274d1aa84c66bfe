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

namespace weft::capture {

// Creates `dir` if needed; returns the paths written.
std::vector<std::string> write_evaluation_report(const CaptureEvaluation& evaluation, const std::string& dir);

// A line plot as an inline SVG element: one polyline per series over frame ids (a jump in
// the ids, and a NaN value unless the series connects gaps, breaks the line; isolated
// points are drawn as dots), axes with ticks, a legend.
struct PlotSeries {
  std::string name;
  std::vector<double> values;  // one per id
  std::string colour;          // CSS colour
  bool connect_gaps = false;   // a series measured on some frames only (IoU every N-th)
};
std::string svg_line_plot(const std::string& title, const std::string& unit, const std::vector<int>& ids,
                          const std::vector<PlotSeries>& series);

}  // namespace weft::capture
