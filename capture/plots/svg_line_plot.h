#pragma once
// Line plots as inline SVG elements, for HTML reports viewable offline (the report of
// `weft eval`); the same axis ticks as the PNG loss plot (axis_ticks.h).
#include <string>
#include <vector>

namespace weft::capture {

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

// `s` with &, <, > and " escaped for HTML text and attributes.
std::string html_escape(const std::string& s);

}  // namespace weft::capture
