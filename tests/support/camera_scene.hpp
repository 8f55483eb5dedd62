// SPDX-License-Identifier: LGPL-2.1-or-later
// Pictures rendered through a known camera (pinhole, radial distortion) looking at a known
// plane: chessboards for the calibration, and boxes whose top face lies a known height above
// the plane for positions in millimetres. Every pixel's ray is cast, so the truth is exact.
#pragma once

#include <pickdetect/calibration.hpp>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace pickdetect::camera_scene {

/// A camera of the tests: 1 mm per pixel about 900 mm away, barrel distortion.
inline Calibration test_camera(const cv::Size& size = {800, 600}) {
  Calibration c;
  c.kind = CalibrationKind::CameraPlane;
  c.image_size = size;
  c.camera_matrix = cv::Matx33d(900.0, 0.0, size.width / 2.0 - 3.5, 0.0, 902.0,
                                size.height / 2.0 + 2.5, 0.0, 0.0, 1.0);
  c.distortion = {-0.18, 0.09, 0.0, 0.0, 0.0};
  return c;
}

/// The plane pose of a camera looking at plane point `target` (mm) from `distance` mm, its
/// optical axis tilted by `tilt_deg` from the plane's normal (about the camera's x axis, then
/// turned by `turn_deg` about the normal). The camera sees the plane's x axis to the right and
/// its y axis down when untilted (plane z away from the camera, as for a chessboard).
inline void look_at(Calibration& c, const cv::Point2d& target, double distance, double tilt_deg,
                    double turn_deg = 0.0) {
  const double a = tilt_deg * CV_PI / 180.0, b = turn_deg * CV_PI / 180.0;
  const cv::Matx33d tilt(1, 0, 0, 0, std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a));
  const cv::Matx33d turn(std::cos(b), -std::sin(b), 0, std::sin(b), std::cos(b), 0, 0, 0, 1);
  c.plane_rotation = tilt * turn;
  c.plane_translation =
      cv::Vec3d(0, 0, distance) - c.plane_rotation * cv::Vec3d(target.x, target.y, 0);
}

/// Each pixel's undistorted normalised coordinates (CV_64FC2), the same for every pose.
inline cv::Mat normalised_rays(const Calibration& c) {
  std::vector<cv::Point2d> pixels;
  pixels.reserve(static_cast<size_t>(c.image_size.area()));
  for (int y = 0; y < c.image_size.height; y++)
    for (int x = 0; x < c.image_size.width; x++)
      pixels.emplace_back(x, y);
  std::vector<cv::Point2d> out;
  cv::undistortPoints(pixels, out, c.camera_matrix, c.distortion, cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 50, 1e-12));
  return cv::Mat(out, true).reshape(2, c.image_size.height);
}

/// Where the ray of the pixel with normalised coordinates `n` meets the plane raised by
/// `height` mm towards the camera (x, y in plane mm), and the pixel's footprint there (mm).
struct Hit {
  cv::Point2d at;
  bool ok = false;
};

inline Hit cast(const Calibration& c, const cv::Vec2d& n, double height) {
  const cv::Matx33d rt = c.plane_rotation.t();
  const cv::Vec3d centre = -(rt * c.plane_translation);
  const double z = centre[2] >= 0 ? height : -height;
  const cv::Vec3d ray = rt * cv::Vec3d(n[0], n[1], 1.0);
  const double s = (z - centre[2]) / ray[2];
  if (!(s > 0))
    return {};
  return {{centre[0] + s * ray[0], centre[1] + s * ray[1]}, true};
}

/// A chessboard of `pattern` lying on the plane (origin at its first inner corner, x along its
/// rows), one square of white margin around it, on a mid-grey floor. Edges are anti-aliased
/// over each pixel's footprint, so the corners found are unbiased.
inline cv::Mat render_chessboard(const Calibration& c, const cv::Mat& rays,
                                 const ChessboardPattern& pattern) {
  const double s = pattern.square_mm;
  const double x0 = -2 * s, x1 = (pattern.inner_corners.width + 1) * s;
  const double y0 = -2 * s, y1 = (pattern.inner_corners.height + 1) * s;
  cv::Mat plane_x(rays.size(), CV_64F), plane_y(rays.size(), CV_64F);
  for (int y = 0; y < rays.rows; y++)
    for (int x = 0; x < rays.cols; x++) {
      const Hit h = cast(c, rays.at<cv::Vec2d>(y, x), 0.0);
      plane_x.at<double>(y, x) = h.ok ? h.at.x : 1e9;
      plane_y.at<double>(y, x) = h.ok ? h.at.y : 1e9;
    }
  cv::Mat out(rays.size(), CV_8UC1);
  // A square wave of the plane coordinate, box-filtered over a footprint `w` wide: the value
  // ramps linearly across each edge.
  auto wave = [s](double u, double w) {
    const double phase = u / s + 1.0; // Edges at integers; the first inner corner at u = 0.
    const double dist = std::abs(phase - std::round(phase)) * s;
    const double sign = (static_cast<long>(std::floor(phase)) % 2 == 0) ? 1.0 : -1.0;
    return sign * std::clamp(dist / std::max(w * 0.5, 1e-9), 0.0, 1.0);
  };
  for (int y = 0; y < rays.rows; y++)
    for (int x = 0; x < rays.cols; x++) {
      const double u = plane_x.at<double>(y, x), v = plane_y.at<double>(y, x);
      const int xn = std::min(x + 1, rays.cols - 1), yn = std::min(y + 1, rays.rows - 1);
      const double wu =
          std::abs(plane_x.at<double>(y, xn) - u) + std::abs(plane_x.at<double>(yn, x) - u);
      const double wv =
          std::abs(plane_y.at<double>(y, xn) - v) + std::abs(plane_y.at<double>(yn, x) - v);
      double value = 110.0;
      if (u > x0 && u < x1 && v > y0 && v < y1) {
        value = 235.0;
        if (u > -s && u < x1 - s && v > -s && v < y1 - s)
          value = 130.0 - 105.0 * wave(u, wu) * wave(v, wv); // Corner squares black.
      }
      out.at<uchar>(y, x) = cv::saturate_cast<uchar>(value);
    }
  return out;
}

/// A box lying on the plane: the model picture on its top face, `height` mm above the plane,
/// its centre (the picture's centre) at `center` (mm), its picture's x axis at `angle_deg`
/// from the plane's x axis towards its y axis; `mm_per_model_px` sizes it.
struct Box {
  cv::Point2d center;
  double angle_deg = 0.0;
  double height = 0.0;
  double mm_per_model_px = 0.5;
};

/// The boxes seen through the camera on a floor of mild noise. `model` is the grey picture;
/// its texture is sampled (bilinear) from a copy shrunk to about the frame's resolution.
inline cv::Mat render_boxes(const Calibration& c, const cv::Mat& rays, const cv::Mat& model,
                            const std::vector<Box>& boxes, int seed = 11) {
  cv::Mat out(rays.size(), CV_8UC1);
  cv::RNG rng(static_cast<uint64>(seed));
  cv::Mat texture;
  cv::pyrDown(model, texture); // texture pixel j shows model pixel 2j.
  const cv::Point2d half(model.cols / 2.0, model.rows / 2.0);
  for (int y = 0; y < rays.rows; y++)
    for (int x = 0; x < rays.cols; x++) {
      const cv::Vec2d n = rays.at<cv::Vec2d>(y, x);
      double value = 110.0 + rng.gaussian(3.0);
      double best_height = -1.0; // The highest top face hit lies in front.
      for (const Box& b : boxes) {
        if (b.height <= best_height)
          continue;
        const Hit h = cast(c, n, b.height);
        if (!h.ok)
          continue;
        const double a = b.angle_deg * CV_PI / 180.0;
        const cv::Point2d d = h.at - b.center;
        // Plane to model pixels: turn back by the angle, then scale.
        const cv::Point2d m(half.x + (std::cos(a) * d.x + std::sin(a) * d.y) / b.mm_per_model_px,
                            half.y + (-std::sin(a) * d.x + std::cos(a) * d.y) / b.mm_per_model_px);
        if (m.x < 0 || m.y < 0 || m.x > model.cols - 1 || m.y > model.rows - 1)
          continue;
        const double tx = m.x / 2.0, ty = m.y / 2.0;
        const int ix = std::min(static_cast<int>(tx), texture.cols - 2);
        const int iy = std::min(static_cast<int>(ty), texture.rows - 2);
        const double fx = tx - ix, fy = ty - iy;
        value = (1 - fx) * (1 - fy) * texture.at<uchar>(iy, ix) +
                fx * (1 - fy) * texture.at<uchar>(iy, ix + 1) +
                (1 - fx) * fy * texture.at<uchar>(iy + 1, ix) +
                fx * fy * texture.at<uchar>(iy + 1, ix + 1);
        best_height = b.height;
      }
      out.at<uchar>(y, x) = cv::saturate_cast<uchar>(value);
    }
  return out;
}

} // namespace pickdetect::camera_scene
