// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: keypoints bucketed by place and orientation, for the searches that pair
// a scene keypoint with the model keypoints near where a pose carries it, turned as it predicts.
#pragma once

#include <opencv2/core.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>
#include <vector>

namespace pickdetect::detail {

/// Keypoints bucketed in square cells `cell` pixels wide and, within a cell, in orientation bins
/// kAngleBinDeg wide (those whose angle is no number apart, found at every turn), each bin's
/// keypoints in order of size. Only occupied cells are stored. Immutable once built.
class KeypointGrid {
public:
  /// Width of an orientation bin (degrees): a search reaches one bin either side of the one its
  /// orientation falls in, so every keypoint within this many degrees of it is visited.
  static constexpr double kAngleBinDeg = 30.0;

  KeypointGrid() = default;
  KeypointGrid(const std::vector<cv::KeyPoint>& keypoints, double cell);

  /// Calls visit(i) for every keypoint in the 3x3 cells around `at` whose orientation lies in
  /// the bin of `angle` (degrees, any turn) or the bins either side and whose size lies within
  /// [min_size, max_size] (a keypoint without a size, 0, is always visited): all keypoints
  /// within one cell width of `at` and kAngleBinDeg of `angle` of such a size, and some farther
  /// or more turned. An angle that is no number asks for every turn. No order is promised.
  template <typename F>
  void for_neighbours(cv::Point2d at, double angle, float min_size, float max_size,
                      F&& visit) const {
    const long cx = cell_index(at.x), cy = cell_index(at.y);
    const bool every_turn = !std::isfinite(angle);
    const int first = every_turn ? 0 : angle_bin(angle) + kAngleBins - 1;
    const int bins = every_turn ? kAngleBins : 3;
    for (long dy = -1; dy <= 1; ++dy)
      for (long dx = -1; dx <= 1; ++dx) {
        const auto it = cells_.find(pack(cx + dx, cy + dy));
        if (it == cells_.end())
          continue;
        const Cell& c = it->second;
        for (int j = 0; j < bins; ++j)
          visit_sized(c.turned[static_cast<size_t>((first + j) % kAngleBins)], min_size, max_size,
                      visit);
        visit_sized(c.unturned, min_size, max_size, visit);
      }
  }

private:
  struct Entry {
    float size;
    int index;
  };
  static bool by_size(const Entry& e, float size) { return e.size < size; }
  static constexpr int kAngleBins = static_cast<int>(360.0 / kAngleBinDeg);
  static_assert(kAngleBins * kAngleBinDeg == 360.0, "orientation bins must tile the turn");
  struct Cell {
    std::array<std::vector<Entry>, kAngleBins> turned;
    std::vector<Entry> unturned; ///< Angle no number.
  };

  /// Visits the unsized entries of `in` (sorted by size: they come first) and those sized within
  /// [min_size, max_size].
  template <typename F>
  static void visit_sized(const std::vector<Entry>& in, float min_size, float max_size, F& visit) {
    auto e = in.begin();
    for (; e != in.end() && !(e->size > 0.f); ++e)
      visit(e->index);
    for (e = std::lower_bound(e, in.end(), min_size, by_size); e != in.end() && e->size <= max_size;
         ++e)
      visit(e->index);
  }

  long cell_index(double v) const;
  static int angle_bin(double angle);
  static long long pack(long x, long y);

  double cell_ = 1.0;
  std::unordered_map<long long, Cell> cells_;
};

} // namespace pickdetect::detail
