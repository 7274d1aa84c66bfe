#include "capture/inference/sequence_detection.h"

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <chrono>
#include <filesystem>
#include <vector>

#include "capture/character/character.h"
#include "capture/detection/person_detection.h"
#include "capture/inference/frame_source.h"
#include "capture/io/openpose.h"
#include "capture/io/png_file.h"
#include "capture/render/detection_drawing.h"
#include "capture/model/capture_networks.h"
#include "capture/model/model_folder.h"
#include "graph/atomic_file.h"
#include "graph/error.h"

namespace weft::capture {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

DetectSummary detect_sequence(const DetectOptions& o, const std::function<void(int, int)>& progress) {
  const auto t0 = Clock::now();
  WEFT_CHECK(o.batch_size >= 1, "weft detect: batch size ", o.batch_size, ", expected ≥ 1");
  WEFT_CHECK(!o.out.empty(), "weft detect: no output folder");
  ModelFolder model = read_model_folder(o.model);
  if (!o.weights.empty()) {
    WEFT_CHECK(fs::is_regular_file(o.weights), "weft detect: --weights ", o.weights, ": no such file");
    model.weights = o.weights;
  }
  const Character character = load_character(model.character);
  CaptureNetworks nets(character, model.network, model.seed);
  PersonDetector& detector = nets.require_detector(o.model);
  load_capture_networks(model.weights, nets);
  FrameSource source(o.input);
  const fs::path out(o.out);
  fs::create_directories(out / "keypoints");
  fs::create_directories(out / "masks");
  if (o.overlays) fs::create_directories(out / "overlays");
  const int total = o.max_frames >= 0 ? std::min(o.max_frames, source.size()) : source.size();
  spdlog::info("detector of {} ({}², width {}, weights {}) on {} ({} frames)", o.model,
               model.network.detector.input_size, model.network.detector.width, model.weights, o.input, total);

  DetectSummary summary;
  nlohmann::json frames = nlohmann::json::array();
  std::vector<InputFrame> batch;
  auto flush = [&] {
    if (batch.empty()) return;
    std::vector<cv::Mat> images;
    for (const InputFrame& f : batch) images.push_back(f.bgr);
    const auto t = Clock::now();
    const std::vector<PersonDetection> found = detect_people(detector, images);
    summary.seconds += std::chrono::duration<double>(Clock::now() - t).count();
    for (size_t i = 0; i < batch.size(); ++i) {
      const PersonDetection& d = found[i];
      OpenPoseFrame json;
      if (d.found) json.people.push_back(d.keypoints);
      write_openpose_json((out / "keypoints" / (batch[i].name + "_keypoints.json")).string(), json);
      write_png_atomically((out / "masks" / (batch[i].name + ".png")).string(), d.mask);
      if (o.overlays)
        write_png_atomically((out / "overlays" / (batch[i].name + ".png")).string(),
                             draw_detection(batch[i].bgr, d.keypoints, d.mask));
      int detected = 0;
      for (int m = 0; m < kBody25Count; ++m) detected += d.keypoints(m, 2) > 0;
      frames.push_back({{"id", batch[i].id}, {"name", batch[i].name}, {"person", d.found}, {"keypoints", detected},
                        {"mask_pixels", cv::countNonZero(d.mask)},
                        {"crop", {d.crop.left, d.crop.top, d.crop.side}}});
      summary.found += d.found;
      ++summary.frames;
    }
    batch.clear();
    if (progress) progress(summary.frames, total);
  };
  InputFrame f;
  while ((o.max_frames < 0 || summary.frames + int(batch.size()) < o.max_frames) && source.next(f)) {
    batch.push_back(f);
    if (int(batch.size()) == o.batch_size) flush();
  }
  flush();
  summary.total_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  nlohmann::json j;
  j["format"] = "weft-detect/1";
  j["model"] = fs::absolute(o.model).lexically_normal().string();
  j["weights"] = fs::absolute(model.weights).lexically_normal().string();
  j["input"] = fs::absolute(o.input).lexically_normal().string();
  j["detector"] = {{"input_size", model.network.detector.input_size},
                   {"width", model.network.detector.width},
                   {"margin", model.network.detector.margin}};
  j["frames"] = frames;
  j["timing"] = {{"detection_seconds", summary.seconds},
                 {"frames_per_second", summary.fps()},
                 {"total_seconds", summary.total_seconds}};
  write_text_atomically((out / "detect.json").string(), j.dump(1) + "\n");
  return summary;
}

}  // namespace weft::capture
