#include "capture/model/network_config.h"

#include <spdlog/fmt/fmt.h>

namespace weft::capture {

void parse_network_config(const StrictYaml& y, const YAML::Node& n, NetworkConfig& c) {
  y.numbers(n, "network.",
            {{"margin", &c.margin, 0, 2},
             {"dof_scale", &c.dof_scale, 1e-6, 100},
             {"angle_scale", &c.angle_scale, 1e-6, 100},
             {"translation_scale_m", &c.translation_scale_m, 1e-6, 100}},
            {{"input_size", &c.input_size, 32, 1024}, {"lift_width", &c.lift_width, 16, 4096},
             {"lift_layers", &c.lift_layers, 1, 8}},
            {"backbone", "keypoint_input", "image_input", "detector"});
  if (n["keypoint_input"])
    c.keypoint_input = y.get<bool>(n["keypoint_input"], "network.keypoint_input", "true or false");
  if (n["image_input"]) c.image_input = y.get<bool>(n["image_input"], "network.image_input", "true or false");
  if (!c.image_input && !c.keypoint_input)
    y.fail_at(n["image_input"] ? n["image_input"] : n, "network.image_input",
              "false leaves PoseNet without an input: set network.keypoint_input: true (the lifting branch)");
  if (const YAML::Node d = n["detector"]) {
    DetectorConfig& dc = c.detector;
    if (!d.IsMap()) y.fail_at(d, "network.detector", "expected a map (input_size, width, margin, sigma_px)");
    dc.enabled = true;
    y.numbers(d, "network.detector.", {{"margin", &dc.margin, 0, 2}, {"sigma_px", &dc.sigma_px, 0.5, 32}},
              {{"input_size", &dc.input_size, 32, 1024}, {"width", &dc.width, 4, 256}}, {});
    if (dc.input_size % 16 != 0)
      y.fail_at(d["input_size"], "network.detector.input_size",
                "expected a multiple of 16 (the detector halves the crop four times), found " +
                    std::to_string(dc.input_size));
  }
  if (n["backbone"]) {
    c.backbone = y.get<std::string>(n["backbone"], "network.backbone", "resnet18, resnet34 or resnet50");
    if (c.backbone != "resnet18" && c.backbone != "resnet34" && c.backbone != "resnet50")
      y.fail_at(n["backbone"], "network.backbone", "expected resnet18, resnet34 or resnet50, found '" + c.backbone + "'");
  }
}

std::string network_config_yaml(const NetworkConfig& c) {
  std::string y = fmt::format(
      "{{backbone: {}, input_size: {}, margin: {}, dof_scale: {}, angle_scale: {}, translation_scale_m: {}, "
      "keypoint_input: {}, image_input: {}, lift_width: {}, lift_layers: {}",
      c.backbone, c.input_size, c.margin, c.dof_scale, c.angle_scale, c.translation_scale_m, c.keypoint_input,
      c.image_input, c.lift_width, c.lift_layers);
  if (c.detector.enabled)
    y += fmt::format(", detector: {{input_size: {}, width: {}, margin: {}, sigma_px: {}}}", c.detector.input_size,
                     c.detector.width, c.detector.margin, c.detector.sigma_px);
  return y + "}";
}

}  // namespace weft::capture
