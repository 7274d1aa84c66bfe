#include "capture/inference/capture_config.h"

#include "files/strict_yaml.h"
#include "files/text_reader.h"

namespace weft::capture {

CaptureConfig parse_capture_config(const std::string& text, const std::string& name) {
  StrictYaml y;
  y.file = name;
  const YAML::Node root = y.parse(text);
  CaptureConfig c;
  c.file = name;
  if (!root || root.IsNull()) return c;
  if (!root.IsMap()) y.fail_at(root, "(document)", "expected a mapping of config keys");
  y.check_keys(root, "", {"batch_size", "keying", "filter", "refine", "output"});
  if (root["batch_size"]) {
    const double b = y.number(root["batch_size"], "batch_size", 1, 1024);
    if (b != int(b)) y.fail_at(root["batch_size"], "batch_size", "expected an integer");
    c.batch_size = int(b);
  }
  if (const YAML::Node k = root["keying"]) {
    KeyingConfig& g = c.keying;
    y.numbers(k, "keying.",
              {{"hue_min", &g.hue_min, 0, 180},
               {"hue_max", &g.hue_max, 0, 180},
               {"min_saturation", &g.min_saturation, 0, 255},
               {"min_value", &g.min_value, 0, 255}},
              {{"open_px", &g.open_px, 0, 50}, {"close_px", &g.close_px, 0, 50}}, {"largest_component"});
    if (k["largest_component"])
      g.largest_component = y.get<bool>(k["largest_component"], "keying.largest_component", "true or false");
    if (g.hue_min > g.hue_max) y.fail_at(k, "keying.hue_min", "must not exceed keying.hue_max");
  }
  if (const YAML::Node f = root["filter"])
    y.numbers(f, "filter.", {{"sigma_frames", &c.filter_sigma_frames, 0, 100}},
              {{"radius_frames", &c.filter_radius_frames, 0, 50}}, {});
  if (const YAML::Node r = root["refine"])
    y.numbers(r, "refine.", {{"prior", &c.refine.prior, 0, 1e6}, {"lr", &c.refine.lr, 1e-6, 10}, {"depth_prior", &c.refine.depth_prior, 0, 1e9}},
              {{"iterations", &c.refine.iterations, 0, 10000}, {"batch_size", &c.refine.batch_size, 1, 4096}}, {});
  if (const YAML::Node o = root["output"]) {
    y.numbers(o, "output.", {{"overlay_alpha", &c.overlay_alpha, 0, 1}}, {},
              {"meshes", "overlays", "video"});
    if (o["meshes"]) {
      c.mesh_formats = y.strings(o["meshes"], "output.meshes");
      for (const std::string& f : c.mesh_formats)
        if (f != "ply" && f != "obj") y.fail_at(o["meshes"], "output.meshes", "expected ply and/or obj, found '" + f + "'");
    }
    if (o["overlays"]) c.overlays = y.get<bool>(o["overlays"], "output.overlays", "true or false");
    if (o["video"]) c.video = y.get<bool>(o["video"], "output.video", "true or false");
  }
  return c;
}

CaptureConfig load_capture_config(const std::string& path) { return parse_capture_config(read_file_bytes(path), path); }

}  // namespace weft::capture
