#pragma once
// The networks' shape and output scales: the `network` section of a training config
// (docs/TRAINING.md), all a model folder's reader needs of that config to rebuild the
// networks (model_folder.h).
#include <string>

#include "capture/detection/person_detector.h"
#include "files/strict_yaml.h"

namespace weft::capture {

struct NetworkConfig {
  std::string backbone = "resnet18";  // resnet18 | resnet34 | resnet50
  int input_size = 128;               // crops are input_size² pixels
  double margin = 0.15;               // crop margin around the person (dataset reader)
  double dof_scale = 0.1;             // PoseNet: dof = rest + dof_scale · output (radians, units); limited dofs: pose_dofs.h
  double angle_scale = 0.05;          // PADefNet: node Euler angle = angle_scale · output (radians)
  double translation_scale_m = 0.01;  // PADefNet: node translation = this · output (metres)
  // PoseNet also reads the input view's 2D detections (a lifting branch, CaptureNetworks):
  // the labelled keypoints tell the person's left from right, which the pixels of a
  // front and a back view barely do.
  bool keypoint_input = false;
  // false: PoseNet is the lifting branch alone (needs keypoint_input), the image network
  // does not run: a lifting network from the detections, as the field's 2D-to-3D lifters.
  bool image_input = true;
  // The lifting branch's shape: lift_layers hidden layers of lift_width units, each a
  // linear map and a ReLU, then a linear map to PoseNet's outputs (zero at the start).
  int lift_width = 512;
  int lift_layers = 2;
  // The person detector (capture/detection/person_detector.h): present with a
  // `network.detector` section, trained by stages.detector; what lets weft find the
  // person's keypoints and mask itself.
  DetectorConfig detector;
};

// Reads the `network` section `n` into `c` (absent keys keep their value); errors name the
// file, the line and the key (network.*).
void parse_network_config(const StrictYaml& yaml, const YAML::Node& n, NetworkConfig& c);

// The `network` section as a one-line YAML flow map with every key, so that a config
// written from it (weft adapt's) rebuilds the same networks: parse_network_config of it
// gives `c` back (numbers in their shortest exact form).
std::string network_config_yaml(const NetworkConfig& c);

}  // namespace weft::capture
