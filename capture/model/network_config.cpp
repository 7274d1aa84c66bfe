#include "capture/model/network_config.h"

namespace weft::capture {

void parse_network_config(const StrictYaml& y, const YAML::Node& n, NetworkConfig& c) {
  y.numbers(n, "network.",
            {{"margin", &c.margin, 0, 2},
             {"dof_scale", &c.dof_scale, 1e-6, 100},
             {"angle_scale", &c.angle_scale, 1e-6, 100},
             {"translation_scale_m", &c.translation_scale_m, 1e-6, 100}},
            {{"input_size", &c.input_size, 32, 1024}}, {"backbone", "keypoint_input", "image_input"});
  if (n["keypoint_input"])
    c.keypoint_input = y.get<bool>(n["keypoint_input"], "network.keypoint_input", "true or false");
  if (n["image_input"]) c.image_input = y.get<bool>(n["image_input"], "network.image_input", "true or false");
  if (!c.image_input && !c.keypoint_input)
    y.fail_at(n["image_input"] ? n["image_input"] : n, "network.image_input",
              "false leaves PoseNet without an input: set network.keypoint_input: true (the lifting branch)");
  if (n["backbone"]) {
    c.backbone = y.get<std::string>(n["backbone"], "network.backbone", "resnet18, resnet34 or resnet50");
    if (c.backbone != "resnet18" && c.backbone != "resnet34" && c.backbone != "resnet50")
      y.fail_at(n["backbone"], "network.backbone", "expected resnet18, resnet34 or resnet50, found '" + c.backbone + "'");
  }
}

}  // namespace weft::capture
