// The method end to end on the tiny dataset, as the demo runs it: a model trained by
// `weft train` (configs/train/tiny.yaml, the shared reference run) captures one studio
// view with `weft infer`, and `weft eval` measures the capture against the ground truth:
// every metric is produced and the report is written.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "capture/evaluation/capture_evaluation.h"
#include "capture/evaluation/evaluation_report.h"
#include "capture/inference/sequence_capture.h"
#include "tests/capture/shared_fixture.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
namespace fs = std::filesystem;

TEST(EndToEnd, TrainInferEvaluateProducesEveryMetricAndTheReport) {
  const fs::path data = weft::capture::testing::tiny_dataset();
  const fs::path model = weft::capture::testing::tiny_reference_run();
  const fs::path scratch = weft::capture::testing::process_scratch("end_to_end");
  CaptureOptions c;
  c.model = model.string();
  c.input = (data / "images" / "cam03").string();
  c.camera = (data / "cameras.yaml").string();
  c.camera_name = "cam03";
  c.keypoints = (data / "keypoints" / "cam03").string();
  c.out = (scratch / "capture").string();
  const CaptureSummary captured = capture_sequence(c);
  ASSERT_EQ(captured.frames, 6);

  EvaluationOptions e;
  e.prediction = c.out;
  e.data = data.string();
  const CaptureEvaluation evaluation = evaluate_capture(e);
  write_evaluation_report(evaluation, (scratch / "report").string());
  EXPECT_EQ(evaluation.view, "cam03");
  EXPECT_EQ(evaluation.oob_frames, 4);  // frames 2–5 have two predecessors
  for (double v : {evaluation.oob_n.mean, evaluation.oob_n.max, evaluation.oob_rel.mean, evaluation.oob_rel.max,
                   evaluation.penetration_mean_mm, evaluation.penetration_max_mm, evaluation.penetrating_fraction,
                   evaluation.amv_iou, evaluation.rv_iou, evaluation.sv_iou, evaluation.cloth_error_mean_mm,
                   evaluation.cloth_error_p95_mm, evaluation.body_error_mean_mm, evaluation.body_error_p95_mm,
                   evaluation.mpjpe_mm})
    EXPECT_TRUE(std::isfinite(v));
  EXPECT_GT(evaluation.amv_iou, 0.0);
  EXPECT_LE(evaluation.amv_iou, 1.0);
  EXPECT_GE(evaluation.oob_n.max, evaluation.oob_n.mean);
  EXPECT_GE(evaluation.cloth_error_p95_mm, 0.0);
  EXPECT_TRUE(fs::exists(scratch / "report" / "report.html"));
  std::ifstream in(scratch / "report" / "metrics.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_FALSE(j.empty());
}
