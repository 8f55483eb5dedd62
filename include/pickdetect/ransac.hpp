// SPDX-License-Identifier: LGPL-2.1-or-later
#pragma once

#include <pickdetect/features.hpp>

#include <opencv2/core.hpp>

#include <vector>

namespace pickdetect {

/// A homography fitted by RANSAC and the matches it kept.
struct HomographyFit {
  cv::Matx33d homography;
  std::vector<int> inliers; ///< Indices into the matches given.
};

/// The paper's baselines: RANSAC and least squares over the given matches (all of them, or one
/// mean-shift cluster). Returns false when no homography with at least `min_inliers` inliers
/// and a sane shape (orientation kept, finite) is found. Deterministic (fixed RANSAC seed).
bool fit_homography_ransac(const std::vector<Match>& matches,
                           const std::vector<cv::KeyPoint>& model_keypoints,
                           const std::vector<cv::KeyPoint>& scene_keypoints, double reprojection_px,
                           int min_inliers, HomographyFit& out);

} // namespace pickdetect
