#include "capture/plots/loss_plot.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

#include "capture/io/png_file.h"
#include "capture/plots/axis_ticks.h"
#include "graph/error.h"

namespace weft::capture {

namespace {

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
const cv::Scalar kWhite(255, 255, 255);
const cv::Scalar kInk(45, 45, 45);
const cv::Scalar kMuted(110, 110, 110);
const cv::Scalar kGrid(226, 226, 226);
const cv::Scalar kFrame(160, 160, 160);
const cv::Scalar kShade(243, 243, 243);
const cv::Scalar kBad(40, 40, 215);
// Tableau 10 (BGR), red left out: red marks nan/inf.
const cv::Scalar kPalette[] = {{180, 119, 31}, {14, 127, 255}, {44, 160, 44},  {189, 103, 148},
                               {75, 86, 140},  {194, 119, 227}, {34, 189, 188}, {207, 190, 23},
                               {127, 127, 127}};

cv::Scalar lighten(const cv::Scalar& c, double keep) { return c * keep + kWhite * (1 - keep); }

int text_width(const std::string& s, double scale, int thickness = 1) {
  int base = 0;
  return cv::getTextSize(s, kFont, scale, thickness, &base).width;
}

// Draws `s` with its baseline at `org`; returns the x after it.
int put(cv::Mat& img, const std::string& s, cv::Point org, double scale, const cv::Scalar& color,
        int thickness = 1) {
  cv::putText(img, s, org, kFont, scale, color, thickness, cv::LINE_AA);
  return org.x + text_width(s, scale, thickness);
}

// Tick labels: plain below 1e5 and from 1e-3, else short scientific ("2.5e-6").
std::string value_label(double v) {
  char buf[32];
  const double a = std::fabs(v);
  if (a == 0 || (a >= 1e-3 && a < 1e5)) {
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
  }
  std::snprintf(buf, sizeof buf, "%.3g", v);
  std::string s = buf;
  const size_t e = s.find('e');
  if (e == std::string::npos) return s;
  std::string mant = s.substr(0, e), exp = s.substr(e + 1);
  const bool neg = !exp.empty() && exp[0] == '-';
  if (!exp.empty() && (exp[0] == '-' || exp[0] == '+')) exp.erase(0, 1);
  exp.erase(0, std::min(exp.find_first_not_of('0'), exp.size() - 1));
  return mant + "e" + (neg ? "-" : "") + exp;
}

std::string step_label(double v) {
  char buf[32];
  const double a = std::fabs(v);
  if (a >= 1e6)
    std::snprintf(buf, sizeof buf, "%.4gM", v / 1e6);
  else if (a >= 1e4)
    std::snprintf(buf, sizeof buf, "%.4gk", v / 1e3);
  else
    std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

struct Span {
  std::string stage;
  size_t begin, end;  // rows [begin, end)
};

std::vector<Span> stage_spans(const std::vector<LossRow>& rows) {
  std::vector<Span> spans;
  for (size_t i = 0; i < rows.size(); ++i) {
    if (spans.empty() || rows[i].stage != spans.back().stage) spans.push_back({rows[i].stage, i, i});
    spans.back().end = i + 1;
  }
  return spans;
}

// The x range of every panel: steps [x0, x1] onto pixels [left, right].
struct XAxis {
  double x0, x1;
  double px(double step, const cv::Rect& r) const {
    return r.x + (step - x0) / (x1 - x0) * (r.width - 1);
  }
};

// Pixel extents [from, to) of each stage span on a plot rect: boundaries halfway between
// the last step of one stage and the first of the next.
std::vector<std::pair<double, double>> span_extents(const std::vector<LossRow>& rows,
                                                    const std::vector<Span>& spans, const XAxis& xa,
                                                    const cv::Rect& r) {
  std::vector<std::pair<double, double>> ext;
  for (size_t k = 0; k < spans.size(); ++k) {
    const double from = k == 0 ? r.x
                               : xa.px(0.5 * (rows[spans[k].begin - 1].step + rows[spans[k].begin].step), r);
    const double to = k + 1 == spans.size()
                          ? r.x + r.width
                          : xa.px(0.5 * (rows[spans[k].end - 1].step + rows[spans[k].end].step), r);
    ext.emplace_back(from, to);
  }
  return ext;
}

constexpr int kShift = 4;  // sub-pixel bits of the anti-aliased polylines
cv::Point subpixel(double x, double y) {
  return {static_cast<int>(std::lround(x * (1 << kShift))), static_cast<int>(std::lround(y * (1 << kShift)))};
}

void dashed_vline(cv::Mat& img, int x, int y0, int y1, const cv::Scalar& color) {
  for (int y = y0; y < y1; y += 8) cv::line(img, {x, y}, {x, std::min(y + 4, y1)}, color, 1);
}

// The stage timeline above a column of panels: shaded boxes, names centred.
void draw_stage_bar(cv::Mat& img, const cv::Rect& bar, const std::vector<LossRow>& rows,
                    const std::vector<Span>& spans, const XAxis& xa) {
  const auto ext = span_extents(rows, spans, xa, bar);
  for (size_t k = 0; k < spans.size(); ++k) {
    const int from = static_cast<int>(std::lround(ext[k].first));
    const int to = static_cast<int>(std::lround(ext[k].second));
    const cv::Rect box(from, bar.y, std::max(1, to - from), bar.height);
    cv::rectangle(img, box, k % 2 ? cv::Scalar(222, 222, 222) : cv::Scalar(236, 236, 236), cv::FILLED);
    if (k > 0) cv::line(img, {from, bar.y}, {from, bar.y + bar.height - 1}, kMuted, 1);
    std::string name = spans[k].stage;
    const double scale = 0.45;
    while (!name.empty() && text_width(name, scale) > box.width - 6) name.pop_back();
    if (name.size() < spans[k].stage.size() && name.size() >= 2) name.back() = '.';
    if (name.size() < 2 && spans[k].stage.size() >= 2) continue;
    put(img, name, {from + (box.width - text_width(name, scale)) / 2, bar.y + bar.height - 6}, scale, kInk);
  }
  cv::rectangle(img, bar, kFrame, 1);
}

void draw_panel(cv::Mat& img, const cv::Rect& cell, const std::string& term,
                const std::vector<LossRow>& rows, const std::vector<Span>& spans, const XAxis& xa,
                const cv::Scalar& color, const cv::Rect& plot) {
  // log10 of each row's value; NaN where there is none to draw.
  enum State : char { absent, non_finite, non_positive, ok };
  std::vector<State> state(rows.size(), absent);
  std::vector<double> lv(rows.size(), std::nan(""));
  int n_bad = 0, n_nonpos = 0, n_ok = 0;
  double lo = INFINITY, hi = -INFINITY, vmin = INFINITY;
  for (size_t i = 0; i < rows.size(); ++i) {
    const auto it = rows[i].terms.find(term);
    if (it == rows[i].terms.end()) continue;
    const double v = it->second;
    if (!std::isfinite(v)) {
      state[i] = non_finite, ++n_bad;
    } else if (v <= 0) {
      state[i] = non_positive, ++n_nonpos;
    } else {
      state[i] = ok, ++n_ok;
      lv[i] = std::log10(v);
      lo = std::min(lo, lv[i]), hi = std::max(hi, lv[i]), vmin = std::min(vmin, v);
    }
  }
  if (n_ok > 0) {
    if (hi - lo < 1e-6) lo -= 0.25, hi += 0.25;
    const double pad = 0.06 * (hi - lo);
    lo -= pad, hi += pad;
  }
  auto py = [&](double l) { return plot.y + (hi - l) / (hi - lo) * (plot.height - 1); };

  // Stage shading and boundaries.
  const auto ext = span_extents(rows, spans, xa, plot);
  for (size_t k = 0; k < spans.size(); ++k) {
    const int from = static_cast<int>(std::lround(ext[k].first));
    const int to = static_cast<int>(std::lround(ext[k].second));
    if (k % 2) cv::rectangle(img, cv::Rect(from, plot.y, std::max(1, to - from), plot.height), kShade, cv::FILLED);
  }

  // Grid and tick labels.
  const double tick_scale = 0.4;
  for (double t : linear_ticks(xa.x0, xa.x1, std::max(2, plot.width / 90), 1)) {
    const int x = static_cast<int>(std::lround(xa.px(t, plot)));
    cv::line(img, {x, plot.y}, {x, plot.y + plot.height - 1}, kGrid, 1);
    const std::string s = step_label(t);
    put(img, s, {x - text_width(s, tick_scale) / 2, plot.y + plot.height + 15}, tick_scale, kMuted);
  }
  if (n_ok > 0) {
    for (double t : log_ticks(lo, hi, std::max(2, plot.height / 26), plot.height / (hi - lo))) {
      const int y = static_cast<int>(std::lround(py(t)));
      cv::line(img, {plot.x, y}, {plot.x + plot.width - 1, y}, kGrid, 1);
      const std::string s = value_label(std::pow(10.0, t));
      put(img, s, {plot.x - 6 - text_width(s, tick_scale), y + 4}, tick_scale, kMuted);
    }
  }
  for (size_t k = 1; k < spans.size(); ++k)
    dashed_vline(img, static_cast<int>(std::lround(ext[k].first)), plot.y, plot.y + plot.height, kMuted);

  // Curves: raw values thin and light, a centred moving average of log10 bold (no lag,
  // and no start-up transient: the window is cut short at the ends of a run). A run is
  // one stage's stretch of rows holding the term; values that cannot be drawn are
  // stepped over.
  double last_avg = std::nan("");
  if (n_ok > 0) {
    const size_t half = static_cast<size_t>(std::clamp(n_ok / 80, 0, 250));
    const cv::Scalar light = lighten(color, 0.35);
    std::vector<std::vector<cv::Point>> raw_runs, avg_runs;
    std::vector<size_t> run;  // row indices of ok values
    auto flush = [&] {
      std::vector<double> prefix(run.size() + 1, 0.0);
      for (size_t k = 0; k < run.size(); ++k) prefix[k + 1] = prefix[k] + lv[run[k]];
      std::vector<cv::Point> raw, avg;
      for (size_t k = 0; k < run.size(); ++k) {
        const size_t from = k >= half ? k - half : 0, to = std::min(run.size(), k + half + 1);
        const double x = xa.px(static_cast<double>(rows[run[k]].step), plot);
        last_avg = (prefix[to] - prefix[from]) / static_cast<double>(to - from);
        raw.push_back(subpixel(x, py(lv[run[k]])));
        avg.push_back(subpixel(x, py(last_avg)));
      }
      if (run.size() == 1) cv::circle(img, avg[0], 3 << kShift, color, cv::FILLED, cv::LINE_AA, kShift);
      if (run.size() >= 2) raw_runs.push_back(std::move(raw)), avg_runs.push_back(std::move(avg));
      run.clear();
    };
    for (const Span& sp : spans) {
      for (size_t i = sp.begin; i < sp.end; ++i) {
        if (state[i] == absent) flush();
        if (state[i] == ok) run.push_back(i);
      }
      flush();
    }
    cv::polylines(img, raw_runs, false, light, 1, cv::LINE_AA, kShift);
    cv::polylines(img, avg_runs, false, color, 2, cv::LINE_AA, kShift);
  } else {
    const std::string s = "no positive finite values";
    const cv::Point org(plot.x + (plot.width - text_width(s, 0.5)) / 2, plot.y + plot.height / 2);
    cv::rectangle(img, cv::Rect(org.x - 6, org.y - 16, text_width(s, 0.5) + 12, 24), kWhite, cv::FILLED);
    put(img, s, org, 0.5, kMuted);
  }
  for (size_t i = 0; i < rows.size(); ++i) {
    if (state[i] != non_finite) continue;
    const int x = static_cast<int>(std::lround(xa.px(static_cast<double>(rows[i].step), plot)));
    cv::line(img, {x, plot.y + plot.height - 12}, {x, plot.y + plot.height - 2}, kBad, 2);
  }
  cv::rectangle(img, plot, kFrame, 1);

  // Caption: the term, its smoothed last value and minimum, what was not drawn.
  const int base = cell.y + 15;
  int x = put(img, term, {plot.x, base}, 0.55, color, 2) + 14;
  if (n_ok > 0)
    x = put(img, "last " + value_label(std::pow(10.0, last_avg)) + "   min " + value_label(vmin),
            {x, base}, 0.45, kMuted) + 14;
  if (n_bad > 0) x = put(img, std::to_string(n_bad) + " nan/inf", {x, base}, 0.45, kBad) + 14;
  if (n_nonpos > 0) put(img, std::to_string(n_nonpos) + " <= 0 not drawn", {x, base}, 0.45, kMuted);
}

}  // namespace

void plot_losses(const std::vector<LossRow>& rows, const std::string& png_path,
                 const std::string& title, int width, int height) {
  WEFT_CHECK(width >= 320 && height >= 240, png_path, ": plot size ", width, "x", height,
             " is too small (at least 320x240)");
  cv::Mat img(height, width, CV_8UC3, kWhite);
  put(img, title, {16, 30}, 0.8, kInk, 2);

  // Terms in the order first seen, "total" first.
  std::vector<std::string> terms;
  for (const LossRow& r : rows)
    for (const auto& [name, v] : r.terms)
      if (std::find(terms.begin(), terms.end(), name) == terms.end()) terms.push_back(name);
  const auto total = std::find(terms.begin(), terms.end(), "total");
  if (total != terms.end()) std::rotate(terms.begin(), total, total + 1);

  if (terms.empty()) {
    const std::string s = "no losses logged yet";
    put(img, s, {(width - text_width(s, 0.7)) / 2, height / 2}, 0.7, kMuted);
  } else {
    char legend[160];
    std::snprintf(legend, sizeof legend, "steps %s-%s   log scale   thin: raw   bold: moving average",
                  step_label(static_cast<double>(rows.front().step)).c_str(),
                  step_label(static_cast<double>(rows.back().step)).c_str());
    put(img, legend, {width - 16 - text_width(legend, 0.45), 28}, 0.45, kMuted);

    double x0 = INFINITY, x1 = -INFINITY;
    for (const LossRow& r : rows) x0 = std::min(x0, double(r.step)), x1 = std::max(x1, double(r.step));
    if (x1 - x0 < 1) x0 -= 1, x1 += 1;
    const XAxis xa{x0, x1};
    const std::vector<Span> spans = stage_spans(rows);

    const int n = static_cast<int>(terms.size());
    const int cols = n <= 3 ? 1 : n <= 8 ? 2 : 3;
    const int nrows = (n + cols - 1) / cols;
    const int bar_top = 42, bar_h = 20, top = bar_top + bar_h + 6, bottom = height - 6;
    const int cell_w = (width - 8) / cols, cell_h = (bottom - top) / nrows;
    const int left = 62, right = 14, caption = 24, ticks = 22;
    for (int c = 0; c < cols; ++c) {
      const int cx = 4 + c * cell_w;
      const cv::Rect bar(cx + left, bar_top, cell_w - left - right, bar_h);
      draw_stage_bar(img, bar, rows, spans, xa);
    }
    for (int i = 0; i < n; ++i) {
      const cv::Rect cell(4 + (i % cols) * cell_w, top + (i / cols) * cell_h, cell_w, cell_h);
      const cv::Rect plot(cell.x + left, cell.y + caption, cell.width - left - right,
                          cell.height - caption - ticks);
      if (plot.width < 20 || plot.height < 20) continue;
      const size_t palette = sizeof kPalette / sizeof kPalette[0];
      draw_panel(img, cell, terms[i], rows, spans, xa, kPalette[i % palette], plot);
    }
  }
  write_png_atomically(png_path, img);
}

}  // namespace weft::capture
