#pragma once
// PNG files written atomically (encoded in memory, then a temporary and a rename), so a
// crash never leaves a truncated image behind.
#include <opencv2/core.hpp>

#include <string>

namespace weft::capture {

// Any image cv::imencode writes as PNG (8- or 16-bit, 1, 3 or 4 channels); errors name the path.
void write_png_atomically(const std::string& path, const cv::Mat& image);

}  // namespace weft::capture
