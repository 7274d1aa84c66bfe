#include "physics/scene.h"


#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>

#include "files/strict_yaml.h"
#include "files/text_reader.h"
#include "geometry/mesh_io.h"
#include "graph/atomic_file.h"
#include "graph/error.h"
#include "physics/cloth_material_yaml.h"

namespace weft::physics {

namespace fs = std::filesystem;

namespace {

// One YAML mapping of the scene, read through the strict reader (files/strict_yaml.h): unknown
// keys and wrong types name the file, the line and the key; the value checks below name the
// file and the key.
class Section {
 public:
  Section(const StrictYaml& yaml, const YAML::Node& node, std::string prefix)
      : y_(yaml), node_(node), prefix_(std::move(prefix)) {
    if (!node_.IsMap()) y_.fail_at(node_, prefix_.empty() ? "(top level)" : prefix_, "must be a mapping");
  }
  void allow(std::initializer_list<const char*> keys) { y_.check_keys(node_, prefix_, keys); }
  bool has(const char* k) const { return static_cast<bool>(node_[k]); }
  std::string key(const std::string& k) const { return prefix_.empty() ? k : prefix_ + "." + k; }
  YAML::Node node(const char* k) const { return node_[k]; }

  template <class T>
  T get(const char* k, const char* expected) const {
    const YAML::Node n = node_[k];
    if (!n) y_.fail_at(node_, key(k), "missing key");
    return convert<T>(n, key(k), expected);
  }
  template <class T>
  T get_or(const char* k, T fallback, const char* expected) const {
    return has(k) ? get<T>(k, expected) : fallback;
  }
  double number_or(const char* k, double fallback) const {
    return get_or<double>(k, fallback, "a number");
  }
  double positive(const char* k, double fallback) const {
    const double v = number_or(k, fallback);
    WEFT_CHECK(std::isfinite(v) && v > 0, y_.file, ": '", key(k), "' must be > 0, got ", v);
    return v;
  }
  Eigen::VectorXd vector(const char* k, int size) const {
    const YAML::Node n = node_[k];
    if (!n) y_.fail_at(node_, key(k), "missing key");
    if (!n.IsSequence() || static_cast<int>(n.size()) != size)
      y_.fail_at(n, key(k), "must be a list of " + std::to_string(size) + " numbers");
    Eigen::VectorXd v(size);
    for (int i = 0; i < size; ++i) v[i] = convert<double>(n[i], key(k), "a number");
    if (!v.allFinite()) y_.fail_at(n, key(k), "must be finite");
    return v;
  }

  template <class T>
  T convert(const YAML::Node& n, const std::string& k, const char* expected) const {
    if (!n.IsScalar()) y_.fail_at(n, k, std::string("must be ") + expected);
    try {
      return n.as<T>();
    } catch (const YAML::Exception&) {
      y_.fail_at(n, k, std::string("must be ") + expected + ", got '" + n.Scalar() + "'");
    }
  }

 private:
  const StrictYaml& y_;
  YAML::Node node_;
  std::string prefix_;
};

// The floor's meshes (geometry/mesh.h) as the simulator's arrays: 3n positions (metres) and
// triangles.
Positions positions_of(const TriangleMesh& m) {
  return Eigen::Map<const Positions>(m.V.data(), 3 * m.V.rows());
}
std::vector<std::array<int, 3>> triangles_of(const TriangleMesh& m) {
  std::vector<std::array<int, 3>> t(m.F.rows());
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) t[f] = {m.F(f, 0), m.F(f, 1), m.F(f, 2)};
  return t;
}

std::string resolve(const std::string& scene_file, const std::string& relative) {
  const fs::path p(relative);
  return p.is_absolute() ? p.string() : (fs::path(scene_file).parent_path() / p).string();
}

std::vector<int> read_face_list(const std::string& path, const std::string& scene_file,
                                const std::string& key) {
  std::ifstream in(path);
  WEFT_CHECK(in.good(), scene_file, ": '", key, "': cannot open '", path, "'");
  std::vector<int> faces;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    line = line.substr(0, line.find('#'));
    std::istringstream ls(line);
    std::string tok;
    while (ls >> tok) {
      try {
        size_t used = 0;
        const int f = std::stoi(tok, &used);
        WEFT_CHECK(used == tok.size() && f >= 0, path, ":", line_no, ": bad face index '", tok, "'");
        faces.push_back(f);
      } catch (const std::logic_error&) {
        fail(path, ":", line_no, ": bad face index '", tok, "'");
      }
    }
  }
  return faces;
}

}  // namespace

std::string sequence_path(const std::string& pattern, int frame) {
  static const std::regex spec("%(0?[0-9]*)d");
  std::smatch m;
  WEFT_CHECK(std::regex_search(pattern, m, spec) &&
                 std::count(pattern.begin(), pattern.end(), '%') == 1,
             "mesh sequence pattern '", pattern, "' must contain exactly one %d or %0Nd");
  char buf[64];
  std::snprintf(buf, sizeof(buf), ("%" + m[1].str() + "d").c_str(), frame);
  return m.prefix().str() + buf + m.suffix().str();
}

namespace {

// The top level's time step, frame count, sub-steps and gravity.
void read_timing(const Section& top, Scene& scene) {
  const std::string& path = scene.file;
  SimulationSettings& s = scene.settings;
  s.time_step = top.positive("time_step", s.time_step);
  scene.frames = top.get_or<int>("frames", scene.frames, "an integer");
  WEFT_CHECK(scene.frames >= 1, path, ": 'frames' must be >= 1, got ", scene.frames);
  s.substeps = top.get_or<int>("substeps", 1, "an integer");
  WEFT_CHECK(s.substeps >= 1, path, ": 'substeps' must be >= 1, got ", s.substeps);
  if (top.has("gravity")) s.gravity = top.vector("gravity", 3);
}

// The cloth's rest shape: a generated grid or an OBJ mesh, with the material's density.
void read_cloth_shape(const StrictYaml& yaml, const Section& cloth, Scene& scene) {
  const std::string& path = scene.file;
  const double density = scene.settings.material.density;
  if (cloth.has("grid")) {
    Section grid(yaml, cloth.node("grid"), "cloth.grid");
    grid.allow({"size", "resolution", "origin", "plane"});
    const Eigen::VectorXd size = grid.vector("size", 2);
    const Eigen::VectorXd res = grid.vector("resolution", 2);
    WEFT_CHECK(size.minCoeff() > 0, path, ": 'cloth.grid.size' must be positive");
    WEFT_CHECK(res.minCoeff() >= 2 && res == res.array().round().matrix() && res.maxCoeff() < 5000,
               path, ": 'cloth.grid.resolution' must be two integers in [2, 5000)");
    const Eigen::VectorXd origin = grid.has("origin") ? grid.vector("origin", 3) : Eigen::VectorXd::Zero(3);
    const std::string plane = grid.get_or<std::string>("plane", "xz", "a string");
    WEFT_CHECK(plane == "xy" || plane == "xz" || plane == "yz", path,
               ": 'cloth.grid.plane' must be xy, xz or yz, got '", plane, "'");
    scene.cloth = make_grid_cloth(Vec3(origin), size[0], size[1], static_cast<int>(res[0]),
                                  static_cast<int>(res[1]), plane.c_str(), density);
  } else {
    const std::string file = resolve(path, cloth.get<std::string>("mesh", "a file path"));
    WEFT_CHECK(fs::exists(file), path, ": 'cloth.mesh': file not found: ", file);
    const TriangleMesh m = read_obj(file);
    scene.cloth = make_cloth_mesh(positions_of(m), triangles_of(m), density);
  }
}

// The cloth's starting positions and previous positions: the rest shape unless 'initial' gives
// OBJ files.
void read_initial_state(const StrictYaml& yaml, const Section& cloth, Scene& scene) {
  const std::string& path = scene.file;
  scene.initial = scene.initial_previous = scene.cloth.rest;
  if (!cloth.has("initial")) return;
  // Any state, as network predictions are: stretched, compressed, inside an obstacle.
  Section init(yaml, cloth.node("initial"), "cloth.initial");
  init.allow({"positions", "previous"});
  auto read_state = [&](const char* k) {
    const std::string key = init.key(k);
    const std::string file = resolve(path, init.get<std::string>(k, "a file path"));
    WEFT_CHECK(fs::exists(file), path, ": '", key, "': file not found: ", file);
    const TriangleMesh m = read_obj(file);
    WEFT_CHECK(m.num_vertices() == scene.cloth.num_vertices(), path, ": '", key, "': ", file, " has ",
               m.num_vertices(), " vertices, the cloth has ", scene.cloth.num_vertices());
    return positions_of(m);
  };
  scene.initial = read_state("positions");
  scene.initial_previous = init.has("previous") ? read_state("previous") : scene.initial;
}

// The pinned cloth vertices, checked against the cloth's vertex count.
void read_pins(const Section& cloth, Scene& scene) {
  const std::string& path = scene.file;
  if (!cloth.has("pins")) return;
  const YAML::Node pins = cloth.node("pins");
  WEFT_CHECK(pins.IsSequence(), path, ": 'cloth.pins' must be a list of vertex ids");
  for (size_t k = 0; k < pins.size(); ++k) {
    const int id = cloth.convert<int>(pins[k], "cloth.pins", "a list of integer vertex ids");
    WEFT_CHECK(id >= 0 && id < scene.cloth.num_vertices(), path, ": 'cloth.pins': vertex ", id,
               " outside [0, ", scene.cloth.num_vertices(), ")");
    scene.pins.push_back(id);
  }
}

// The 'cloth' section: material, pin stiffness, shape, initial state and pins.
void read_cloth(const StrictYaml& yaml, const Section& top, Scene& scene) {
  const std::string& path = scene.file;
  SimulationSettings& s = scene.settings;
  WEFT_CHECK(top.has("cloth"), path, ": missing key 'cloth'");
  Section cloth(yaml, top.node("cloth"), "cloth");
  cloth.allow({"grid", "mesh", "material", "pins", "pin_stiffness", "initial"});
  if (cloth.has("material")) read_cloth_material(yaml, cloth.node("material"), "cloth.material", s.material);
  s.pin_stiffness = cloth.positive("pin_stiffness", s.pin_stiffness);
  WEFT_CHECK(cloth.has("grid") != cloth.has("mesh"), path,
             ": 'cloth' needs exactly one of 'grid' or 'mesh'");
  read_cloth_shape(yaml, cloth, scene);
  read_initial_state(yaml, cloth, scene);
  read_pins(cloth, scene);
}

// One entry of 'obstacles': a sphere, a mesh or a mesh sequence (whose frames 0..frames must
// all exist), with its friction and inactive faces. `sequences` counts the mesh sequences so far.
SceneObstacle read_obstacle(const StrictYaml& yaml, const YAML::Node& node, size_t k,
                            const Scene& scene, int& sequences) {
  const std::string& path = scene.file;
  const std::string prefix = "obstacles[" + std::to_string(k) + "]";
  Section o(yaml, node, prefix);
  o.allow({"sphere", "mesh", "mesh_sequence", "inactive_faces", "friction"});
  SceneObstacle ob;
  ob.friction = o.number_or("friction", ob.friction);
  WEFT_CHECK(std::isfinite(ob.friction) && ob.friction >= 0, path, ": '", o.key("friction"),
             "' must be >= 0, got ", ob.friction);
  const int kinds = o.has("sphere") + o.has("mesh") + o.has("mesh_sequence");
  WEFT_CHECK(kinds == 1, path, ": '", prefix, "' needs exactly one of sphere, mesh, mesh_sequence");
  if (o.has("sphere")) {
    Section sp(yaml, o.node("sphere"), prefix + ".sphere");
    sp.allow({"center", "radius"});
    ob.kind = SceneObstacle::Kind::sphere;
    ob.sphere.center = sp.vector("center", 3);
    ob.sphere.radius = sp.positive("radius", 0);
    ob.sphere.friction = ob.friction;
    WEFT_CHECK(!o.has("inactive_faces"), path, ": '", prefix, ".inactive_faces' applies to meshes only");
  } else if (o.has("mesh")) {
    ob.kind = SceneObstacle::Kind::mesh;
    ob.path = resolve(path, o.get<std::string>("mesh", "a file path"));
    WEFT_CHECK(fs::exists(ob.path), path, ": '", prefix, ".mesh': file not found: ", ob.path);
  } else {
    ob.kind = SceneObstacle::Kind::mesh_sequence;
    WEFT_CHECK(++sequences == 1, path, ": '", prefix, "': at most one mesh_sequence per scene");
    ob.path = resolve(path, o.get<std::string>("mesh_sequence", "a file pattern"));
    for (int f = 0; f <= scene.frames; ++f) {
      const std::string p = sequence_path(ob.path, f);
      WEFT_CHECK(fs::exists(p), path, ": '", prefix, ".mesh_sequence': frame ", f,
                 " not found: ", p, " (frames 0..", scene.frames, " are needed)");
    }
  }
  if (o.has("inactive_faces"))
    ob.inactive_faces = read_face_list(
        resolve(path, o.get<std::string>("inactive_faces", "a file path")), path,
        prefix + ".inactive_faces");
  return ob;
}

// The 'obstacles' list, if any.
void read_obstacles(const StrictYaml& yaml, const Section& top, Scene& scene) {
  if (!top.has("obstacles")) return;
  const YAML::Node list = top.node("obstacles");
  WEFT_CHECK(list.IsSequence(), scene.file, ": 'obstacles' must be a list");
  int sequences = 0;
  for (size_t k = 0; k < list.size(); ++k)
    scene.obstacles.push_back(read_obstacle(yaml, list[k], k, scene, sequences));
}

// The 'collision' section, if any: thickness, stiffness and friction velocity.
void read_collision(const StrictYaml& yaml, const Section& top, SimulationSettings& s) {
  if (!top.has("collision")) return;
  Section c(yaml, top.node("collision"), "collision");
  c.allow({"thickness", "stiffness", "friction_velocity"});
  s.collision_thickness = c.positive("thickness", s.collision_thickness);
  s.collision_stiffness = c.positive("stiffness", s.collision_stiffness);
  s.friction_velocity = c.positive("friction_velocity", s.friction_velocity);
}

// The 'solver' section, if any: Newton's iterations and tolerance, the linear solver and the
// Cholesky kind.
void read_solver(const StrictYaml& yaml, const Section& top, SimulationSettings& s) {
  if (!top.has("solver")) return;
  const std::string& path = yaml.file;
  Section sv(yaml, top.node("solver"), "solver");
  sv.allow({"max_iterations", "tolerance", "linear_solver", "cholesky"});
  s.newton.max_iterations = sv.get_or<int>("max_iterations", s.newton.max_iterations, "an integer");
  WEFT_CHECK(s.newton.max_iterations >= 1, path, ": 'solver.max_iterations' must be >= 1");
  s.newton.tolerance = sv.positive("tolerance", s.newton.tolerance);
  const std::string ls = sv.get_or<std::string>("linear_solver", "direct", "a string");
  WEFT_CHECK(ls == "direct" || ls == "reused_factor", path,
             ": 'solver.linear_solver' must be direct or reused_factor, got '", ls, "'");
  s.newton.linear_solver = ls == "direct" ? LinearSolverKind::direct : LinearSolverKind::reused_factor;
  const std::string ch = sv.get_or<std::string>("cholesky", "automatic", "a string");
  WEFT_CHECK(ch == "automatic" || ch == "simplicial" || ch == "supernodal", path,
             ": 'solver.cholesky' must be automatic, simplicial or supernodal, got '", ch, "'");
  s.newton.cholesky = ch == "simplicial"   ? CholeskyKind::simplicial
                      : ch == "supernodal" ? CholeskyKind::supernodal
                                           : CholeskyKind::automatic;
}

}  // namespace

Scene load_scene(const std::string& path) {
  WEFT_CHECK(fs::exists(path), path, ": scene file not found");
  StrictYaml yaml;
  yaml.file = path;
  yaml.dir = fs::path(path).parent_path();
  const YAML::Node root = yaml.parse(read_file_bytes(path));
  Scene scene;
  scene.file = path;
  Section top(yaml, root, "");
  top.allow({"time_step", "frames", "substeps", "gravity", "cloth", "obstacles", "collision",
             "solver"});
  read_timing(top, scene);
  read_cloth(yaml, top, scene);
  read_obstacles(yaml, top, scene);
  read_collision(yaml, top, scene.settings);
  read_solver(yaml, top, scene.settings);
  validate(scene.settings);
  return scene;
}

namespace {

BodyMesh load_body(const std::string& file, const std::vector<int>& inactive) {
  const TriangleMesh m = read_obj(file);
  for (int f : inactive)
    WEFT_CHECK(f < m.num_faces(), file, ": inactive face ", f, " outside [0, ", m.num_faces(), ")");
  return BodyMesh(m.V, triangles_of(m), inactive);
}

// One frame of the cloth as an OBJ (the floor's writer: atomic, shortest round-trip numbers).
void write_cloth_obj(const std::string& file, const Positions& x, const Faces& faces) {
  TriangleMesh m;
  m.V = Eigen::Map<const Vertices>(x.data(), x.size() / 3, 3);
  m.F = faces;
  write_obj(file, m);
}

// JSON has no infinity: a distance with no obstacle to measure against is null.
nlohmann::json finite_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

}  // namespace

nlohmann::json frame_record_json(const FrameRecord& rec, bool with_timing) {
  const FrameMetrics& m = rec.metrics;
  nlohmann::json j = {{"frame", rec.frame},
                      {"status", to_string(rec.status)},
                      {"newton_iterations", rec.newton_iterations},
                      {"gradient_norm", rec.gradient_norm},
                      {"energy", rec.energy},
                      {"min_signed_distance", finite_or_null(m.min_signed_distance)},
                      {"penetration_mean", m.penetration_mean},
                      {"penetration_max", m.penetration_max},
                      {"oob_force_mean", m.oob_force_mean},
                      {"oob_force_max", m.oob_force_max},
                      {"oob_force_mean_rel", m.oob_force_mean_rel},
                      {"oob_force_max_rel", m.oob_force_max_rel}};
  if (with_timing) j["step_ms"] = rec.step_ms;
  return j;
}

SceneRun run_scene(const Scene& scene, const std::string& out_dir,
                   const std::function<void(const FrameRecord&)>& progress) {
  ClothSimulator sim(scene.cloth, scene.settings);
  sim.set_pins(scene.pins);
  std::vector<SphereObstacle> spheres;
  const SceneObstacle* sequence = nullptr;
  for (const auto& o : scene.obstacles) {
    if (o.kind == SceneObstacle::Kind::sphere) spheres.push_back(o.sphere);
    if (o.kind == SceneObstacle::Kind::mesh_sequence) sequence = &o;
  }
  sim.set_spheres(spheres);
  // The moving body goes first: the simulator's step() moves body 0.
  if (sequence)
    sim.add_body(load_body(sequence_path(sequence->path, 0), sequence->inactive_faces),
                 sequence->friction);
  for (const auto& o : scene.obstacles)
    if (o.kind == SceneObstacle::Kind::mesh) sim.add_body(load_body(o.path, o.inactive_faces), o.friction);

  if (!out_dir.empty()) {
    std::error_code ec;
    fs::create_directories(out_dir, ec);
    WEFT_CHECK(!ec && fs::is_directory(out_dir), out_dir, ": cannot create the output directory");
  }
  auto obj_path = [&](int f) {
    char name[32];
    std::snprintf(name, sizeof(name), "cloth_%04d.obj", f);
    return (fs::path(out_dir) / name).string();
  };
  Faces tris(static_cast<Eigen::Index>(scene.cloth.triangles.size()), 3);
  for (size_t t = 0; t < scene.cloth.triangles.size(); ++t)
    tris.row(static_cast<Eigen::Index>(t)) << scene.cloth.triangles[t][0], scene.cloth.triangles[t][1],
        scene.cloth.triangles[t][2];
  if (!out_dir.empty()) write_cloth_obj(obj_path(0), scene.initial, tris);

  SceneRun run;
  const double h = scene.settings.time_step;
  Positions x2 = scene.initial_previous, x1 = scene.initial;
  Eigen::MatrixX3d body_prev, body_now;
  if (sequence) body_prev = sim.body(0).vertices();
  for (int f = 1; f <= scene.frames; ++f) {
    StepResult r;
    if (sequence) {
      const std::string file = sequence_path(sequence->path, f);
      const TriangleMesh m = read_obj(file);
      WEFT_CHECK(m.V.rows() == body_prev.rows(), file, ": ", m.V.rows(),
                 " vertices, but frame 0 of the sequence has ", body_prev.rows());
      body_now = m.V;
      r = sim.step(x2, x1, &body_prev, &body_now);
      body_prev = body_now;
    } else {
      r = sim.step(x2, x1);
    }
    FrameRecord rec;
    rec.frame = f;
    rec.status = r.status;
    rec.newton_iterations = r.newton_iterations;
    rec.gradient_norm = r.gradient_norm;
    rec.energy = r.energy;
    rec.step_ms = r.step_ms;
    rec.metrics = frame_metrics(sim, x2, x1, r.x, h);
    if (!out_dir.empty()) write_cloth_obj(obj_path(f), r.x, tris);
    x2 = std::move(x1);
    x1 = std::move(r.x);
    if (progress) progress(rec);
    run.frames.push_back(rec);
  }

  // metrics.json
  nlohmann::json frames = nlohmann::json::array();
  std::vector<double> ms;
  int converged = 0, iterations = 0;
  double pen_max = 0, min_d = std::numeric_limits<double>::infinity(), oob_mean = 0, oob_max = 0;
  double oob_mean_rel = 0, oob_max_rel = 0;
  for (const auto& rec : run.frames) {
    const FrameMetrics& m = rec.metrics;
    frames.push_back(frame_record_json(rec));
    ms.push_back(rec.step_ms);
    converged += rec.status == StepStatus::converged;
    iterations += rec.newton_iterations;
    pen_max = std::max(pen_max, m.penetration_max);
    min_d = std::min(min_d, m.min_signed_distance);
    oob_mean += m.oob_force_mean / run.frames.size();
    oob_mean_rel += m.oob_force_mean_rel / run.frames.size();
    oob_max = std::max(oob_max, m.oob_force_max);
    oob_max_rel = std::max(oob_max_rel, m.oob_force_max_rel);
  }
  std::vector<double> sorted = ms;
  std::sort(sorted.begin(), sorted.end());
  double total_ms = 0;
  for (double v : ms) total_ms += v;
  nlohmann::json summary = {
      {"scene", scene.file},
      {"vertices", scene.cloth.num_vertices()},
      {"triangles", scene.cloth.triangles.size()},
      {"frames", run.frames.size()},
      {"time_step", h},
      {"substeps", scene.settings.substeps},
      {"converged_frames", converged},
      {"newton_iterations_total", iterations},
      {"newton_iterations_mean", static_cast<double>(iterations) / run.frames.size()},
      {"step_ms_median", sorted[sorted.size() / 2]},
      {"step_ms_mean", total_ms / ms.size()},
      {"step_ms_total", total_ms},
      {"penetration_max", pen_max},
      {"min_signed_distance", finite_or_null(min_d)},
      {"oob_force_mean", oob_mean},
      {"oob_force_max", oob_max},
      {"oob_force_mean_rel", oob_mean_rel},
      {"oob_force_max_rel", oob_max_rel}};
  const nlohmann::json doc = {{"frames", frames}, {"summary", summary}};
  run.metrics_json = doc.dump(2);
  if (!out_dir.empty()) write_text_atomically((fs::path(out_dir) / "metrics.json").string(), run.metrics_json);
  return run;
}

}  // namespace weft::physics
