// SPDX-License-Identifier: LGPL-2.1-or-later
#pragma once

#include <opencv2/core.hpp>

#include <vector>

namespace pickdetect {

/// SIFT keypoints and their descriptors (CV_32F, one row per keypoint).
struct Features {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
};

/// SIFT on a grey picture (CV_8UC1, any stride); an optional mask limits where keypoints lie.
Features extract_features(const cv::Mat& grey, const cv::Mat& mask = cv::Mat());

/// A correspondence between a model keypoint and a scene keypoint that passed the 2NN test.
struct Match {
  int model = 0;        ///< Index of the model (in the detector's model list).
  int model_point = 0;  ///< Keypoint index in that model.
  int scene_point = 0;  ///< Keypoint index in the scene.
  float distance = 0.f; ///< Descriptor distance to the nearest neighbour.
  float ratio = 0.f;    ///< Nearest / second nearest distance (lower is more distinctive).
};

} // namespace pickdetect
