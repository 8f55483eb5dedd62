// SPDX-License-Identifier: LGPL-2.1-or-later
// Poses: similarity transforms, their least-squares fit (Umeyama, Eigen) and angle arithmetic.
#include <pickdetect/pose.hpp>

#include <Eigen/Geometry>

#include <cmath>

namespace pickdetect {
namespace {

double wrap_degrees(double a) {
  a = std::fmod(a, 360.0);
  return a < 0.0 ? a + 360.0 : a;
}

} // namespace

cv::Point2f Similarity::apply(cv::Point2f p) const {
  const double rad = angle * CV_PI / 180.0;
  const double c = std::cos(rad) * scale, s = std::sin(rad) * scale;
  return cv::Point2f(static_cast<float>(c * p.x - s * p.y + translation.x),
                     static_cast<float>(s * p.x + c * p.y + translation.y));
}

std::vector<cv::Point2f> Similarity::apply(const std::vector<cv::Point2f>& points) const {
  std::vector<cv::Point2f> out;
  out.reserve(points.size());
  for (const cv::Point2f& p : points)
    out.push_back(apply(p));
  return out;
}

bool fit_similarity(const std::vector<cv::Point2f>& from, const std::vector<cv::Point2f>& to,
                    bool allow_scale, Similarity& out) {
  const size_t n = from.size();
  if (n < 2 || to.size() != n)
    return false;
  Eigen::MatrixXd src(2, n), dst(2, n);
  for (size_t i = 0; i < n; ++i) {
    src.col(i) << from[i].x, from[i].y;
    dst.col(i) << to[i].x, to[i].y;
  }
  const Eigen::VectorXd spread = (src.colwise() - src.rowwise().mean()).rowwise().norm();
  if (spread.norm() < 1e-6)
    return false;
  const Eigen::MatrixXd t = Eigen::umeyama(src, dst, allow_scale);
  if (!t.allFinite())
    return false;
  const Eigen::Matrix2d a = t.topLeftCorner(2, 2);
  const double scale = std::sqrt(std::abs(a.determinant()));
  if (!(scale > 1e-9) || a.determinant() < 0.0)
    return false;
  out.scale = scale;
  out.angle = wrap_degrees(std::atan2(a(1, 0), a(0, 0)) * 180.0 / CV_PI);
  out.translation = cv::Point2d(t(0, 2), t(1, 2));
  return true;
}

Similarity similarity_near(const cv::Matx33d& h, cv::Point2f at) {
  const double x = at.x, y = at.y;
  const double w = h(2, 0) * x + h(2, 1) * y + h(2, 2);
  const double u = h(0, 0) * x + h(0, 1) * y + h(0, 2);
  const double v = h(1, 0) * x + h(1, 1) * y + h(1, 2);
  // Jacobian of the projective map at `at`.
  const double j00 = (h(0, 0) * w - u * h(2, 0)) / (w * w);
  const double j01 = (h(0, 1) * w - u * h(2, 1)) / (w * w);
  const double j10 = (h(1, 0) * w - v * h(2, 0)) / (w * w);
  const double j11 = (h(1, 1) * w - v * h(2, 1)) / (w * w);
  Similarity s;
  // Closest similarity to the Jacobian: rotation of its conformal part.
  const double a = (j00 + j11) / 2.0, b = (j10 - j01) / 2.0;
  s.angle = wrap_degrees(std::atan2(b, a) * 180.0 / CV_PI);
  s.scale = std::sqrt(std::abs(j00 * j11 - j01 * j10));
  const cv::Point2f mapped(static_cast<float>(u / w), static_cast<float>(v / w));
  const cv::Point2f rotated = Similarity{s.angle, s.scale, {0.0, 0.0}}.apply(at);
  s.translation = cv::Point2d(mapped.x - rotated.x, mapped.y - rotated.y);
  return s;
}

double angle_difference(double a, double b) {
  const double d = std::fabs(wrap_degrees(a - b));
  return d > 180.0 ? 360.0 - d : d;
}

} // namespace pickdetect
