// SPDX-License-Identifier: LGPL-2.1-or-later
#pragma once

#include <pickdetect/detector.hpp>

#include <opencv2/core.hpp>

#include <vector>

namespace pickdetect {

/// Share of an outline's area that another outline must cover for the two to count as
/// overlapping (absorbs the pose noise of two instances that only touch).
constexpr double kOverlapTolerance = 0.005;

/// Area of the intersection of two outlines, in square pixels (outlines are taken as convex).
double overlap_area(const std::vector<cv::Point2f>& a, const std::vector<cv::Point2f>& b);

/// Sets each instance's visibility (share of its outline inside the frame), pickable flag (its
/// outline overlaps no other instance's) and pick order (1 = first, by score, among pickable).
void assess_occlusion(std::vector<Instance>& instances, const cv::Size& frame_size);

} // namespace pickdetect
