// SPDX-License-Identifier: LGPL-2.1-or-later
// A test scene of one face turned away from the camera (a pinhole camera looking at it).
#pragma once

#include "common/scene.hpp"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <vector>

namespace pickdetect::test_scene {

/// `picture` (grey) turned `tilt_deg` about its horizontal axis, scaled by `scale`, seen from
/// `distance` pixels away by a camera looking at its centre, in the middle of a plain frame of
/// `frame` pixels: foreshortened to cos(tilt) of its height, the far edge smaller. `h` gets the
/// homography carrying picture pixels into the frame.
inline cv::Mat tilted_face(const cv::Mat& picture, double tilt_deg, double scale, double distance,
                           const cv::Size& frame, cv::Matx33d& h) {
  const double tilt = tilt_deg * CV_PI / 180.0;
  const float w = static_cast<float>(picture.cols), hh = static_cast<float>(picture.rows);
  const std::vector<cv::Point2f> corners = {{0.f, 0.f}, {w, 0.f}, {w, hh}, {0.f, hh}};
  std::vector<cv::Point2f> seen;
  for (const cv::Point2f& p : corners) {
    const double x = (p.x - w / 2.0) * scale, y = (p.y - hh / 2.0) * scale;
    const double z = distance + y * std::sin(tilt);
    seen.emplace_back(static_cast<float>(frame.width / 2.0 + distance * x / z),
                      static_cast<float>(frame.height / 2.0 + distance * y * std::cos(tilt) / z));
  }
  h = cv::Matx33d(cv::getPerspectiveTransform(corners, seen));
  cv::Mat scene = plain_background(frame, 100), warped, mask;
  cv::warpPerspective(picture, warped, cv::Mat(h), frame, cv::INTER_AREA);
  cv::warpPerspective(cv::Mat(picture.size(), CV_8UC1, cv::Scalar(255)), mask, cv::Mat(h), frame,
                      cv::INTER_NEAREST);
  warped.copyTo(scene, mask);
  return scene;
}

} // namespace pickdetect::test_scene
