// Every loss term of training (loss_terms(), capture/training/training_config.h) checked
// whole against central differences in float64: the function the trainer calls, not only
// the ops it is made of. A case is named "loss term <name>: ..."; the coverage test fails
// on a term of the table without one, as GradcheckCoverage does for ops.
#include <gtest/gtest.h>

#include <cmath>

#include "capture/deformation/losses.h"
#include "capture/detection/detection_losses.h"
#include "capture/studio/studio_rig.h"
#include "capture/training/multiview_losses.h"
#include "capture/training/simulation_loss.h"
#include "capture/training/training_config.h"
#include "graph/error.h"
#include "tests/gradcheck/cases.h"

namespace weft::testing {
namespace {

using capture::loss_terms;
using capture::LossTerm;

std::string case_prefix(const std::string& term) { return "loss term " + term + ":"; }

// A four-node graph, two edges per node at least (the ARAP test's).
capture::ArapTerms small_arap() {
  capture::EmbeddedGraph g;
  g.nodes.resize(4, 3);
  g.nodes << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  g.edges.resize(5, 2);
  g.edges << 0, 1, 0, 2, 0, 3, 1, 2, 2, 3;
  g.rigidity = Eigen::Vector4d(1, 0.5, 2, 1);
  return capture::arap_terms(g, DType::F64);
}

// Two anchors on two body triangles, with barycentric weights summing to 1.
capture::AttachmentTerms small_attachment() {
  capture::Attachment a;
  a.anchors.resize(2);
  a.anchors << 1, 3;
  a.triangles.resize(2);
  a.triangles << 0, 1;
  a.body_vertices.resize(2, 3);
  a.body_vertices << 0, 1, 2, 2, 1, 3;
  a.barycentric.resize(2, 3);
  a.barycentric << 0.2, 0.3, 0.5, 0.6, 0.1, 0.3;
  return capture::attachment_terms(a, DType::F64);
}

// Image points away from the pixel grid, where bilinear sampling has its kinks.
Tensor off_grid_points(Generator& g, int64_t B, int64_t N, double max_x, double max_y) {
  Tensor p = Tensor::empty({B, N, 2}, DType::F64);
  double* d = p.data<double>();
  for (int64_t i = 0; i < B * N; ++i) {
    d[2 * i] = std::floor(g.uniform(1.0, max_x)) + g.uniform(0.2, 0.8);
    d[2 * i + 1] = std::floor(g.uniform(1.0, max_y)) + g.uniform(0.2, 0.8);
  }
  return p;
}

}  // namespace

WEFT_GRADCHECK_CASES(loss_terms) {
  std::vector<GradcheckCase> cases;
  {
    GradcheckCase c;
    c.op = "mul";
    c.name = case_prefix("landmarks") + " projected [2,4,2], detections, confidences";
    c.make_inputs = [](Generator& g) {
      return std::vector<Tensor>{uniform64(g, {2, 4, 2}, -50, 50), uniform64(g, {2, 4, 2}, -50, 50),
                                 uniform64(g, {2, 4}, 0, 1)};
    };
    c.function = [](const std::vector<Tensor>& in) { return capture::landmark_loss(in[0], in[1], in[2]); };
    cases.push_back(c);
  }
  {
    // The whole term: keypoints [2,25,3] projected into two views each (one sample's first
    // camera in front, the other from the side) against detections with confidences.
    GradcheckCase c;
    c.op = "project_points";
    c.name = case_prefix("virtual_landmarks") + " keypoints [2,25,3] in 2 views each, detections, confidences";
    c.make_inputs = [](Generator& g) { return std::vector<Tensor>{uniform64(g, {2, capture::kBody25Count, 3}, -0.5, 0.5)}; };
    c.function = [](const std::vector<Tensor>& in) {
      std::vector<std::vector<capture::KeypointView>> views(2);
      for (int b = 0; b < 2; ++b)
        for (int v = 0; v < 2; ++v) {
          const double azimuth = 0.7 * v + 0.3 * b;
          capture::KeypointView kv;
          kv.camera = capture::look_at_camera("cam", Eigen::Vector3d(3 * std::sin(azimuth), 0.4, 3 * std::cos(azimuth)),
                                              Eigen::Vector3d::Zero(), 64, 48, 50);
          for (int m = 0; m < capture::kBody25Count; ++m)
            kv.detections.row(m) << 5 + 2.1 * m + 3 * v, 40 - 1.3 * m + b, m % 5 == 0 ? 0.0 : 0.1 + 0.03 * m;
          views[b].push_back(kv);
        }
      std::vector<double> mask(capture::kBody25Count, 1.0);
      mask[3] = 0;
      return capture::landmark_loss_over_views(in[0], views, mask);
    };
    cases.push_back(c);
  }
  {
    GradcheckCase c;
    c.op = "mul";
    c.name = case_prefix("keypoints_3d") + " points [2,5,3], triangulated targets, weights";
    c.make_inputs = [](Generator& g) {
      return std::vector<Tensor>{uniform64(g, {2, 5, 3}, -1, 1), uniform64(g, {2, 5, 3}, -1, 1),
                                 uniform64(g, {2, 5}, 0, 1)};
    };
    c.function = [](const std::vector<Tensor>& in) { return capture::keypoint_3d_loss(in[0], in[1], in[2]); };
    cases.push_back(c);
  }
  {
    GradcheckCase c;
    c.op = "slice";
    c.name = case_prefix("lumbopelvic") + " root rotations [3,3,3] against targets [3,3]";
    c.make_inputs = [](Generator& g) {
      return std::vector<Tensor>{uniform64(g, {3, 3, 3}, -1, 1), uniform64(g, {3, 3}, -1, 1)};
    };
    c.function = [](const std::vector<Tensor>& in) { return capture::lumbopelvic_loss(in[0], in[1]); };
    cases.push_back(c);
  }
  {
    GradcheckCase c;
    c.op = "image_sample_bilinear";
    c.name = case_prefix("silhouette") + " 5 boundary points in a 6x8 distance transform, per-point rho";
    c.make_inputs = [](Generator& g) {
      return std::vector<Tensor>{off_grid_points(g, 1, 5, 6, 4), uniform64(g, {1, 6, 8}, 0, 5),
                                 uniform64(g, {1, 5}, 0, 1)};
    };
    c.wrt = {0, 1};  // ρ is a constant of the step (silhouette_weights)
    c.function = [](const std::vector<Tensor>& in) { return capture::silhouette_loss(in[0], in[1], in[2]); };
    cases.push_back(c);
  }
  {
    GradcheckCase c;
    c.op = "arap_energy";
    c.name = case_prefix("arap") + " 4 nodes, 5 edges, 2 frames of rotations and translations";
    c.make_inputs = [](Generator& g) {
      return std::vector<Tensor>{uniform64(g, {2, 4, 3, 3}), uniform64(g, {2, 4, 3}, -0.5, 0.5)};
    };
    c.function = [terms = small_arap()](const std::vector<Tensor>& in) {
      return capture::arap_loss(terms, in[0], in[1]);
    };
    cases.push_back(c);
  }
  {
    GradcheckCase c;
    c.op = "index_select";
    c.name = case_prefix("attachment") + " 2 anchors of 4 cloth vertices on 4 body vertices, 2 frames";
    c.make_inputs = [](Generator& g) {
      return std::vector<Tensor>{uniform64(g, {2, 4, 3}), uniform64(g, {2, 4, 3})};
    };
    c.function = [terms = small_attachment()](const std::vector<Tensor>& in) {
      return capture::attachment_loss(terms, in[0], in[1]);
    };
    cases.push_back(c);
  }
  {
    GradcheckCase c;
    c.op = "mul";
    c.name = case_prefix("simulation") + " 2 frames of 5 vertices against their targets, millimetre units";
    c.make_inputs = [](Generator& g) {
      return std::vector<Tensor>{uniform64(g, {2, 5, 3}, -100, 100), uniform64(g, {2, 5, 3}, -100, 100)};
    };
    c.wrt = {0};  // the targets are the simulator's: a stop-gradient
    c.function = [](const std::vector<Tensor>& in) { return capture::simulation_loss(in[0], in[1], 1e-3); };
    cases.push_back(c);
  }
  {
    GradcheckCase c;
    c.op = "mul";
    c.name = case_prefix("heatmaps") + " heatmaps [2,3,4,5] against targets, per-heatmap confidences";
    c.make_inputs = [](Generator& g) {
      return std::vector<Tensor>{uniform64(g, {2, 3, 4, 5}, -0.2, 1), uniform64(g, {2, 3, 4, 5}, 0, 1),
                                 uniform64(g, {2, 3}, 0, 1)};
    };
    c.wrt = {0, 1};  // the confidences are the labels' (constants; they also normalise the sum)
    c.function = [](const std::vector<Tensor>& in) { return capture::heatmap_loss(in[0], in[1], in[2]); };
    cases.push_back(c);
  }
  {
    GradcheckCase c;
    c.op = "softplus";
    c.name = case_prefix("mask") + " logits [2,1,4,4] against soft masks in [0, 1]";
    c.make_inputs = [](Generator& g) {
      return std::vector<Tensor>{uniform64(g, {2, 1, 4, 4}, -4, 4), uniform64(g, {2, 1, 4, 4}, 0, 1)};
    };
    c.function = [](const std::vector<Tensor>& in) { return capture::mask_loss(in[0], in[1]); };
    cases.push_back(c);
  }
  return cases;
}

namespace {

TEST(LossTermCoverage, EveryLossTermHasAGradientCheck) {
  std::string missing;
  for (const LossTerm& t : loss_terms()) {
    bool found = false;
    for (const GradcheckCase& c : gradcheck_cases()) found |= c.name.rfind(case_prefix(t.name), 0) == 0;
    if (!found) missing += std::string(" ") + t.name;
  }
  EXPECT_TRUE(missing.empty()) << "loss terms without a \"loss term <name>:\" gradient check:" << missing;
}

TEST(LossTermCoverage, EveryLossCaseNamesATermOfTheTable) {
  for (const GradcheckCase& c : gradcheck_cases()) {
    if (c.name.rfind("loss term ", 0) != 0) continue;
    bool known = false;
    for (const LossTerm& t : loss_terms()) known |= c.name.rfind(case_prefix(t.name), 0) == 0;
    EXPECT_TRUE(known) << c.name;
  }
}

// Terms that belong to one other stage: PoseNet's lifting branch alone (pose), the person
// detector's (detector).
const char* home_stage(const LossTerm& t) {
  const std::string n = t.name;
  if (n == "virtual_landmarks") return "pose";
  if (n == "heatmaps" || n == "mask") return "detector";
  return "physics";
}

TEST(LossTermCoverage, EveryTermIsAStageWeightOfTheConfig) {
  // A physics stage that sets every term's weight parses, and each key lands in its own
  // field; a term of another stage there is an error naming it, and parses in its stage.
  std::string yaml = "stages:\n  physics: {steps: 1, batch_size: 8";
  double value = 1;
  for (const LossTerm& t : loss_terms())
    if (std::string(home_stage(t)) == "physics") yaml += ", " + std::string(t.name) + ": " + std::to_string(value++);
  yaml += "}\n";
  const capture::TrainingConfig cfg = capture::parse_training_config(yaml, "loss_terms.yaml", ".");
  const capture::StageConfig& physics = cfg.stages.at(2);
  ASSERT_EQ(physics.kind, capture::StageKind::physics);
  value = 1;
  for (const LossTerm& t : loss_terms())
    if (std::string(home_stage(t)) == "physics") EXPECT_EQ(physics.weights.*t.weight, value++) << t.name;
  for (const LossTerm& t : loss_terms()) {
    const std::string home = home_stage(t);
    if (home == "physics") continue;
    const std::string bad = "stages:\n  physics: {steps: 1, batch_size: 8, " + std::string(t.name) + ": 1}\n";
    try {
      capture::parse_training_config(bad, "loss_terms.yaml", ".");
      ADD_FAILURE() << t.name << " accepted in the physics stage";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("stages.physics.") + t.name), std::string::npos) << e.what();
    }
    const std::string good = std::string(home == "detector" ? "network: {detector: {}}\n" : "") +
                             "stages:\n  " + home + ": {steps: 1, batch_size: 8, " + t.name + ": 3}\n";
    if (home == "pose") continue;  // virtual_landmarks needs a virtual_poses section (training_config_test)
    const capture::TrainingConfig ok = capture::parse_training_config(good, "loss_terms.yaml", ".");
    EXPECT_EQ(ok.stages.at(3).weights.*t.weight, 3) << t.name;
  }
}

}  // namespace
}  // namespace weft::testing
