// SPDX-License-Identifier: LGPL-2.1-or-later
// A camera tilted off vertical: the scene is laid out on a floor seen from straight above, and
// one homography (the floor plane through a pin-hole camera looking at the floor's centre from
// the tilted direction, the far side at the top of the frame) carries the floor and every
// instance on it into the frame. Each instance's homography is that one times its placement
// on the floor, so its annotations go through it exactly.
#include "synth.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>

namespace synth {

Camera tilted_camera(double degrees, cv::Size frame) {
  const double w = frame.width, h = frame.height;
  const double f = std::max(w, h); // about 53 degrees across the longer side
  const double phi = degrees * CV_PI / 180.0;
  // Floor point (u, v) about the point looked at; v < 0 is the far side. The camera at distance
  // f sees it at depth f - v sin(phi), so the floor's scale at the frame's centre is 1.
  auto project = [&](double u, double v) {
    const double z = f - v * std::sin(phi);
    return cv::Point2f(static_cast<float>(w / 2 + f * u / z),
                       static_cast<float>(h / 2 + f * v * std::cos(phi) / z));
  };
  const cv::Point2f floor_pts[4] = {
      {-100.f, -100.f}, {100.f, -100.f}, {100.f, 100.f}, {-100.f, 100.f}};
  cv::Point2f frame_pts[4];
  for (int k = 0; k < 4; ++k)
    frame_pts[k] = project(floor_pts[k].x, floor_pts[k].y);
  const cv::Matx33d to_frame(cv::getPerspectiveTransform(floor_pts, frame_pts));
  const cv::Matx33d to_floor = to_frame.inv();
  // The floor's picture: the bounding box of what the frame's corners see.
  double x0 = 1e18, y0 = 1e18, x1 = -1e18, y1 = -1e18;
  for (const cv::Point2d& c : apply(to_floor, {{0, 0}, {w, 0}, {w, h}, {0, h}})) {
    x0 = std::min(x0, c.x);
    y0 = std::min(y0, c.y);
    x1 = std::max(x1, c.x);
    y1 = std::max(y1, c.y);
  }
  Camera cam;
  cam.floor = cv::Size(static_cast<int>(std::ceil(x1 - x0)), static_cast<int>(std::ceil(y1 - y0)));
  cam.floor_to_frame = to_frame * cv::Matx33d(1, 0, x0, 0, 1, y0, 0, 0, 1);
  const double fw = cam.floor.width, fh = cam.floor.height;
  for (const cv::Point2d& c : std::vector<cv::Point2d>{{0, 0}, {fw, 0}, {fw, fh}, {0, fh}}) {
    const std::vector<cv::Point2d> q =
        apply(cam.floor_to_frame, {c, c + cv::Point2d(1, 0), c + cv::Point2d(0, 1)});
    cam.magnification = std::max({cam.magnification, cv::norm(q[1] - q[0]), cv::norm(q[2] - q[0])});
    const double out = std::max({-q[0].x, q[0].x - w, -q[0].y, q[0].y - h, 0.0});
    cam.excess = std::max(cam.excess, static_cast<int>(std::ceil(out)));
  }
  return cam;
}

} // namespace synth
