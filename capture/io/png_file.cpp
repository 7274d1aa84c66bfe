#include "capture/io/png_file.h"

#include <opencv2/imgcodecs.hpp>

#include <vector>

#include "graph/atomic_file.h"
#include "graph/error.h"

namespace weft::capture {

void write_png_atomically(const std::string& path, const cv::Mat& image) {
  std::vector<uchar> bytes;
  WEFT_CHECK(!image.empty() && cv::imencode(".png", image, bytes), path, ": PNG encoding failed");
  write_bytes_atomically(path, bytes.data(), bytes.size());
}

}  // namespace weft::capture
