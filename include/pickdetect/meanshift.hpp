// SPDX-License-Identifier: LGPL-2.1-or-later
#pragma once

#include <opencv2/core.hpp>

#include <vector>

namespace pickdetect {

/// A mode of the vote density and the votes it gathered.
struct Cluster {
  cv::Point2f mode;
  std::vector<int> members; ///< Indices into the clustered points, ascending.
};

/// Mean shift with a flat kernel of radius `bandwidth` (pixels), started from every point.
/// Modes closer than `bandwidth` to a stronger one are merged into it; every point joins the
/// nearest mode within `bandwidth` (points farther from all modes join none). Clusters come out
/// strongest first. Deterministic: the result depends only on the points and their order.
std::vector<Cluster> mean_shift_clusters(const std::vector<cv::Point2f>& points, double bandwidth);

/// The mode of `points` reached by mean shift (flat kernel, radius `bandwidth`) from `start`.
cv::Point2f mean_shift_mode(const std::vector<cv::Point2f>& points, cv::Point2f start,
                            double bandwidth);

} // namespace pickdetect
