// SPDX-License-Identifier: LGPL-2.1-or-later
#pragma once

#include <pickdetect/features.hpp>

#include <opencv2/core.hpp>

#include <vector>

namespace pickdetect {

/// The roto-translation (and, with allow_scale, scaling) one match implies, and where it puts
/// each principal point of the model in the scene.
struct Vote {
  float angle = 0.f; ///< Degrees in [0, 360), scene keypoint angle minus model keypoint angle.
  float scale = 1.f; ///< Scene keypoint size / model keypoint size (1 without allow_scale).
  std::vector<cv::Point2f> points; ///< One estimate per principal point; [0] is the centre.
};

/// Casts one vote per match: the match's two keypoints (position, orientation and, with
/// allow_scale, size) give the transform that carries each principal point into the scene.
std::vector<Vote> cast_votes(const std::vector<Match>& matches,
                             const std::vector<cv::KeyPoint>& model_keypoints,
                             const std::vector<cv::KeyPoint>& scene_keypoints,
                             const std::vector<cv::Point2f>& principal_points, bool allow_scale);

} // namespace pickdetect
