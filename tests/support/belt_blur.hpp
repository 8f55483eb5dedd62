// SPDX-License-Identifier: LGPL-2.1-or-later
// A belt's motion blur, as the core's tests put it on their frames.
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace pickdetect::test_scene {

/// `scene` as a camera whose shutter stays open while the belt moves `length` pixels along the
/// frame's rows sees it: a box blur along x.
inline cv::Mat blurred_along_x(const cv::Mat& scene, int length) {
  cv::Mat out;
  cv::filter2D(scene, out, -1, cv::Mat(1, length, CV_32FC1, cv::Scalar(1.0 / length)));
  return out;
}

} // namespace pickdetect::test_scene
