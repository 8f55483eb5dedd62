// SPDX-License-Identifier: LGPL-2.1-or-later
// The colourful print that the colour tests make their model pictures from: a crop of OpenCV's
// fruits.jpg (Debian's opencv-doc), rich in oranges, reds and greens.
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <string>

namespace pickdetect::test_scene {

/// Where the print lies in fruits.jpg (300x220 pixels).
inline const cv::Rect kFruitsPrint(150, 120, 300, 220);

/// The print as BGR, read afresh from fruits.jpg in `data_dir`; empty when the picture cannot be
/// read or is too small to hold it.
inline cv::Mat fruits_print(const std::string& data_dir) {
  const cv::Mat fruits = cv::imread(data_dir + "/fruits.jpg", cv::IMREAD_COLOR);
  if ((kFruitsPrint & cv::Rect(0, 0, fruits.cols, fruits.rows)) != kFruitsPrint)
    return cv::Mat();
  return fruits(kFruitsPrint).clone();
}

} // namespace pickdetect::test_scene
