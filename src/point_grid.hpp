// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: points bucketed in square cells, for the mean shift's windows and the
// refinement's inlier scans.
#pragma once

#include <opencv2/core.hpp>

#include <unordered_map>
#include <vector>

namespace pickdetect::detail {

/// Points bucketed in square cells `cell` pixels wide; only occupied cells are stored (a hash
/// map), so a few points spread over a huge area cost nothing more. Immutable once built.
class PointGrid {
public:
  PointGrid() = default;
  PointGrid(std::vector<cv::Point2f> points, double cell);

  /// Calls visit(i) for every point in the 3x3 cells around `at`: all points within one cell
  /// width of it, and some farther.
  template <typename F> void for_neighbours(cv::Point2d at, F&& visit) const {
    const long cx = cell_index(at.x), cy = cell_index(at.y);
    for (long dy = -1; dy <= 1; ++dy)
      for (long dx = -1; dx <= 1; ++dx) {
        const auto it = cells_.find(pack(cx + dx, cy + dy));
        if (it != cells_.end())
          for (int i : it->second)
            visit(i);
      }
  }

  /// Indices of the points inside `box` (edges included), in increasing order.
  std::vector<int> inside(const cv::Rect2f& box) const;

  /// Index of the cell of width `cell` holding coordinate `v`. Cells far out (or not finite: a
  /// tiny width) are clamped into the last one, so that the conversion stays defined.
  static long cell_of(double v, double cell);
  /// One key for two cell indices.
  static long long pack(long x, long y);

private:
  long cell_index(double v) const { return cell_of(v, cell_); }

  std::vector<cv::Point2f> points_;
  double cell_ = 1.0;
  std::unordered_map<long long, std::vector<int>> cells_;
  long min_x_ = 0, max_x_ = -1, min_y_ = 0, max_y_ = -1; ///< Occupied cell range.
};

} // namespace pickdetect::detail
