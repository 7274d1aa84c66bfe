#include "capture/garment/garment_windows.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "capture/garment/garment_simulator.h"
#include "geometry/mesh_io.h"
#include "capture/character/skeletool_io.h"
#include "capture/dataset/synthetic_dataset.h"
#include "graph/error.h"

namespace weft::capture {

namespace fs = std::filesystem;

namespace {

std::string gt_file(const std::string& dir, const char* kind, int frame) {
  return (fs::path(dir) / "gt" / (std::string(kind) + "_" + dataset_frame_name(frame) + ".ply")).string();
}

}  // namespace

Eigen::MatrixX3d GarmentSequence::body(int frame) const {
  WEFT_CHECK(frame >= 0 && frame < frames, dir, ": body frame ", frame, " outside [0, ", frames, ")");
  const std::string path = gt_file(dir, "body", frame);
  const TriangleMesh m = read_ply(path);
  WEFT_CHECK(m.num_vertices() == character.body.mesh.num_vertices(), path, ": ", m.num_vertices(),
             " vertices, the character's body has ", character.body.mesh.num_vertices());
  return Eigen::MatrixX3d(m.V * character.metres_per_unit);
}

physics::SimulatorFactory GarmentSequence::simulator_factory() const {
  return garment_simulator_factory(character, simulation, fps);
}

GarmentSequence load_garment_sequence(const std::string& dataset_dir) {
  const DatasetInfo info = read_dataset_info(dataset_dir);
  const SynthSimulationConfig simulation = read_dataset_simulation(dataset_dir);
  WEFT_CHECK(simulation.enabled, dataset_dir, "/dataset.yaml: simulation.enabled is false: the dataset's garment is skinned");
  GarmentSequence s;
  s.dir = dataset_dir;
  s.character = load_character(info.character);
  WEFT_CHECK(s.character.has_cloth(), info.character, ": the character has no garment");
  s.simulation = simulation;
  s.fps = info.fps;
  s.frames = info.frames;
  s.failed_frames = info.failed_frames;
  s.segments = info.segments;
  const Motion motion = read_motion((fs::path(dataset_dir) / "gt" / "pose.motion").string(),
                                    static_cast<int>(s.character.rest_dofs.size()));
  WEFT_CHECK(motion.num_frames() == s.frames, dataset_dir, "/gt/pose.motion: ", motion.num_frames(),
             " frames, dataset.yaml says ", s.frames);
  const double mpu = s.character.metres_per_unit;
  for (int f = 0; f < s.frames; ++f) {
    const std::string path = gt_file(dataset_dir, "cloth", f);
    const TriangleMesh m = read_ply(path);
    WEFT_CHECK(m.num_vertices() == s.character.cloth->mesh.num_vertices(), path, ": ", m.num_vertices(),
               " vertices, the character's garment has ", s.character.cloth->mesh.num_vertices());
    s.cloth.push_back(to_positions(m.V, mpu));
    const PosedCharacter posed = pose_character(s.character, motion.dofs.row(f).transpose());
    s.pin_targets.push_back(garment_pin_targets(s.character, posed.cloth));
  }
  return s;
}

physics::SimulationWindow garment_window(const GarmentSequence& s, int start, int frames,
                                         physics::Positions x_prev2, physics::Positions x_prev) {
  WEFT_CHECK(frames >= 1 && start >= 0 && start + frames < s.frames, s.dir, ": a window of ", frames,
             " frames after frame ", start, " does not fit in ", s.frames, " frames");
  // The ground truth's garment restarts at each clip's first frame: no window crosses one.
  const auto next_clip = std::upper_bound(s.segments.begin(), s.segments.end(), start);
  WEFT_CHECK(next_clip == s.segments.end() || *next_clip > start + frames, s.dir, ": a window of ", frames,
             " frames after frame ", start, " crosses the clip starting at frame ",
             next_clip == s.segments.end() ? 0 : *next_clip, " (dataset.yaml segments)");
  physics::SimulationWindow w;
  w.x_prev2 = std::move(x_prev2);
  w.x_prev = std::move(x_prev);
  w.frames = frames;
  for (int f = start; f <= start + frames; ++f) w.body.push_back(s.body(f));
  w.pin_vertices = garment_pin_vertices(s.character);
  for (int f = start + 1; f <= start + frames; ++f) w.pin_targets.push_back(s.pin_targets[f]);
  return w;
}

Penetration body_penetration(const physics::BodyMesh& body, const physics::Positions& x, double contact_distance) {
  Penetration p;
  for (int i = 0; i < x.size() / 3; ++i) {
    const physics::ClosestPoint c = body.closest_point(x.segment<3>(3 * i));
    if (c.face >= 0 && c.distance < 0) {
      p.max_depth = std::max(p.max_depth, -c.distance);
      p.depth_sum -= c.distance;
      ++p.vertices_inside;
    } else if (c.face >= 0 && c.distance < contact_distance) {
      ++p.vertices_in_contact;
    }
  }
  return p;
}

physics::BodyMesh collision_body(const GarmentSequence& s, int frame) { return body_obstacle(s.character, s.body(frame)); }

}  // namespace weft::capture
