#include "capture/training/pose_noise.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "capture/io/portable_random.h"
#include "files/text_reader.h"
#include "graph/error.h"

namespace weft::capture {

namespace fs = std::filesystem;

namespace {

constexpr uint64_t kPoseNoiseStream = 0x706f73656e6f6973ull;  // "posenois"

PoseNoiseConfig parse_mapping(const StrictYaml& y, const YAML::Node& n, const std::string& key) {
  if (!n.IsMap()) y.fail_at(n, key, "expected a mapping (seed, scale, correlation_frames, spread) or a file holding one");
  PoseNoiseConfig c;
  c.file = y.file;
  const std::string where = key + ".";
  y.numbers(n, where, {{"scale", &c.scale, 0, 100}, {"correlation_frames", &c.correlation_frames, 1e-3, 1e6}}, {},
            {"seed", "spread", "bias"});
  if (n["seed"]) c.seed = y.get<uint64_t>(n["seed"], where + "seed", "a non-negative integer");
  if (!n["spread"] && !n["bias"])
    y.fail_at(n, where + "spread", "missing: the standard deviation of each perturbed dof (dof name: value), or a bias");
  const auto read = [&](const char* key, double lo, auto& out) {
    const YAML::Node s = n[key];
    if (!s) return;
    if (!s.IsMap() || s.size() == 0)
      y.fail_at(s, where + key, "expected a non-empty mapping of dof names to values (radians or character units)");
    for (const auto& kv : s) {
      const std::string name = y.get<std::string>(kv.first, where + key, "a dof name");
      out.emplace_back(name, y.number(kv.second, where + key + "." + name, lo, 10));
    }
  };
  read("spread", 0, c.spread);
  read("bias", -10, c.bias);
  return c;
}

}  // namespace

PoseNoiseConfig parse_pose_noise(const StrictYaml& y, const YAML::Node& node, const std::string& key) {
  if (!node.IsScalar()) return parse_mapping(y, node, key);
  const std::string path = y.path(node, key);
  StrictYaml inner;
  inner.file = path;
  inner.dir = fs::path(path).parent_path();
  return parse_mapping(inner, inner.parse(read_file_bytes(path)), key);
}

Motion perturbed_motion(const Motion& truth, const Skeleton& skeleton, const PoseNoiseConfig& config) {
  const auto dof_of = [&](const std::string& key, const std::string& name) {
    const int d = skeleton.dof_index(name);
    WEFT_CHECK(d >= 0, config.file, ": oracle_pose_noise.", key, " names the dof '", name,
               "', which the character's skeleton does not have");
    WEFT_CHECK(d < truth.dofs.cols(), "oracle_pose_noise: the motion has ", truth.dofs.cols(), " dofs, the dof '", name,
               "' is number ", d);
    return d;
  };
  Eigen::MatrixXd error = Eigen::MatrixXd::Zero(truth.num_frames(), truth.dofs.cols());
  std::vector<bool> listed(size_t(truth.dofs.cols()), false);
  for (const auto& [name, b] : config.bias) {
    const int d = dof_of("bias", name);
    error.col(d).array() += b * config.scale;
    listed[size_t(d)] = true;
  }
  const double rho = std::exp(-1.0 / config.correlation_frames);
  const double innovation = std::sqrt(std::max(0.0, 1.0 - rho * rho));
  for (const auto& [name, sigma_raw] : config.spread) {
    const int d = dof_of("spread", name);
    const double sigma = sigma_raw * config.scale;
    PortableRandom rng(mix_seed(config.seed, kPoseNoiseStream, static_cast<uint64_t>(d)));
    double e = 0;
    for (int f = 0; f < truth.num_frames(); ++f) {
      const double n = rng.gaussian();
      e = f == 0 ? sigma * n : rho * e + sigma * innovation * n;
      error(f, d) += e;
    }
    listed[size_t(d)] = true;
  }
  Motion out = truth;
  for (int d = 0; d < truth.dofs.cols(); ++d) {
    if (!listed[size_t(d)]) continue;
    const Dof& dof = skeleton.dofs[d];
    for (int f = 0; f < truth.num_frames(); ++f) {
      double& v = out.dofs(f, d);
      v += error(f, d);
      if (dof.limited) v = std::clamp(v, dof.lower, dof.upper);
    }
  }
  return out;
}

}  // namespace weft::capture
