#include "capture/training/model_folder_writer.h"

#include <yaml-cpp/yaml.h>

#include <filesystem>

#include "capture/dataset/synthetic_dataset.h"
#include "capture/training/training_config.h"
#include "graph/atomic_file.h"

namespace weft::capture {

namespace fs = std::filesystem;

void write_model_folder(const std::string& run, const std::string& config_path, const std::string& data_dir) {
  const DatasetInfo info = read_dataset_info(data_dir);
  const TrainingConfig cfg = load_training_config(config_path);
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
  if (!cfg.physics.synth_config.empty())
    y << YAML::Key << "synth_config" << YAML::Value
      << fs::absolute(cfg.physics.synth_config).lexically_normal().string();
  y << YAML::EndMap;
  write_text_atomically((dir / "model.yaml").string(),
                        "# What `weft infer`, `weft adapt` and `weft eval` need to use this model "
                        "(capture/model/model_folder.h).\n" +
                            std::string(y.c_str()) + "\n");
}

}  // namespace weft::capture
