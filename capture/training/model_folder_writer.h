#pragma once
// Writing the model folder of a `weft train` run (the format: capture/model/model_folder.h).
#include <string>

namespace weft::capture {

// Writes RUN/model.yaml and RUN/character/ for a run of `config_path` on `data_dir`
// (atomically; an existing character/ is replaced by the dataset's).
void write_model_folder(const std::string& run, const std::string& config_path, const std::string& data_dir);

}  // namespace weft::capture
