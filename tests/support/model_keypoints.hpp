// SPDX-License-Identifier: LGPL-2.1-or-later
// A model's own keypoints (those of its picture, not of its tilted views), for tests that build
// a frame's features from them.
#pragma once

#include <pickdetect/pickdetect.hpp>

#include <opencv2/core.hpp>

#include <cstddef>

namespace pickdetect::test_scene {

/// How many of the model's SIFT keypoints are its picture's own: they come first, then its
/// tilted views'.
inline size_t own_keypoints(const Model& model) {
  return extract_features(model.image, model.mask, FeatureKind::Sift, model.contrast_threshold)
      .keypoints.size();
}

/// The strongest (by response) of the model's first `own` keypoints (own_keypoints: counted
/// once by the caller, a SIFT run on the picture) for which `wanted(index, keypoint)` holds, or
/// -1 when none does.
template <typename Wanted>
int strongest_own_keypoint(const Model& model, size_t own, Wanted&& wanted) {
  int best = -1;
  for (size_t i = 0; i < own; ++i) {
    const cv::KeyPoint& k = model.sift.keypoints[i];
    if (wanted(static_cast<int>(i), k) &&
        (best < 0 || k.response > model.sift.keypoints[static_cast<size_t>(best)].response))
      best = static_cast<int>(i);
  }
  return best;
}

} // namespace pickdetect::test_scene
