// SPDX-License-Identifier: LGPL-2.1-or-later
// Poses: similarity transforms, their least-squares fit (Umeyama, Eigen) and angle arithmetic.
#include <pickdetect/pose.hpp>

#include "median.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace pickdetect {
namespace {

double wrap_degrees(double a) {
  a = std::fmod(a, 360.0);
  return a < 0.0 ? a + 360.0 : a;
}

/// Gauss-Newton: at most this many steps, ended earlier by a step this small (normalised units).
constexpr int kHomographySteps = 10;
constexpr double kHomographyStop = 1e-10;
/// With Loss::Cauchy the weights move a little at every step: stop at steps this small
/// (about a hundredth of a pixel for an object 200 px across).
constexpr double kRobustHomographyStop = 1e-8;
/// Smallest pivot of the normal equations, relative to the largest, of a determined fit.
constexpr double kMinPivot = 1e-9;

/// Loss::Cauchy: weights 1 / (1 + (r / (k sigma))^2), k = 2.385 (95 % efficiency on Gaussian
/// noise), sigma the residuals' median * 1.4826, floored at kMinRobustSigmaPx (in `to`'s
/// pixels) so that a nearly exact fit does not single out pairs by noise far below a pixel.
/// The similarity is reweighted this many times.
constexpr double kCauchyK = 2.385;
constexpr double kMinRobustSigmaPx = 0.05;
constexpr int kRobustRounds = 5;

/// Weights for `n` pairs: none (all count once), or one per pair, none negative.
bool valid_weights(const std::vector<double>& weights, size_t n) {
  return weights.empty() || (weights.size() == n && std::all_of(weights.begin(), weights.end(),
                                                                [](double w) { return w >= 0.0; }));
}

/// Cauchy weights of `residuals` (any unit; `min_sigma` in the same), times `base` if given.
std::vector<double> cauchy_weights(const std::vector<double>& residuals, double min_sigma,
                                   const std::vector<double>& base) {
  const double sigma = std::max(min_sigma, 1.4826 * detail::median(residuals));
  std::vector<double> w(residuals.size());
  for (size_t k = 0; k < residuals.size(); ++k) {
    const double u = residuals[k] / (kCauchyK * sigma);
    w[k] = (base.empty() ? 1.0 : base[k]) / (1.0 + u * u);
  }
  return w;
}

/// Similarity normalisation (Hartley): centroid to the origin, mean distance sqrt(2).
Eigen::Matrix3d normaliser(const std::vector<cv::Point2f>& points) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const cv::Point2f& p : points)
    mean += Eigen::Vector2d(p.x, p.y);
  mean /= static_cast<double>(points.size());
  double spread = 0.0;
  for (const cv::Point2f& p : points)
    spread += (Eigen::Vector2d(p.x, p.y) - mean).norm();
  spread /= static_cast<double>(points.size());
  const double k = spread > 1e-12 ? std::sqrt(2.0) / spread : 1.0;
  Eigen::Matrix3d t;
  t << k, 0.0, -k * mean.x(), 0.0, k, -k * mean.y(), 0.0, 0.0, 1.0;
  return t;
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

namespace {

bool similarity_closed_form(const std::vector<cv::Point2f>& from,
                            const std::vector<cv::Point2f>& to, bool allow_scale,
                            const std::vector<double>& weights, Similarity& out) {
  // Umeyama's closed form in the plane, with weights (Eigen::umeyama has none): weighted
  // centroids, then the rotation and scale from the weighted cross-covariance.
  const size_t n = from.size();
  if (n < 2 || to.size() != n || !valid_weights(weights, n))
    return false;
  auto weight = [&](size_t i) { return weights.empty() ? 1.0 : weights[i]; };
  double total = 0.0;
  Eigen::Vector2d mean_from = Eigen::Vector2d::Zero(), mean_to = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < n; ++i) {
    const double w = weight(i);
    total += w;
    mean_from += w * Eigen::Vector2d(from[i].x, from[i].y);
    mean_to += w * Eigen::Vector2d(to[i].x, to[i].y);
  }
  if (!(total > 0.0))
    return false;
  mean_from /= total;
  mean_to /= total;
  double dot = 0.0, cross = 0.0, spread = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d x = Eigen::Vector2d(from[i].x, from[i].y) - mean_from;
    const Eigen::Vector2d y = Eigen::Vector2d(to[i].x, to[i].y) - mean_to;
    const double w = weight(i);
    dot += w * x.dot(y);
    cross += w * (x.x() * y.y() - x.y() * y.x());
    spread += w * x.squaredNorm();
  }
  if (!(spread > 1e-12 * total))
    return false;
  const double scale = allow_scale ? std::hypot(dot, cross) / spread : 1.0;
  if (!(scale > 1e-9) || !std::isfinite(scale))
    return false;
  const double angle = std::atan2(cross, dot);
  const Eigen::Vector2d t = mean_to - scale * (Eigen::Rotation2Dd(angle) * mean_from);
  out.scale = scale;
  out.angle = wrap_degrees(angle * 180.0 / CV_PI);
  out.translation = cv::Point2d(t.x(), t.y());
  return true;
}

} // namespace

bool fit_similarity(const std::vector<cv::Point2f>& from, const std::vector<cv::Point2f>& to,
                    bool allow_scale, Similarity& out, const std::vector<double>& weights,
                    Loss loss) {
  Similarity fit;
  if (!similarity_closed_form(from, to, allow_scale, weights, fit))
    return false;
  if (loss == Loss::Cauchy)
    for (int round = 0; round < kRobustRounds; ++round) {
      const cv::Matx33d m = to_matrix(fit);
      std::vector<double> r(from.size());
      for (size_t i = 0; i < from.size(); ++i)
        r[i] = std::hypot(m(0, 0) * from[i].x + m(0, 1) * from[i].y + m(0, 2) - to[i].x,
                          m(1, 0) * from[i].x + m(1, 1) * from[i].y + m(1, 2) - to[i].y);
      Similarity next;
      if (!similarity_closed_form(from, to, allow_scale,
                                  cauchy_weights(r, kMinRobustSigmaPx, weights), next))
        break;
      fit = next;
    }
  out = fit;
  return true;
}

cv::Matx33d to_matrix(const Similarity& pose) {
  const double rad = pose.angle * CV_PI / 180.0;
  const double c = std::cos(rad) * pose.scale, s = std::sin(rad) * pose.scale;
  return {c, -s, pose.translation.x, s, c, pose.translation.y, 0.0, 0.0, 1.0};
}

bool fit_homography(const std::vector<cv::Point2f>& from, const std::vector<cv::Point2f>& to,
                    const cv::Matx33d& initial, cv::Matx33d& out,
                    const std::vector<double>& weights, Loss loss) {
  const size_t n = from.size();
  if (n < 4 || to.size() != n || !valid_weights(weights, n))
    return false;
  // In normalised coordinates the eight unknowns have comparable sizes, so the normal
  // equations stay well conditioned; the residuals are scaled by the scene's factor only.
  const Eigen::Matrix3d tf = normaliser(from), tt = normaliser(to);
  Eigen::Matrix3d h0;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      h0(r, c) = initial(r, c);
  Eigen::Matrix3d hn = tt * h0 * tf.inverse();
  if (!(std::abs(hn(2, 2)) > 1e-12))
    return false;
  hn /= hn(2, 2);
  std::vector<Eigen::Vector2d> x(n), y(n);
  for (size_t i = 0; i < n; ++i) {
    x[i] = (tf * Eigen::Vector3d(from[i].x, from[i].y, 1.0)).head<2>();
    y[i] = (tt * Eigen::Vector3d(to[i].x, to[i].y, 1.0)).head<2>();
  }
  // Cauchy: each step reweights the pairs by their residuals under the current estimate
  // (iteratively reweighted Gauss-Newton); the sigma floor in normalised units.
  const double min_sigma = kMinRobustSigmaPx * tt(0, 0);
  std::vector<Eigen::Vector2d> mapped(n);
  std::vector<double> denominators(n), residuals(loss == Loss::Cauchy ? n : 0), robust;
  for (int step = 0; step < kHomographySteps; ++step) {
    for (size_t i = 0; i < n; ++i) {
      const double px = x[i].x(), py = x[i].y();
      const double w = hn(2, 0) * px + hn(2, 1) * py + 1.0;
      if (!(w > 1e-9))
        return false; // A point maps behind the camera: no valid picture of the object.
      denominators[i] = w;
      mapped[i] = Eigen::Vector2d((hn(0, 0) * px + hn(0, 1) * py + hn(0, 2)) / w,
                                  (hn(1, 0) * px + hn(1, 1) * py + hn(1, 2)) / w);
      if (loss == Loss::Cauchy)
        residuals[i] = (mapped[i] - y[i]).norm();
    }
    if (loss == Loss::Cauchy)
      robust = cauchy_weights(residuals, min_sigma, weights);
    const std::vector<double>& wts = loss == Loss::Cauchy ? robust : weights;
    Eigen::Matrix<double, 8, 8> jtj = Eigen::Matrix<double, 8, 8>::Zero();
    Eigen::Matrix<double, 8, 1> jtr = Eigen::Matrix<double, 8, 1>::Zero();
    for (size_t i = 0; i < n; ++i) {
      const double px = x[i].x(), py = x[i].y(), w = denominators[i];
      const double u = mapped[i].x(), v = mapped[i].y();
      Eigen::Matrix<double, 2, 8> j;
      j << px / w, py / w, 1.0 / w, 0.0, 0.0, 0.0, -u * px / w, -u * py / w, //
          0.0, 0.0, 0.0, px / w, py / w, 1.0 / w, -v * px / w, -v * py / w;
      const Eigen::Vector2d r = mapped[i] - y[i];
      const double wt = wts.empty() ? 1.0 : wts[i];
      // A fixed-size product: Eigen evaluates it in place, where a rank update of the lower
      // half goes through its general matrix kernel, dear at these sizes.
      jtj.noalias() += wt * j.transpose() * j;
      jtr.noalias() += wt * j.transpose() * r;
    }
    const Eigen::LDLT<Eigen::Matrix<double, 8, 8>, Eigen::Lower> solver(jtj);
    // A (near) zero pivot: the points do not fix the eight unknowns (collinear, repeated).
    const Eigen::Matrix<double, 8, 1> pivots = solver.vectorD();
    if (solver.info() != Eigen::Success || !(pivots.minCoeff() > kMinPivot * pivots.maxCoeff()))
      return false;
    const Eigen::Matrix<double, 8, 1> delta = solver.solve(-jtr);
    if (!delta.allFinite())
      return false;
    for (int k = 0; k < 8; ++k)
      hn(k / 3, k % 3) += delta(k);
    if (delta.squaredNorm() < (loss == Loss::Cauchy ? kRobustHomographyStop : kHomographyStop))
      break;
  }
  const Eigen::Matrix3d h = tt.inverse() * hn * tf;
  if (!h.allFinite() || !(std::abs(h(2, 2)) > 1e-12))
    return false;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      out(r, c) = h(r, c) / h(2, 2);
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
  if (a >= 0.0 && a < 360.0 && b >= 0.0 && b < 360.0) { // Wrapped already: no fmod.
    const double d = std::fabs(a - b);
    return d > 180.0 ? 360.0 - d : d;
  }
  const double d = std::fabs(wrap_degrees(a - b));
  return d > 180.0 ? 360.0 - d : d;
}

} // namespace pickdetect
