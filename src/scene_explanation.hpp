// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: the set of instances that together explain the frame's features.
#pragma once

#include <pickdetect/detector.hpp>
#include <pickdetect/features.hpp>
#include <pickdetect/model.hpp>

#include <vector>

namespace pickdetect::detail {

/// One visible surface, one object. Each instance claims the scene keypoints it explains: those
/// that lie on its outline and whose descriptor resembles that of a model keypoint where its
/// pose puts that keypoint (same place, rotation and size). Instances are taken in order of how
/// many keypoints they explain, each keypoint going to the first that explains it; an instance
/// is kept only when it still explains at least `min_matches` keypoints of its own, nearly all
/// of those it explains are its own, and they spread over enough of the model to place it; one
/// that rests on few matches must also explain more than the chance share of the keypoints on
/// its outline (a few agree by chance wherever the frame is dense with print); one that explains
/// few keypoints must also show its print in the frame's pixels where it is seen (`grey`, the
/// frame as CV_8UC1; empty: no such test; `motion_blur`, the frame's, compare_cells). A copy
/// of an instance shifted along a repeated design, a second pose of one object and an instance
/// spanning two neighbours rest on keypoints that a better instance explains, and lose to it.
void explain_scene(std::vector<Instance>& instances, const std::vector<Model>& models,
                   const Features& scene, FeatureKind kind, int min_matches,
                   const cv::Mat& grey = cv::Mat(), const cv::Point2f& motion_blur = cv::Point2f());

} // namespace pickdetect::detail
