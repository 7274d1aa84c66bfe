#include "capture/evaluation/capture_folder.h"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>

#include "capture/character/skeletool_io.h"
#include "geometry/mesh_io.h"
#include "files/text_reader.h"
#include "graph/error.h"

namespace weft::capture {

namespace fs = std::filesystem;

namespace {

using nlohmann::json;

// The value of a required key, of the expected JSON type.
const json& required(const json& object, const std::string& key, json::value_t type, const std::string& where,
                     const char* expected) {
  const auto it = object.find(key);
  WEFT_CHECK(it != object.end(), where, ": missing key '", key, "' (expected ", expected, ")");
  const bool ok = type == json::value_t::number_float ? it->is_number()
                  : type == json::value_t::number_integer ? it->is_number_integer()
                                                          : it->type() == type;
  WEFT_CHECK(ok, where, ": key '", key, "' is ", it->type_name(), ", expected ", expected);
  return *it;
}

std::string required_string(const json& o, const std::string& key, const std::string& where) {
  return required(o, key, json::value_t::string, where, "a string").get<std::string>();
}

double required_number(const json& o, const std::string& key, const std::string& where) {
  const double v = required(o, key, json::value_t::number_float, where, "a number").get<double>();
  WEFT_CHECK(std::isfinite(v), where, ": key '", key, "' is not finite");
  return v;
}

std::string resolve(const fs::path& dir, const std::string& path) {
  if (path.empty() || fs::path(path).is_absolute()) return path;
  return (dir / path).lexically_normal().string();
}

}  // namespace

CaptureFolder read_capture_folder(const std::string& dir) {
  WEFT_CHECK(fs::is_directory(dir), dir, ": no such capture folder (expected the --out folder of `weft infer`)");
  const fs::path file = fs::path(dir) / "capture.json";
  const std::string where = file.string();
  WEFT_CHECK(fs::exists(file), where, ": missing (a capture folder of `weft infer` holds capture.json)");
  const std::string text = read_file_bytes(where);
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    fail(where, ": invalid JSON: ", e.what());
  }
  WEFT_CHECK(j.is_object(), where, ": expected a JSON object");
  CaptureFolder c;
  c.dir = dir;
  c.format = required_string(j, "format", where);
  WEFT_CHECK(c.format == "weft-capture/1", where, ": format is '", c.format, "', expected 'weft-capture/1'");
  c.model = required_string(j, "model", where);
  c.character = resolve(dir, required_string(j, "character", where));
  c.metres_per_unit = required_number(j, "metres_per_unit", where);
  WEFT_CHECK(c.metres_per_unit > 0, where, ": metres_per_unit must be > 0, is ", c.metres_per_unit);
  c.input = required_string(j, "input", where);
  c.camera = required_string(j, "camera", where);
  c.view = required_string(j, "view", where);
  c.fps = required_number(j, "fps", where);
  WEFT_CHECK(c.fps > 0, where, ": fps must be > 0, is ", c.fps);
  c.collisions_resolved =
      required(j, "collisions_resolved", json::value_t::boolean, where, "true or false").get<bool>();
  // Optional (captures before the person detector have neither).
  for (const char* key : {"masks_from", "keypoints_from", "detections"}) {
    const auto it = j.find(key);
    if (it == j.end()) continue;
    WEFT_CHECK(it->is_string(), where, ": key '", key, "' is ", it->type_name(), ", expected a string");
  }
  c.masks_from = j.value("masks_from", std::string());
  c.keypoints_from = j.value("keypoints_from", std::string());
  c.detections = resolve(dir, j.value("detections", std::string()));
  const json& frames = required(j, "frames", json::value_t::array, where, "an array of frames");
  WEFT_CHECK(!frames.empty(), where, ": 'frames' is empty (expected at least one captured frame)");
  std::set<int> seen;
  for (size_t i = 0; i < frames.size(); ++i) {
    const std::string at = fmt::format("{}: frames[{}]", where, i);
    const json& f = frames[i];
    WEFT_CHECK(f.is_object(), at, ": expected an object {id, source, pivot, translation_from}");
    CapturedFrame cf;
    const json& id = required(f, "id", json::value_t::number_integer, at, "an integer frame id");
    WEFT_CHECK(id.get<int64_t>() >= 0 && id.get<int64_t>() < (int64_t(1) << 30), at, ": id ", id.dump(),
               " is out of range (expected a frame id ≥ 0)");
    cf.id = id.get<int>();
    WEFT_CHECK(seen.insert(cf.id).second, at, ": frame id ", cf.id, " appears twice");
    cf.source = required_string(f, "source", at);
    const json& p = required(f, "pivot", json::value_t::array, at, "[x, y, z]");
    WEFT_CHECK(p.size() == 3, at, ": pivot has ", p.size(), " values, expected [x, y, z]");
    for (int a = 0; a < 3; ++a) {
      WEFT_CHECK(p[a].is_number() && std::isfinite(p[a].get<double>()), at, ": pivot[", a,
                 "] is not a finite number");
      cf.pivot[a] = p[a].get<double>();
    }
    cf.translation_from = required_string(f, "translation_from", at);
    c.frames.push_back(cf);
  }
  return c;
}

CapturedMeshes read_captured_meshes(const CaptureFolder& c, int id, const Character& ch) {
  const auto read = [&](const std::string& name, int vertices, const char* what) {
    const fs::path path = fs::path(c.dir) / "meshes" / fmt::format("{}_{:04d}.ply", name, id);
    WEFT_CHECK(fs::exists(path), path.string(), ": missing (expected the predicted ", what, " of frame ", id,
               ", listed in capture.json)");
    const TriangleMesh m = read_ply(path.string());
    WEFT_CHECK(m.V.rows() == vertices, path.string(), ": ", m.V.rows(), " vertices, expected ", vertices,
               " (the ", what, " template of ", ch.source, ")");
    WEFT_CHECK(m.V.allFinite(), path.string(), ": non-finite vertex positions");
    return m.V;
  };
  CapturedMeshes m;
  m.body = read("body", int(ch.body.mesh.V.rows()), "body");
  if (ch.has_cloth()) m.cloth = read("cloth", int(ch.cloth->mesh.V.rows()), "garment");
  return m;
}

Eigen::MatrixXd read_captured_dofs(const CaptureFolder& c, const Character& ch) {
  const fs::path path = fs::path(c.dir) / "pose.motion";
  WEFT_CHECK(fs::exists(path), path.string(), ": missing (expected one row of the character's ", ch.rest_dofs.size(),
             " dofs per captured frame)");
  const Motion m = read_motion(path.string(), int(ch.rest_dofs.size()));
  WEFT_CHECK(m.num_frames() == int(c.frames.size()), path.string(), ": ", m.num_frames(), " rows, expected ",
             c.frames.size(), " (one per entry of capture.json's frames)");
  WEFT_CHECK(m.dofs.allFinite(), path.string(), ": non-finite dofs");
  return m.dofs;
}

}  // namespace weft::capture
