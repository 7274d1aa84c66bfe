#pragma once
// A trained model as other commands use it: the run folder `weft train` writes
// (docs/TRAINING.md) is also the model folder `weft infer`, `weft adapt` and `weft eval`
// read. Besides the training files it holds, written when a run starts:
//   model.yaml            what follows, so the folder is usable without the dataset
//   character/            a copy of the dataset's character folder
// model.yaml:
//   format: weft-model/1
//   config: config.yaml            # the training config as given (a byte copy)
//   config_dir: /abs/configs/train # where it came from: its relative paths resolve there
//   data: /abs/data/training_set   # the dataset it trained on
//   character: character/character.yaml
//   simulation: {...}              # the dataset's simulation section (garment_config.h;
//                                  # absent when the dataset has none): the cloth material
//                                  # and settings of the collision pass, adaptation's
//                                  # simulation loss and the out-of-balance force
// The weights are model.safetensors once training finished, else the last checkpoint.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "capture/garment/garment_config.h"
#include "capture/model/capture_networks.h"
#include "capture/model/network_config.h"

namespace weft::capture {

struct ModelFolder {
  std::string dir;
  std::string config;        // the training config's copy (RUN/config.yaml)
  std::string config_dir;    // where that config came from: its relative paths resolve there
  uint64_t seed = 0;         // the config's seed and network section: what rebuilds the networks
  NetworkConfig network;
  std::string character;     // path of character.yaml (in the folder)
  std::string data;          // the training dataset (may no longer exist)
  std::optional<SynthSimulationConfig> simulation;  // the garment's, from the training dataset
  std::string weights;       // model.safetensors or the last checkpoint
};

// Reads a model folder; errors name the folder and what is missing (no model.yaml: a run
// of a weft before model folders, or not a run; no weights: training has not written a
// checkpoint yet). Of the training config only `seed` and `network` are read (the trainer
// reads the whole of it: capture/training/training_config.h, model_training_config).
ModelFolder read_model_folder(const std::string& run);

// Writes RUN/model.yaml and RUN/character/ for a run of `config_path` on `data_dir`
// (atomically; an existing character/ is replaced by the dataset's), with the dataset's
// simulation section when it has one.
void write_model_folder(const std::string& run, const std::string& config_path, const std::string& data_dir);

// Loads both networks from model.safetensors or a training checkpoint (which also holds
// the optimiser's state: left out).
void load_capture_networks(const std::string& weights, CaptureNetworks& networks);

// The same for a run's starting weights (`weft train --init`): weights or a checkpoint that
// hold no `detector.*` tensor while the networks have a detector (network.detector) load the
// other networks and leave the detector as initialised, so a detector stage can add the
// person detector to a model trained without one; returns whether it did. Otherwise (a
// detector in the file, no detector in the networks) as load_capture_networks.
bool load_capture_networks_for_a_new_detector(const std::string& weights, CaptureNetworks& networks);

// The checkpoints of RUN/checkpoints (step_NNNNNNN.safetensors), oldest first.
std::vector<std::pair<int64_t, std::filesystem::path>> list_checkpoints(const std::filesystem::path& dir);
std::string checkpoint_file(int64_t step);

}  // namespace weft::capture
