#include "capture/io/openpose.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "graph/atomic_file.h"
#include "files/text_reader.h"
#include "graph/error.h"

namespace weft::capture {

const std::array<const char*, kBody25Count> kBody25Names = {
    "Nose",   "Neck",   "RShoulder", "RElbow",   "RWrist",    "LShoulder", "LElbow",
    "LWrist", "MidHip", "RHip",      "RKnee",    "RAnkle",    "LHip",      "LKnee",
    "LAnkle", "REye",   "LEye",      "REar",     "LEar",      "LBigToe",   "LSmallToe",
    "LHeel",  "RBigToe", "RSmallToe", "RHeel"};

int body25_index(const std::string& name) {
  for (int i = 0; i < kBody25Count; ++i)
    if (name == kBody25Names[i]) return i;
  return -1;
}

OpenPoseFrame parse_openpose_json(const std::string& text, const std::string& path) {
  const std::string name = display_name(path);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    const size_t byte = std::min<size_t>(e.byte, text.size());
    const long line = 1 + std::count(text.begin(), text.begin() + static_cast<long>(byte > 0 ? byte - 1 : 0), '\n');
    fail(name, ":", line, ": invalid JSON: ", e.what());
  }
  if (!j.is_object()) fail(name, ": expected a JSON object with 'people'");
  if (!j.contains("people") || !j["people"].is_array()) fail(name, ": expected an array 'people'");
  OpenPoseFrame frame;
  int p = 0;
  for (const auto& person : j["people"]) {
    const std::string where = name + ": people[" + std::to_string(p++) + "]";
    if (!person.is_object() || !person.contains("pose_keypoints_2d"))
      fail(where, ": expected an object with 'pose_keypoints_2d'");
    const auto& k = person["pose_keypoints_2d"];
    if (!k.is_array() || k.size() != 3 * kBody25Count)
      fail(where, ".pose_keypoints_2d: expected ", 3 * kBody25Count,
           " numbers (25 BODY_25 keypoints × x, y, confidence), found ",
           k.is_array() ? std::to_string(k.size()) : std::string("a ") + k.type_name());
    Body25 b;
    for (int i = 0; i < 3 * kBody25Count; ++i) {
      if (!k[i].is_number()) fail(where, ".pose_keypoints_2d[", i, "]: expected a number, found ", k[i].type_name());
      const double v = k[i].get<double>();
      if (!std::isfinite(v)) fail(where, ".pose_keypoints_2d[", i, "]: non-finite value");
      b(i / 3, i % 3) = v;
    }
    frame.people.push_back(b);
  }
  return frame;
}

OpenPoseFrame read_openpose_json(const std::string& path) {
  return parse_openpose_json(read_file_bytes(path), path);
}

void write_openpose_json(const std::string& path, const OpenPoseFrame& frame) {
  nlohmann::json j;
  j["version"] = 1.3;
  j["people"] = nlohmann::json::array();
  for (const Body25& b : frame.people) {
    if (!b.allFinite()) fail(path, ": non-finite keypoint value");
    nlohmann::json person;
    person["person_id"] = {-1};
    std::vector<double> flat(b.data(), b.data() + b.size());
    person["pose_keypoints_2d"] = flat;
    j["people"].push_back(person);
  }
  const std::string text = j.dump(1) + "\n";
  write_bytes_atomically(path, text.data(), text.size());
}

}  // namespace weft::capture
