#pragma once
// Photographs as backgrounds, for the synthetic studio's takes (capture/studio/scene_dressing.h)
// and for training-time augmentation (capture/dataset/augmentation.h): finding a folder's
// photos and cutting a frame-shaped crop out of one. Debian's mate-backgrounds puts nature
// photos in /usr/share/backgrounds/mate/nature (GPL-2+; scripts/setup.sh installs it); they
// are read from there, never copied.
#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace weft::capture {

// The image files of `path`: a folder's .jpg/.jpeg/.png (sorted by name), or one such file.
// Throws weft::Error naming `key` and the path when it holds no photo.
std::vector<std::string> list_photos(const std::string& path, const std::string& key);

// A width×height crop of `photo` (CV_8UC3), resized to the frame: the frame's aspect ratio,
// `fill` (0..1] of the largest such window the photo holds, its place given by x and y in
// [0, 1] (0: left / top edge, 1: right / bottom edge).
cv::Mat photo_crop(const cv::Mat& photo, int width, int height, double fill, double x, double y);

}  // namespace weft::capture
