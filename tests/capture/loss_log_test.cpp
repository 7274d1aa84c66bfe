// The training loss log: rows read back as written (%.9g), a new term widens the file,
// resuming drops the rows after the checkpoint, malformed files name file and line, and
// the plot draws something readable from realistic and from degenerate rows.
// WEFT_KEEP_LOSS_PLOTS=DIR keeps the plots for a look.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>

#include "capture/training/loss_log.h"
#include "tests/capture/test_files.h"

namespace weft::capture {
namespace {

using testing::expect_error;
using testing::ScratchDir;
using testing::slurp;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

double through_9g(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return std::strtod(buf, nullptr);
}

void expect_rows_equal(const std::vector<LossRow>& got, const std::vector<LossRow>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].step, want[i].step);
    EXPECT_EQ(got[i].stage, want[i].stage);
    ASSERT_EQ(got[i].terms.size(), want[i].terms.size()) << "step " << want[i].step;
    for (const auto& [name, v] : want[i].terms) {
      ASSERT_TRUE(got[i].terms.count(name)) << name;
      const double g = got[i].terms.at(name);
      if (std::isnan(v))
        EXPECT_TRUE(std::isnan(g)) << name;
      else
        EXPECT_EQ(g, through_9g(v)) << name << " at step " << want[i].step;
    }
  }
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream ss(text);
  for (std::string l; std::getline(ss, l);) lines.push_back(l);
  return lines;
}

LossRow row(int64_t step, const std::string& stage, std::map<std::string, double> terms) {
  return LossRow{step, stage, std::move(terms)};
}

TEST(LossLog, RowsReadBackAndANewTermAddsAColumn) {
  ScratchDir dir("loss_log");
  const std::string path = dir.file("losses.csv");
  std::vector<LossRow> want = {
      row(1, "pose", {{"total", 1.0 / 3}, {"landmarks", 12345.678912345}}),
      row(2, "pose", {{"total", 1e-12}, {"landmarks", -0.5}}),
      row(3, "pose", {{"total", kNaN}, {"landmarks", kInf}}),
      row(4, "physics", {{"total", 2.5}, {"landmarks", 1}, {"silhouette", 7e-300}, {"physics", -kInf}}),
      row(5, "physics", {{"total", 2}, {"silhouette", 3}}),
  };
  LossLog log(path, -1);
  for (size_t i = 0; i < want.size(); ++i) {
    log.append(want[i]);
    expect_rows_equal(read_loss_log(path), std::vector<LossRow>(want.begin(), want.begin() + i + 1));
  }
  expect_rows_equal(log.rows(), want);
  const std::vector<std::string> lines = lines_of(slurp(path));
  ASSERT_EQ(lines.size(), 6u);
  EXPECT_EQ(lines[0], "step,stage,landmarks,total,physics,silhouette");
  EXPECT_EQ(lines[1], "1,pose,12345.6789,0.333333333,,");
  EXPECT_EQ(lines[3], "3,pose,inf,nan,,");
  EXPECT_EQ(lines[4], "4,physics,1,2.5,-inf,7e-300");
  EXPECT_EQ(lines[5], "5,physics,,2,,3");
}

TEST(LossLog, AppendRejectsBadRowsAndKeepsTheFileIntact) {
  ScratchDir dir("loss_log");
  const std::string path = dir.file("losses.csv");
  LossLog log(path, -1);
  log.append(row(5, "pose", {{"total", 1}}));
  expect_error([&] { log.append(row(5, "pose", {{"total", 1}})); }, {"losses.csv", "step 5"});
  expect_error([&] { log.append(row(6, "po,se", {{"total", 1}})); }, {"stage"});
  expect_error([&] { log.append(row(6, "pose", {{"a,b", 1}})); }, {"a,b"});
  expect_error([&] { log.append(row(6, "pose", {{"step", 1}})); }, {"step"});
  log.append(row(6, "pose", {{"total", 2}}));
  expect_rows_equal(read_loss_log(path), {row(5, "pose", {{"total", 1}}), row(6, "pose", {{"total", 2}})});
}

TEST(LossLog, ResumeKeepsTheRowsUpToTheCheckpoint) {
  ScratchDir dir("loss_log");
  const std::string path = dir.file("losses.csv");
  std::vector<LossRow> all;
  {
    LossLog log(path, -1);
    for (int s = 1; s <= 10; ++s) {
      std::map<std::string, double> terms = {{"total", 1.0 / s}};
      if (s >= 8) terms["physics"] = 0.1 * s;  // a column only the dropped rows use
      all.push_back(row(s, s <= 7 ? "pose" : "physics", terms));
      log.append(all.back());
    }
  }
  {
    std::FILE* f = std::fopen(path.c_str(), "ab");  // a row torn by a kill
    std::fputs("11,physics,0.0", f);
    std::fclose(f);
  }
  LossLog resumed(path, 6);
  const std::vector<LossRow> first6(all.begin(), all.begin() + 6);
  expect_rows_equal(resumed.rows(), first6);
  expect_rows_equal(read_loss_log(path), first6);
  EXPECT_EQ(lines_of(slurp(path))[0], "step,stage,total");
  resumed.append(all[6]);
  expect_rows_equal(read_loss_log(path), std::vector<LossRow>(all.begin(), all.begin() + 7));

  LossLog fresh(path, -1);
  EXPECT_TRUE(fresh.rows().empty());
  EXPECT_TRUE(read_loss_log(path).empty());
  LossLog missing(dir.file("none.csv"), 3);  // resuming a run that logged nothing
  EXPECT_TRUE(missing.rows().empty());
  EXPECT_TRUE(std::filesystem::exists(dir.file("none.csv")));
}

TEST(LossLog, MalformedFilesNameTheFileAndLine) {
  ScratchDir dir("loss_log");
  const std::string head = "step,stage,total,landmarks\n1,pose,0.5,2\n";
  expect_error([&] { read_loss_log(dir.write("losses.csv", head + "2,pose,abc,1\n")); },
               {"losses.csv:3", "total", "abc"});
  expect_error([&] { read_loss_log(dir.write("losses.csv", head + "2,pose,1\n")); },
               {"losses.csv:3", "4", "found 3"});
  expect_error([&] { read_loss_log(dir.write("losses.csv", head + "1,pose,1,1\n")); },
               {"losses.csv:3", "step 1"});
  expect_error([&] { read_loss_log(dir.write("losses.csv", head + "x,pose,1,1\n")); },
               {"losses.csv:3", "integer step"});
  expect_error([&] { read_loss_log(dir.write("losses.csv", "iteration,total\n1,2\n")); },
               {"losses.csv:1", "header"});
  expect_error([&] { LossLog(dir.write("losses.csv", head + "2,pose,abc,1\n"), 5); },
               {"losses.csv:3"});  // resume never silently discards a damaged log
  expect_error([&] { read_loss_log(dir.file("absent.csv")); }, {"absent.csv"});
  EXPECT_EQ(read_loss_log(dir.write("losses.csv", head + "\r\n2,pose,,1\r\n")).size(), 2u);
}

// Two stages, three terms decaying with multiplicative noise, and their weighted total.
std::vector<LossRow> realistic_rows(int pose_steps, int physics_steps) {
  std::mt19937 gen(7);
  std::normal_distribution<double> noise(0, 0.25);
  std::vector<LossRow> rows;
  for (int s = 1; s <= pose_steps + physics_steps; ++s) {
    LossRow r;
    r.step = s;
    r.stage = s <= pose_steps ? "pose" : "physics";
    const double t = s;
    r.terms["landmarks"] = (3e3 * std::exp(-t / 150) + 40) * std::exp(noise(gen));
    r.terms["silhouette"] = (0.8 * std::exp(-t / 400) + 0.05) * std::exp(noise(gen));
    if (s > pose_steps) r.terms["physics"] = (2e-2 * std::exp(-(t - pose_steps) / 200) + 1e-4) * std::exp(noise(gen));
    double total = 0;
    for (const auto& [name, v] : r.terms) total += (name == "landmarks" ? 1e-3 : 1.0) * v;
    r.terms["total"] = total;
    rows.push_back(r);
  }
  return rows;
}

// Reads a plot back: the expected size, and a fair share of pixels not background.
void expect_drawn(const std::string& png, int width, int height, double min_ink) {
  const cv::Mat img = cv::imread(png, cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty()) << png;
  EXPECT_EQ(img.cols, width);
  EXPECT_EQ(img.rows, height);
  const cv::Mat ink = img != cv::Scalar(255, 255, 255);
  std::vector<cv::Mat> ch;
  cv::split(ink, ch);
  const double share = cv::countNonZero(ch[0] | ch[1] | ch[2]) / double(width * height);
  EXPECT_GT(share, min_ink) << png;
  if (const char* keep = std::getenv("WEFT_KEEP_LOSS_PLOTS")) {
    std::filesystem::create_directories(keep);
    std::filesystem::copy_file(png, std::filesystem::path(keep) / std::filesystem::path(png).filename(),
                               std::filesystem::copy_options::overwrite_existing);
  }
}

TEST(LossPlot, DrawsRealisticCurves) {
  ScratchDir dir("loss_plot");
  const std::string png = dir.file("losses.png");
  plot_losses(realistic_rows(600, 900), png);
  expect_drawn(png, 1200, 800, 0.05);
  std::vector<LossRow> three = realistic_rows(300, 300);  // one column of panels
  for (LossRow& r : three) r.terms.erase("total");
  plot_losses(three, dir.file("three_terms.png"), "three terms");
  expect_drawn(dir.file("three_terms.png"), 1200, 800, 0.05);
  std::filesystem::remove(dir.file("three_terms.png"));
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.file("")),
                          std::filesystem::directory_iterator()),
            1);  // no temporary left behind
}

TEST(LossPlot, DrawsDegenerateRows) {
  ScratchDir dir("loss_plot");
  std::vector<LossRow> rows = realistic_rows(40, 40);
  rows[5].terms["landmarks"] = kNaN;
  rows[6].terms["silhouette"] = kInf;
  rows[7].terms["silhouette"] = 0;
  rows[8].terms["total"] = -1;
  for (LossRow& r : rows) r.terms["zero"] = 0;          // nothing to draw on a log axis
  for (int i = 10; i < 20; ++i) rows[i].terms.erase("landmarks");  // a gap
  rows[30].stage = "warmup";                             // a one-step stage
  rows[50].terms["constant"] = 4;                         // a single point
  plot_losses(rows, dir.file("degenerate.png"), "degenerate");
  expect_drawn(dir.file("degenerate.png"), 1200, 800, 0.03);

  plot_losses({row(1, "pose", {{"total", 1}})}, dir.file("one_row.png"), "one row", 640, 480);
  expect_drawn(dir.file("one_row.png"), 640, 480, 0.01);
  plot_losses({}, dir.file("empty.png"), "empty");
  expect_drawn(dir.file("empty.png"), 1200, 800, 0.001);
  std::vector<LossRow> many;
  for (int s = 1; s <= 50; ++s) {
    LossRow r{s, s < 25 ? "pose" : "physics", {}};
    for (int k = 0; k < 10; ++k) r.terms["term" + std::to_string(k)] = std::pow(10.0, -k) / s;
    many.push_back(r);
  }
  plot_losses(many, dir.file("ten_terms.png"), "ten terms");
  expect_drawn(dir.file("ten_terms.png"), 1200, 800, 0.05);
  EXPECT_THROW(plot_losses(many, dir.file("tiny.png"), "tiny", 10, 10), Error);
}

}  // namespace
}  // namespace weft::capture
