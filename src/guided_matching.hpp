// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: guided matching, which completes a hypothesis that too few of the
// frame's 2NN matches support (a faint or steeply tilted face) from the model keypoints near
// where its pose carries each scene keypoint.
#pragma once

#include "model_scene.hpp"
#include "keypoint_grid.hpp"
#include "point_grid.hpp"

#include <pickdetect/features.hpp>

#include <opencv2/core.hpp>

#include <vector>

namespace pickdetect::detail {

/// Fewest votes of a hypothesis that guided matching completes (voting.cpp: models of faint
/// print only).
constexpr size_t kMinGuidedVotes = 2;
/// Fewest keypoints that guided matching must pair before its pose stands.
constexpr size_t kMinGuidedMatches = 5;

/// What guided matching searches, built once per model and frame where a hypothesis needs it.
class GuidedMatcher {
public:
  explicit GuidedMatcher(const ModelScene& ms);
  /// Pairs the scene keypoints on the outline of `pose` with model keypoints of a close
  /// descriptor near where the pose carries them, fits an affine map on them (RANSAC), pairs
  /// again near where that map carries them and fits a homography when they are
  /// kMinForeshortenedMatches or more. True, with the map `h` and the paired scene keypoints'
  /// positions in `support`, when kMinGuidedMatches or more agree with it. A homography that
  /// shows no front view fails it, unless `keep_affine` (a face found on a few matches bunched
  /// in one part of it): then the map before it stands.
  bool complete(const Similarity& pose, cv::Matx33d& h, std::vector<cv::Point2f>& support,
                bool keep_affine = false) const;

private:
  struct Pair {
    cv::Point2f model, scene;
  };
  /// For each scene keypoint inside `outline`, the model keypoint within `radius` model pixels
  /// of where `map` carries it back, at the rotation and size `near` predicts there, of the
  /// closest descriptor within the agreement distance.
  std::vector<Pair> pairs(const cv::Matx33d& map, const Similarity& near,
                          const std::vector<cv::Point2f>& outline, double radius) const;

  const ModelScene& ms_;
  KeypointGrid model_grid_;
  PointGrid scene_grid_;
  double reach_; ///< First pass's radius, model pixels.
};

} // namespace pickdetect::detail
