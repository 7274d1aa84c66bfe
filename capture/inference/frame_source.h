#pragma once
// The frames `weft infer` captures: a video file (anything OpenCV's VideoCapture opens) or
// a folder of images (.png, .jpg, .jpeg, .bmp, in name order). A frame's id is its index
// in a video; in a folder it is the number its file is named by when every name is a
// number (0007.png → 7, so a dataset's frames keep their ids), else its position.
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include <map>
#include <string>
#include <vector>

namespace weft::capture {

struct InputFrame {
  int id = 0;
  std::string name;  // the image's file stem, or the frame's id with 4 digits for a video
  cv::Mat bgr;       // CV_8UC3
};

class FrameSource {
 public:
  // Errors (weft::Error naming the path): a missing path, a folder without images, a file
  // OpenCV cannot open as a video.
  explicit FrameSource(const std::string& path);
  bool is_video() const { return video_; }
  const std::string& path() const { return path_; }
  int size() const { return size_; }      // frames (a video's count as its container states it)
  double fps() const { return fps_; }     // a video's frame rate; 0 for a folder
  // The next frame; false at the end. An image that cannot be read is an error naming it.
  bool next(InputFrame& frame);
  void rewind();

 private:
  std::string path_;
  bool video_ = false;
  int size_ = 0, next_ = 0;
  double fps_ = 0;
  cv::VideoCapture capture_;
  std::vector<std::string> files_;
  std::vector<int> ids_;
};

// Per-frame files that go with the frames: foreground masks (MASKS/<name>.png) and OpenPose
// detections (`<name>_keypoints.json`, as OpenPose names them for an image folder; for a
// video OpenPose writes `<video>_<frame:012d>_keypoints.json`, found by the number).
class FrameFiles {
 public:
  FrameFiles() = default;
  // Scans `dir` for files ending in `suffix` (e.g. ".png", "_keypoints.json").
  FrameFiles(const std::string& dir, const std::string& suffix);
  bool empty() const { return by_name_.empty(); }
  // The file of a frame, or "" when there is none.
  std::string find(const InputFrame& frame) const;

 private:
  std::string dir_;
  std::map<std::string, std::string> by_name_;
  std::map<int, std::string> by_number_;
};

}  // namespace weft::capture
