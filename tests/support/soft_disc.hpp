// SPDX-License-Identifier: LGPL-2.1-or-later
// A plain patch whose rim fades over several pixels into what lies under it, as a highlight's
// does: the glare and cover tests lay highlights and soft-edged discs of colour with it.
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace pickdetect::test_scene {

/// Blends `frame` (BGR, CV_8UC3) towards `colour` inside the ellipse of `axes` turned by `angle`
/// degrees around `centre`, the blend's weight blurred by `sigma` pixels so that the rim fades.
inline void add_soft_disc(cv::Mat& frame, cv::Point centre, cv::Size axes, double angle,
                          const cv::Vec3b& colour, double sigma = 8.0) {
  cv::Mat weight = cv::Mat::zeros(frame.size(), CV_32F);
  cv::ellipse(weight, centre, axes, angle, 0, 360, cv::Scalar(1.0), cv::FILLED);
  cv::GaussianBlur(weight, weight, cv::Size(0, 0), sigma);
  for (int y = 0; y < frame.rows; ++y)
    for (int x = 0; x < frame.cols; ++x) {
      const float a = weight.at<float>(y, x);
      cv::Vec3b& p = frame.at<cv::Vec3b>(y, x);
      for (int c = 0; c < 3; ++c)
        p[c] = cv::saturate_cast<uchar>(p[c] * (1.0f - a) + colour[c] * a);
    }
}

} // namespace pickdetect::test_scene
