// SPDX-License-Identifier: LGPL-2.1-or-later
// Model features that survive a face seen far off its normal: the model picture seen under
// simulated tilts (ASIFT's view simulation), each view's keypoints carried back to the picture.
#include <pickdetect/features.hpp>

#include "object_mask.hpp"

#include <opencv2/imgproc.hpp>

#include <cmath>

namespace pickdetect {
namespace {

/// ASIFT's anti-aliasing before the compression of a tilt t: a Gaussian of 0.8 * sqrt(t^2 - 1)
/// pixels across the compressed axis.
constexpr double kAntiAliasSigma = 0.8;

} // namespace

std::vector<TiltedView> tilted_views(double max_tilt_deg) {
  std::vector<TiltedView> views;
  // Tilts t = 1 / cos(theta) in steps of sqrt(2) (ASIFT's), up to max_tilt_deg; for each, the
  // face turned in steps of 72 / t degrees over half a turn.
  const double max_t = 1.0 / std::cos(max_tilt_deg * CV_PI / 180.0);
  for (double t = std::sqrt(2.0); t <= max_t * 1.0001; t *= std::sqrt(2.0)) {
    const double step = 72.0 / t;
    for (double phi = 0.0; phi < 180.0 - 1e-6; phi += step)
      views.push_back({t, phi});
  }
  return views;
}

Features features_of_view(const cv::Mat& grey, const cv::Mat& mask, const TiltedView& view,
                          double contrast_threshold) {
  // The view: the picture turned by phi, then compressed by t along x (the face tilted about
  // the y axis of the turned picture). `a` carries picture pixels into the view.
  const double rad = view.phi * CV_PI / 180.0;
  const double c = std::cos(rad), s = std::sin(rad);
  cv::Matx23d a(c, -s, 0.0, s, c, 0.0);
  std::vector<cv::Point2f> corners = {
      {0.f, 0.f},
      {static_cast<float>(grey.cols), 0.f},
      {static_cast<float>(grey.cols), static_cast<float>(grey.rows)},
      {0.f, static_cast<float>(grey.rows)}};
  cv::transform(corners, corners, a);
  const cv::Rect box = cv::boundingRect(corners);
  a(0, 2) = -box.x;
  a(1, 2) = -box.y;
  cv::Mat turned, turned_mask;
  cv::warpAffine(grey, turned, a, box.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  cv::warpAffine(detail::object_mask(mask, grey.size()), turned_mask, a, box.size(),
                 cv::INTER_NEAREST, cv::BORDER_CONSTANT);
  cv::GaussianBlur(turned, turned, cv::Size(0, 0),
                   kAntiAliasSigma * std::sqrt(view.tilt * view.tilt - 1.0), 0.01);
  cv::Mat squeezed, squeezed_mask;
  cv::resize(turned, squeezed, cv::Size(), 1.0 / view.tilt, 1.0, cv::INTER_LINEAR);
  cv::resize(turned_mask, squeezed_mask, squeezed.size(), 0, 0, cv::INTER_NEAREST);
  Features f = extract_features(squeezed, squeezed_mask, FeatureKind::Sift, contrast_threshold);
  // Back into the picture: the view's pixels x_v = S (A x + b), S = diag(1/t, 1).
  const cv::Matx22d sa(a(0, 0) / view.tilt, a(0, 1) / view.tilt, a(1, 0), a(1, 1));
  const cv::Matx22d back = sa.inv();
  // cv::resize aligns pixel centres: view pixel x covers turned pixel (x + 0.5) * t - 0.5.
  std::vector<cv::KeyPoint> kept;
  cv::Mat rows;
  for (size_t i = 0; i < f.keypoints.size(); ++i) {
    cv::KeyPoint k = f.keypoints[i];
    const cv::Vec2d v((k.pt.x + 0.5) * view.tilt - 0.5, k.pt.y);
    const cv::Vec2d turned_pt(v[0] - a(0, 2), v[1] - a(1, 2));
    const cv::Matx22d rot_back(a(0, 0), a(1, 0), a(0, 1), a(1, 1)); // A's inverse (a rotation)
    const cv::Vec2d p = rot_back * turned_pt;
    // The keypoint's direction and size carried back through the view's inverse map.
    const double ang = k.angle * CV_PI / 180.0;
    const cv::Vec2d dir = back * cv::Vec2d(std::cos(ang), std::sin(ang));
    double angle = std::atan2(dir[1], dir[0]) * 180.0 / CV_PI;
    if (angle < 0.0)
      angle += 360.0;
    k.pt = cv::Point2f(static_cast<float>(p[0]), static_cast<float>(p[1]));
    k.angle = static_cast<float>(angle);
    k.size = static_cast<float>(k.size * std::sqrt(view.tilt));
    if (k.pt.x < 0.f || k.pt.y < 0.f || k.pt.x > grey.cols - 1.f || k.pt.y > grey.rows - 1.f)
      continue;
    kept.push_back(k);
    rows.push_back(f.descriptors.row(static_cast<int>(i)));
  }
  f.keypoints = std::move(kept);
  f.descriptors = rows;
  return f;
}

} // namespace pickdetect
