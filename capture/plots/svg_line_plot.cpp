#include "capture/plots/svg_line_plot.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "capture/plots/axis_ticks.h"
#include "graph/error.h"

namespace weft::capture {

std::string html_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string svg_line_plot(const std::string& title, const std::string& unit, const std::vector<int>& ids,
                          const std::vector<PlotSeries>& series) {
  const double W = 640, H = 230, left = 64, right = 12, top = 28, bottom = 36;
  double lo = 0, hi = 0;
  bool any = false;
  for (const PlotSeries& s : series)
    for (double v : s.values)
      if (std::isfinite(v)) lo = any ? std::min(lo, v) : std::min(0.0, v), hi = any ? std::max(hi, v) : v, any = true;
  if (!(hi > lo)) hi = lo + 1;
  const double step = nice_step(hi - lo, 5);
  hi = std::ceil(hi / step - 1e-9) * step, lo = std::floor(lo / step + 1e-9) * step;
  const int x0 = ids.empty() ? 0 : ids.front(), x1 = ids.empty() ? 1 : std::max(ids.back(), ids.front() + 1);
  const auto X = [&](double id) { return left + (id - x0) / double(x1 - x0) * (W - left - right); };
  const auto Y = [&](double v) { return top + (hi - v) / (hi - lo) * (H - top - bottom); };
  std::string svg = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" viewBox=\"0 0 {} {}\" "
      "font-family=\"sans-serif\" font-size=\"11\">\n<text x=\"{}\" y=\"16\" font-size=\"13\" "
      "font-weight=\"bold\">{}</text>\n",
      W, H, W, H, left, html_escape(title));
  for (double v = lo; v <= hi + 1e-9 * step; v += step)
    svg += fmt::format(
        "<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#ddd\"/><text x=\"{:.1f}\" "
        "y=\"{:.1f}\" text-anchor=\"end\">{:.4g}</text>\n",
        left, Y(v), W - right, Y(v), left - 4, Y(v) + 4, v);
  const int xstep = std::max(1, int(nice_step(x1 - x0, 5)));
  for (int id = (x0 / xstep) * xstep; id <= x1; id += xstep) {
    if (id < x0) continue;
    svg += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{}</text>\n", X(id),
                       H - bottom + 14, id);
  }
  svg += fmt::format(
      "<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">frame</text>\n<text x=\"12\" y=\"{:.1f}\" "
      "transform=\"rotate(-90 12 {:.1f})\" text-anchor=\"middle\">{}</text>\n"
      "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#888\"/>\n",
      (left + W - right) / 2, H - 4, (top + H - bottom) / 2, (top + H - bottom) / 2, html_escape(unit), left, top,
      W - left - right, H - top - bottom);
  double legend_x = W - right - 8;
  for (auto it = series.rbegin(); it != series.rend(); ++it) {
    legend_x -= 7.0 * it->name.size() + 22;
    svg += fmt::format(
        "<line x1=\"{:.1f}\" y1=\"12\" x2=\"{:.1f}\" y2=\"12\" stroke=\"{}\" stroke-width=\"2\"/><text x=\"{:.1f}\" "
        "y=\"16\">{}</text>\n",
        legend_x, legend_x + 14, it->colour, legend_x + 17, html_escape(it->name));
  }
  for (const PlotSeries& s : series) {
    WEFT_CHECK(s.values.size() == ids.size(), "svg_line_plot: series '", s.name, "' has ", s.values.size(),
               " values for ", ids.size(), " frames");
    std::string run;
    int run_points = 0;
    size_t last = 0;  // the run's last point
    const auto flush = [&] {
      if (run_points == 1)
        svg += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"2.5\" fill=\"{}\"/>\n", X(ids[last]),
                           Y(s.values[last]), s.colour);
      else if (run_points > 1)
        svg += fmt::format("<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"1.5\" points=\"{}\"/>\n",
                           s.colour, run);
      run.clear(), run_points = 0;
    };
    for (size_t i = 0; i < ids.size(); ++i) {
      if (!std::isfinite(s.values[i])) {
        if (!s.connect_gaps) flush();
        continue;
      }
      // A gap where captured frame ids jump.
      if (run_points && ids[i] - ids[last] != int(i - last)) flush();
      run += fmt::format("{:.1f},{:.1f} ", X(ids[i]), Y(s.values[i]));
      ++run_points, last = i;
    }
    flush();
  }
  return svg + "</svg>\n";
}

}  // namespace weft::capture
