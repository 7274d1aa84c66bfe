#include "capture/model/model_folder.h"

#include <algorithm>
#include <cstdio>
#include <system_error>

#include "capture/dataset/synthetic_dataset.h"
#include "files/strict_yaml.h"
#include "graph/atomic_file.h"
#include "files/text_reader.h"
#include "graph/error.h"
#include "nn/checkpoint.h"
#include "nn/safetensors.h"

namespace weft::capture {

namespace fs = std::filesystem;

std::string checkpoint_file(int64_t step) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "step_%07lld.safetensors", static_cast<long long>(step));
  return buf;
}

std::vector<std::pair<int64_t, fs::path>> list_checkpoints(const fs::path& dir) {
  std::vector<std::pair<int64_t, fs::path>> out;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return out;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string n = e.path().filename().string();
    long long step = 0;
    char tail[32] = {0};
    if (std::sscanf(n.c_str(), "step_%lld.%31s", &step, tail) == 2 && std::string(tail) == "safetensors")
      out.emplace_back(step, e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

void load_capture_networks(const std::string& path, CaptureNetworks& nets) {
  nets.load_state_dict(nn::model_tensors(nn::load_safetensors(path)), "weights '" + path + "'");
}

bool load_capture_networks_for_a_new_detector(const std::string& path, CaptureNetworks& nets) {
  nn::TensorMap state = nn::model_tensors(nn::load_safetensors(path));
  const bool add = nets.detector && std::none_of(state.begin(), state.end(), [](const auto& t) {
                     return t.first.starts_with("detector.");
                   });
  if (add)  // the file's networks, the detector's own initialisation
    for (const auto& [name, t] : nets.state_dict())
      if (name.starts_with("detector.")) state.emplace(name, t.clone());
  nets.load_state_dict(state, "weights '" + path + "'");
  return add;
}

void write_model_folder(const std::string& run, const std::string& config_path, const std::string& data_dir) {
  const DatasetInfo info = read_dataset_info(data_dir);
  const std::optional<SynthSimulationConfig> simulation = find_dataset_simulation(data_dir);
  const fs::path dir(run);
  // The character: a fresh copy next to the old one, then swapped in, so an interrupted
  // copy never leaves a half-written character/.
  const fs::path source = fs::path(info.character).parent_path();
  const fs::path target = dir / "character", staging = dir / "character.partial";
  fs::remove_all(staging);
  fs::copy(source, staging, fs::copy_options::recursive);
  fs::remove_all(target);
  fs::rename(staging, target);

  YAML::Emitter y;
  y << YAML::BeginMap;
  y << YAML::Key << "format" << YAML::Value << "weft-model/1";
  y << YAML::Key << "config" << YAML::Value << "config.yaml";
  y << YAML::Key << "config_dir" << YAML::Value << fs::absolute(config_path).parent_path().lexically_normal().string();
  y << YAML::Key << "data" << YAML::Value << fs::absolute(data_dir).lexically_normal().string();
  y << YAML::Key << "character" << YAML::Value
    << ("character/" + fs::path(info.character).filename().string());
  y << YAML::EndMap;
  write_text_atomically((dir / "model.yaml").string(),
                        "# What `weft infer`, `weft adapt` and `weft eval` need to use this model "
                        "(capture/model/model_folder.h).\n" +
                            std::string(y.c_str()) + "\n" +
                            (simulation ? simulation_config_yaml(*simulation) : std::string()));
}

ModelFolder read_model_folder(const std::string& run) {
  const fs::path dir(run);
  WEFT_CHECK(fs::is_directory(dir), run, ": model folder not found (the --out folder of `weft train`)");
  const fs::path file = dir / "model.yaml";
  WEFT_CHECK(fs::exists(file), run,
             ": no model.yaml; a model folder is the --out folder of `weft train` (runs started before "
             "model folders existed get one by `weft train --resume` with their config and data)");
  StrictYaml y;
  y.file = file.string();
  y.dir = dir;
  const YAML::Node root = y.parse(read_file_bytes(file.string()));
  if (!root.IsMap()) y.fail_at(root, "(document)", "expected a mapping");
  // synth_config: model folders written before datasets carried their simulation settings
  // named the recipe instead; read for them only.
  y.check_keys(root, "", {"format", "config", "config_dir", "data", "character", "simulation", "synth_config"});
  for (const char* key : {"format", "config", "config_dir", "character"})
    if (!root[key]) y.fail_at(root, key, "missing");
  const std::string format = y.get<std::string>(root["format"], "format", "a string");
  if (format != "weft-model/1") y.fail_at(root["format"], "format", "expected weft-model/1, found " + format);

  ModelFolder m;
  m.dir = run;
  m.config = y.path(root["config"], "config");
  m.config_dir = y.get<std::string>(root["config_dir"], "config_dir", "a folder");
  {
    StrictYaml cy;
    cy.file = m.config;
    cy.dir = m.config_dir;
    const YAML::Node config = cy.parse(read_file_bytes(m.config));
    if (!config.IsMap()) cy.fail_at(config, "(document)", "expected a mapping of config keys");
    if (config["seed"]) m.seed = cy.get<uint64_t>(config["seed"], "seed", "a non-negative integer");
    if (config["network"]) parse_network_config(cy, config["network"], m.network);
  }
  m.character = y.path(root["character"], "character");
  if (root["data"]) m.data = y.get<std::string>(root["data"], "data", "a folder");
  if (root["simulation"]) {
    m.simulation.emplace();
    parse_simulation_config(y, root["simulation"], *m.simulation);
  } else if (root["synth_config"]) {
    m.simulation = load_simulation_config(y.path(root["synth_config"], "synth_config"));
  }

  if (fs::exists(dir / "model.safetensors")) {
    m.weights = (dir / "model.safetensors").string();
  } else {
    const auto all = list_checkpoints(dir / "checkpoints");
    WEFT_CHECK(!all.empty(), run,
               ": no model.safetensors and no checkpoints/step_*.safetensors: training has not saved any weights yet");
    m.weights = all.back().second.string();
  }
  return m;
}

}  // namespace weft::capture
