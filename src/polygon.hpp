// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: boxes of points and points in polygons, for the tests between instances.
#pragma once

#include <opencv2/core.hpp>

#include <vector>

namespace pickdetect::detail {

/// Bounding box of points (edges on the extreme points; empty input: an empty box at 0).
cv::Rect2f bounds(const std::vector<cv::Point2f>& points);

/// Whether a point lies in a box (edges included).
bool in_box(const cv::Rect2f& box, const cv::Point2f& p);

/// Whether two boxes share a point (edges included).
bool touch(const cv::Rect2f& a, const cv::Rect2f& b);

/// How many of the points lie in the polygon (edges included). The polygon test runs only on
/// the points in the polygon's bounding box: it costs far more than the box test, and most
/// keypoints of a model or an instance lie outside a small shared area.
int count_inside(const std::vector<cv::Point2f>& points, const std::vector<cv::Point2f>& polygon);
int count_inside(const std::vector<cv::KeyPoint>& points, const std::vector<cv::Point2f>& polygon);

} // namespace pickdetect::detail
