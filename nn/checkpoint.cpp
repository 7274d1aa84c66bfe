#include "nn/checkpoint.h"

#include <cstdio>

#include "graph/error.h"

namespace weft::nn {

namespace {

constexpr const char* kFormat = "training-checkpoint-1";
const std::string kModelPrefix = "model.";
const std::string kOptimizerPrefix = "optimizer.";

const std::string& require_meta(const Metadata& m, const std::string& path,
                                const std::string& key) {
  auto it = m.find(key);
  if (it == m.end()) fail("checkpoint '", path, "': missing metadata '", key, "'");
  return it->second;
}

int64_t parse_int(const std::string& s, const std::string& path, const std::string& key) {
  size_t used = 0;
  int64_t v = 0;
  try {
    v = std::stoll(s, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != s.size() || v < 0)
    fail("checkpoint '", path, "': metadata '", key, "' = '", s,
         "' is not a non-negative integer");
  return v;
}

double parse_double(const std::string& s, const std::string& path, const std::string& key) {
  size_t used = 0;
  double v = 0;
  try {
    v = std::stod(s, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != s.size()) fail("checkpoint '", path, "': metadata '", key, "' = '", s,
                                          "' is not a number");
  return v;
}

}  // namespace

void save_weights(const std::string& path, const Module& model, const Metadata& metadata) {
  save_safetensors(path, model.state_dict(), metadata);
}

void load_weights(const std::string& path, Module& model, bool strict) {
  const SafetensorsFile file = load_safetensors(path);
  model.load_state_dict(file.tensors, "weights '" + path + "'", strict);
}

void save_checkpoint(const std::string& path, const Module& model, const Optimizer* optimizer,
                     int64_t step, const Generator* gen, const Metadata& extra) {
  if (step < 0) fail("checkpoint '", path, "': step ", step, " is negative");
  TensorMap tensors;
  for (auto& [name, t] : model.state_dict()) tensors.emplace(kModelPrefix + name, t);
  Metadata meta = extra;
  meta["weft.format"] = kFormat;
  meta["weft.step"] = std::to_string(step);
  if (optimizer) {
    for (auto& [name, t] : optimizer->state()) tensors.emplace(kOptimizerPrefix + name, t);
    meta["weft.optimizer"] = optimizer->type_name();
    char lr[64];
    std::snprintf(lr, sizeof lr, "%.17g", optimizer->lr());
    meta["weft.lr"] = lr;
  }
  if (gen) meta["weft.rng_state"] = gen->state();
  save_safetensors(path, tensors, meta);
}

bool is_training_checkpoint(const SafetensorsFile& file) {
  const auto format = file.metadata.find("weft.format");
  return format != file.metadata.end() && format->second == kFormat;
}

TensorMap model_tensors(const SafetensorsFile& file) {
  if (!is_training_checkpoint(file)) return file.tensors;
  TensorMap model;
  for (const auto& [name, t] : file.tensors)
    if (name.starts_with(kModelPrefix)) model.emplace(name.substr(kModelPrefix.size()), t);
  return model;
}

TrainingCheckpoint load_checkpoint(const std::string& path, Module& model, Optimizer* optimizer,
                                   Generator* gen) {
  const SafetensorsFile file = load_safetensors(path);
  const std::string source = "checkpoint '" + path + "'";
  const std::string& format = require_meta(file.metadata, path, "weft.format");
  if (format != kFormat)
    fail(source, ": format '", format, "' is not '", kFormat, "'");
  TrainingCheckpoint out;
  out.metadata = file.metadata;
  out.step = parse_int(require_meta(file.metadata, path, "weft.step"), path, "weft.step");

  TensorMap model_state, optimizer_state;
  for (const auto& [name, t] : file.tensors) {
    if (name.starts_with(kModelPrefix))
      model_state.emplace(name.substr(kModelPrefix.size()), t);
    else if (name.starts_with(kOptimizerPrefix))
      optimizer_state.emplace(name.substr(kOptimizerPrefix.size()), t);
    else
      fail(source, ": tensor '", name, "' is neither 'model.*' nor 'optimizer.*'");
  }
  model.check_state_dict(model_state, source + " (model)");
  double lr = 0;
  if (optimizer) {
    const std::string& type = require_meta(file.metadata, path, "weft.optimizer");
    if (type != optimizer->type_name())
      fail(source, ": holds the state of a ", type, " optimiser, not of a ",
           optimizer->type_name());
    lr = parse_double(require_meta(file.metadata, path, "weft.lr"), path, "weft.lr");
    optimizer->check_state(optimizer_state, source + " (optimizer)");
  }
  Generator restored;
  if (gen) {
    try {
      restored.set_state(require_meta(file.metadata, path, "weft.rng_state"));
    } catch (const Error& e) {
      fail(source, ": metadata 'weft.rng_state': ", e.what());
    }
  }

  // Everything checked: apply.
  model.load_state_dict(model_state, source + " (model)");
  if (optimizer) {
    optimizer->load_state(optimizer_state, source + " (optimizer)");
    optimizer->set_lr(lr);
  }
  if (gen) *gen = restored;
  return out;
}

}  // namespace weft::nn
