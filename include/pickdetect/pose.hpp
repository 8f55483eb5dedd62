// SPDX-License-Identifier: LGPL-2.1-or-later
#pragma once

#include <opencv2/core.hpp>

#include <vector>

namespace pickdetect {

/// scene = scale * R(angle) * model + translation, in image coordinates (y axis down), so a
/// positive angle turns clockwise on screen.
struct Similarity {
  double angle = 0.0; ///< Degrees in [0, 360).
  double scale = 1.0;
  cv::Point2d translation;

  cv::Point2f apply(cv::Point2f p) const;
  std::vector<cv::Point2f> apply(const std::vector<cv::Point2f>& points) const;
};

/// How a fit counts the distance r between a carried point and its pair.
enum class Loss {
  Squared, ///< r^2: least squares.
  Cauchy,  ///< log(1 + (r/s)^2), s from the residuals' median: pairs far off against the others
           ///< weigh little (an M-estimator, by iteratively reweighted least squares).
};

/// Least-squares similarity (or, without allow_scale, rigid transform) that carries `from`
/// onto `to` (Umeyama's closed form), each pair's squared distance counted `weights[i]` times
/// (all once when `weights` is empty). Needs two points or more; returns false when the fit is
/// degenerate or a weight is negative. With Loss::Cauchy, the least-squares fit is then
/// reweighted by the residuals a few times.
bool fit_similarity(const std::vector<cv::Point2f>& from, const std::vector<cv::Point2f>& to,
                    bool allow_scale, Similarity& out, const std::vector<double>& weights = {},
                    Loss loss = Loss::Squared);

/// Homography that carries `from` onto `to` with the least squared distance in `to`'s pixels
/// (Gauss-Newton on the eight free entries, in normalised coordinates), starting from `initial`,
/// which must already be close (e.g. a similarity fitted on the same points). Each pair's squared
/// distance counts `weights[i]` times (all once when `weights` is empty); with Loss::Cauchy each
/// step also reweights the pairs by their residuals. Needs four points or more; returns false
/// when the fit is degenerate or does not converge.
bool fit_homography(const std::vector<cv::Point2f>& from, const std::vector<cv::Point2f>& to,
                    const cv::Matx33d& initial, cv::Matx33d& out,
                    const std::vector<double>& weights = {}, Loss loss = Loss::Squared);

/// The similarity as a 3x3 matrix.
cv::Matx33d to_matrix(const Similarity& pose);

/// Similarity of a 3x3 homography near `at` (model coordinates): rotation and scale of the
/// homography's local linear part there, and where it carries `at`.
Similarity similarity_near(const cv::Matx33d& homography, cv::Point2f at);

/// Smallest angular difference in degrees between two angles, in [0, 180].
double angle_difference(double a, double b);

} // namespace pickdetect
