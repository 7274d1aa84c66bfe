// The windows of the simulation loss (capture/training/simulation_loss.h) on the coarse
// generated skirt (448 vertices) over the MakeHuman body at rest: a prediction with
// patches pushed 2 cm into the body gets a target outside it, which is what makes L_sim a
// penalty on penetration; a start with 30 % of the skirt inside converges once cleared by
// the collision-resolution pass; a window that fails keeps its converged frames; the mask
// contour of the silhouette constraint.
#include <gtest/gtest.h>

#include <memory>

#include "capture/character/default_character.h"
#include "capture/studio/cloth_perturbation.h"
#include "capture/garment/garment_simulator.h"
#include "capture/garment/garment_windows.h"
#include "geometry/mesh_io.h"
#include "capture/training/silhouette_rays.h"
#include "capture/training/pose_noise.h"
#include "capture/training/simulation_loss.h"
#include "tests/capture/coarse_skirt.h"
#include "tests/capture/shared_fixture.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::coarse_skirt;
using weft::capture::testing::repo_file;
using weft::capture::testing::skirt_pushed_into_body;

namespace {


// The training windows' simulator: the synth's garment with the default training config's Newton settings.
SynthSimulationConfig training_simulation() {
  SynthSimulationConfig s;
  s.max_iterations = 100;  // configs/train/default.yaml
  s.tolerance = 1e-2;
  return s;
}

weft::physics::BodyMesh rest_body(const Character& ch) { return body_obstacle(ch, ch.body.mesh.V * ch.metres_per_unit); }

double inside_fraction(const Character& ch, const Vertices& cloth) {
  return double(body_penetration(rest_body(ch), to_positions(cloth, ch.metres_per_unit)).vertices_inside) /
         cloth.rows();
}


// The bind-pose skirt drawn toward the body's vertical axis (anchors kept) until at least
// `fraction` of its vertices are inside the body.
Vertices shrunk_inside(const Character& ch, double fraction) {
  const Vertices& V = ch.cloth->mesh.V;
  const Eigen::RowVector3d centre = V.colwise().mean();
  std::vector<bool> anchor(V.rows(), false);
  for (int a : garment_pin_vertices(ch)) anchor[a] = true;
  for (double s = 0.98; s > 0.3; s -= 0.02) {
    Vertices out = V;
    for (int i = 0; i < V.rows(); ++i)
      if (!anchor[i]) {
        out(i, 0) = centre(0) + s * (V(i, 0) - centre(0));
        out(i, 2) = centre(2) + s * (V(i, 2) - centre(2));
      }
    if (inside_fraction(ch, out) >= fraction) return out;
  }
  ADD_FAILURE() << "no scale puts " << fraction << " of the skirt inside the body";
  return V;
}

PredictedWindow still_window(const Character& ch, const Vertices& cloth, int frames) {
  PredictedWindow w;
  for (int j = 0; j < frames; ++j) {
    w.cloth.push_back(cloth);
    w.body.push_back(ch.body.mesh.V);
  }
  return w;
}

std::vector<weft::physics::StepResult> run(const Character& ch, const weft::physics::SimulationWindow& w) {
  const auto sim = garment_simulator_factory(ch, training_simulation(), 30)();
  return weft::physics::simulate_window(*sim, w);
}

}  // namespace

TEST(SimulationLoss, TargetOfAClothInsideTheBodyLiesOutsideIt) {
  REQUIRE_HUMAN();
  const Character& ch = coarse_skirt();
  const Vertices cloth = skirt_pushed_into_body(ch);
  const double mpu = ch.metres_per_unit;
  const Penetration before = body_penetration(rest_body(ch), to_positions(cloth, mpu));
  ASSERT_GT(before.max_depth, 0.01);
  for (bool resolve_start : {true, false}) {
    SCOPED_TRACE(resolve_start ? "start cleared" : "start as predicted");
    SimulationWindowRecord rec;
    const auto w = simulation_loss_window(ch, training_simulation(), still_window(ch, cloth, 2), resolve_start, rec);
    EXPECT_EQ(w.frames, 1);
    EXPECT_EQ(rec.start_inside, before.vertices_inside);
    EXPECT_NEAR(rec.start_max_mm, before.max_depth * 1e3, 1e-9);
    const std::vector<Vertices> targets = simulation_loss_targets(run(ch, w), mpu, rec);
    ASSERT_EQ(targets.size(), 1u) << rec.status;
    const Penetration target = body_penetration(rest_body(ch), to_positions(targets[0], mpu));
    EXPECT_LE(target.max_depth, 1e-3) << target.vertices_inside << " target vertices inside";
    // The loss pulls the prediction outward: the deepest predicted vertices move out.
    double moved_out = 0;
    for (int i = 0; i < cloth.rows(); ++i)
      moved_out += (targets[0].row(i) - cloth.row(i)).norm() * mpu;
    EXPECT_GT(moved_out, 0.0);
  }
}

// The factory builds the cloth's rest state and the body's search tree once and hands out
// copies: each simulator it makes, the first and one made after it has stepped, steps to
// the same states, bit for bit, as one built from scratch.
TEST(SimulationLoss, SimulatorsFromTheFactoryStepAsOneBuiltFromScratch) {
  REQUIRE_HUMAN();
  const Character& ch = coarse_skirt();
  SimulationWindowRecord rec;
  const auto w = simulation_loss_window(ch, training_simulation(), still_window(ch, skirt_pushed_into_body(ch), 2),
                                        true, rec);
  const auto fresh = make_garment_simulator(ch, training_simulation(), 30, ch.body.mesh.V * ch.metres_per_unit,
                                            garment_pin_targets(ch, ch.cloth->mesh.V));
  const auto expected = weft::physics::simulate_window(*fresh, w);
  const weft::physics::SimulatorFactory factory = garment_simulator_factory(ch, training_simulation(), 30);
  for (int call = 0; call < 2; ++call) {
    SCOPED_TRACE(call == 0 ? "first simulator" : "second simulator");
    const auto got = weft::physics::simulate_window(*factory(), w);
    ASSERT_EQ(got.size(), expected.size());
    for (size_t f = 0; f < got.size(); ++f) {
      EXPECT_EQ(got[f].status, expected[f].status);
      EXPECT_EQ(got[f].newton_iterations, expected[f].newton_iterations);
      EXPECT_EQ(got[f].x, expected[f].x) << "frame " << f;
    }
  }
}

// The physics claim's quick check (bench/physics_claim.sh, oracle_pose_noise): the oracle
// pose perturbed as PoseNet errs moves the body into the garment the true pose dressed;
// the window's target lies outside the perturbed body, so L_sim has penetration to remove.
TEST(SimulationLoss, TargetUnderAPerturbedPoseLiesOutsideThePerturbedBody) {
  REQUIRE_HUMAN();
  const Character& ch = coarse_skirt();
  const double mpu = ch.metres_per_unit;
  Motion truth;
  truth.dofs = ch.rest_dofs.transpose().replicate(2, 1);  // the true pose: at rest, where the skirt is drawn
  truth.frame_ids = {0, 1};
  PoseNoiseConfig noise;
  noise.file = "test";
  noise.correlation_frames = 1e6;  // one error for both frames
  for (const Dof& d : ch.skeleton.dofs)
    if (d.limited && d.upper > d.lower) noise.spread.emplace_back(d.name, 0.25);
  ASSERT_FALSE(noise.spread.empty());
  // The first seed whose perturbed body holds at least 10 of the (loose) skirt's vertices, one deeper than 1 cm.
  Vertices body;
  Penetration before;
  for (noise.seed = 1; noise.seed <= 40; ++noise.seed) {
    const Motion perturbed = perturbed_motion(truth, ch.skeleton, noise);
    body = pose_character(ch, perturbed.dofs.row(0).transpose()).body;
    before = body_penetration(body_obstacle(ch, body * mpu), to_positions(ch.cloth->mesh.V, mpu));
    if (before.vertices_inside >= 10 && before.max_depth > 0.01) break;
  }
  ASSERT_LE(noise.seed, 40u) << "no seed's perturbed pose puts the skirt inside the body";
  PredictedWindow w;
  for (int j = 0; j < 2; ++j) {
    w.cloth.push_back(ch.cloth->mesh.V);
    w.body.push_back(body);
  }
  SimulationWindowRecord rec;
  const auto window = simulation_loss_window(ch, training_simulation(), w, true, rec);
  EXPECT_EQ(rec.start_inside, before.vertices_inside);
  const std::vector<Vertices> targets = simulation_loss_targets(run(ch, window), mpu, rec);
  ASSERT_EQ(targets.size(), 1u) << rec.status;
  const Penetration target = body_penetration(body_obstacle(ch, body * mpu), to_positions(targets[0], mpu));
  EXPECT_LE(target.max_depth, 1e-3) << target.vertices_inside << " of " << before.vertices_inside
                                     << " vertices still inside (seed " << noise.seed << ")";
}

TEST(SimulationLoss, StartWithAThirdOfTheSkirtInsideConvergesAfterTheCleanUp) {
  REQUIRE_HUMAN();
  const Character& ch = coarse_skirt();
  const Vertices cloth = shrunk_inside(ch, 0.3);
  SimulationWindowRecord rec;
  const auto w = simulation_loss_window(ch, training_simulation(), still_window(ch, cloth, 4), true, rec);
  EXPECT_GE(rec.start_inside, 0.3 * cloth.rows());
  EXPECT_GT(rec.cleanup_iterations, 0);
  EXPECT_LT(rec.cleaned_inside, rec.start_inside / 10) << "the clean-up left " << rec.cleaned_inside << " inside";
  const auto results = run(ch, w);
  const std::vector<Vertices> targets = simulation_loss_targets(results, ch.metres_per_unit, rec);
  EXPECT_EQ(rec.status, "converged");
  EXPECT_EQ(rec.frames_kept, 3);
  ASSERT_EQ(targets.size(), 3u);
  for (const Vertices& t : targets)
    EXPECT_LE(body_penetration(rest_body(ch), to_positions(t, ch.metres_per_unit)).max_depth, 1e-3);
}

TEST(SimulationLoss, PinsRideTheBodysSkin) {
  REQUIRE_HUMAN();
  const Character& ch = coarse_skirt();
  // On the bind-pose body: exactly the bind-pose anchors.
  const auto rest = garment_pin_targets_on_body(ch, ch.body.mesh.V);
  const auto bind = garment_pin_targets(ch, ch.cloth->mesh.V);
  ASSERT_EQ(rest.size(), bind.size());
  for (size_t i = 0; i < rest.size(); ++i) EXPECT_LT((rest[i] - bind[i]).norm(), 1e-9) << i;
  // A rigidly moved body carries them rigidly.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
  const Eigen::RowVector3d shift(0.3, -0.1, 0.25);
  Vertices moved = (ch.body.mesh.V * R.transpose()).rowwise() + shift;
  const auto carried = garment_pin_targets_on_body(ch, moved);
  for (size_t i = 0; i < rest.size(); ++i) {
    const Eigen::Vector3d expected = R * rest[i] + shift.transpose() * ch.metres_per_unit;
    EXPECT_LT((carried[i] - expected).norm(), 1e-9) << i;
  }
  weft::capture::testing::expect_error([&] { garment_pin_targets_on_body(ch, moved.topRows(10)); },
                                       {"10 body vertices"});
}

TEST(SimulationLoss, AWindowThatFailsKeepsItsConvergedFrames) {
  std::vector<weft::physics::StepResult> results(3);
  for (auto& r : results) r.x = weft::physics::Positions::Constant(6, 0.5);
  results[1].status = weft::physics::StepStatus::max_iterations;
  SimulationWindowRecord rec;
  const auto targets = simulation_loss_targets(results, 0.5, rec);
  ASSERT_EQ(targets.size(), 1u);
  EXPECT_EQ(rec.frames_kept, 1);
  EXPECT_EQ(rec.status, "max_iterations");
  EXPECT_DOUBLE_EQ(targets[0](1, 2), 1.0);  // metres → character units
  results[1].status = weft::physics::StepStatus::converged;
  results[0].x[4] = std::nan("");
  EXPECT_TRUE(simulation_loss_targets(results, 0.5, rec).empty());
  EXPECT_EQ(rec.status, "non_finite");
}

TEST(SimulationLoss, WindowErrorsNameWhatIsWrong) {
  REQUIRE_HUMAN();
  const Character& ch = coarse_skirt();
  SimulationWindowRecord rec;
  PredictedWindow one = still_window(ch, ch.cloth->mesh.V, 1);
  weft::capture::testing::expect_error(
      [&] { simulation_loss_window(ch, training_simulation(), one, true, rec); }, {"at least 2"});
  PredictedWindow uneven = still_window(ch, ch.cloth->mesh.V, 3);
  uneven.body.pop_back();
  weft::capture::testing::expect_error(
      [&] { simulation_loss_window(ch, training_simulation(), uneven, true, rec); }, {"2 bodies for 3"});
}

// On the tiny dataset's ground truth, whose meshes made the masks, E_cons is nearly
// satisfied already: every ray starts at one of the cameras, belongs to a garment vertex
// on the silhouette in front of it, and passes within about a pixel of it (the contour
// is quantised to the silhouette images' pixels: about 3 cm at the person at 64²).
TEST(SilhouetteRays, GroundTruthGarmentLiesOnItsRays) {
  REQUIRE_HUMAN();
  const auto data = weft::capture::testing::tiny_dataset();
  const DatasetInfo info = read_dataset_info(data.string());
  const Character ch = load_character(info.character);
  const int frame = 2;
  const MultiviewSupervision sup(info, {frame}, 64);
  const Vertices body = read_ply((data / "gt" / "body_0002.ply").string()).V;
  const Vertices cloth = read_ply((data / "gt" / "cloth_0002.ply").string()).V;
  Faces faces(ch.body.mesh.F.rows() + ch.cloth->mesh.F.rows(), 3);
  faces << ch.body.mesh.F, (ch.cloth->mesh.F.array() + int(body.rows())).matrix();
  SilhouetteRayOptions o;
  o.metres_per_unit = ch.metres_per_unit;
  const std::vector<weft::physics::RayTarget> rays = silhouette_rays(sup, frame, body, cloth, faces, o);
  // At 64² the silhouette's visibility test keeps few garment vertices (10 on this frame).
  ASSERT_GE(rays.size(), 5u);
  std::vector<double> miss_px;
  for (const auto& r : rays) {
    ASSERT_GE(r.vertex, 0);
    ASSERT_LT(r.vertex, cloth.rows());
    EXPECT_NEAR(r.direction.norm(), 1.0, 1e-9);
    int view = -1;
    for (int v = 0; v < sup.views(); ++v)
      if ((r.origin - sup.silhouette_camera(frame, v).center() * ch.metres_per_unit).norm() < 1e-9) view = v;
    ASSERT_GE(view, 0) << "a ray that starts at no camera";
    const Eigen::Vector3d x = cloth.row(r.vertex).transpose() * ch.metres_per_unit;
    const Eigen::Vector3d d = x - r.origin;
    ASSERT_GT(d.dot(r.direction), 0.0) << "the vertex lies in front of its camera";
    const double pixel_m = d.dot(r.direction) / sup.silhouette_camera(frame, view).K(0, 0);
    miss_px.push_back((d - d.dot(r.direction) * r.direction).norm() / pixel_m);
  }
  std::sort(miss_px.begin(), miss_px.end());
  EXPECT_LT(miss_px[miss_px.size() / 2], 1.5) << "median distance of a vertex to its ray, in pixels";
  EXPECT_LT(miss_px.back(), o.max_pixels + 1.0);
  // A contour within 0 pixels: almost no vertex projects exactly onto a pixel centre.
  o.max_pixels = 0;
  EXPECT_LT(silhouette_rays(sup, frame, body, cloth, faces, o).size(), rays.size() / 4 + 1);
}

TEST(SilhouetteRays, MaskContourIsTheForegroundsBorder) {
  cv::Mat mask = cv::Mat::zeros(8, 10, CV_8UC1);
  mask(cv::Rect(2, 3, 4, 3)).setTo(255);  // x 2..5, y 3..5
  const auto contour = mask_contour(mask);
  EXPECT_EQ(contour.size(), 10u);  // a 4 × 3 block: all but its 2 inner pixels
  for (const auto& p : contour) {
    EXPECT_EQ(mask.at<uint8_t>(int(p.y()), int(p.x())), 255);
    EXPECT_TRUE(p.x() == 2 || p.x() == 5 || p.y() == 3 || p.y() == 5) << p.transpose();
  }
  mask.setTo(255);  // foreground to the image's edge: the edge is the contour
  EXPECT_EQ(mask_contour(mask).size(), size_t(2 * 10 + 2 * 6));
}
