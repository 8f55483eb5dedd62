// SPDX-License-Identifier: LGPL-2.1-or-later
#include "keypoint_grid.hpp"

#include "point_grid.hpp"

#include <algorithm>
#include <cmath>

namespace pickdetect::detail {

KeypointGrid::KeypointGrid(const std::vector<cv::KeyPoint>& keypoints, double cell) : cell_(cell) {
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const cv::KeyPoint& k = keypoints[i];
    // A size that is no number sorts with the unsized: visited always, as placed_alike decides.
    const float size = k.size > 0.f ? k.size : 0.f;
    Cell& cell = cells_[pack(cell_index(k.pt.x), cell_index(k.pt.y))];
    (std::isfinite(k.angle) ? cell.turned[static_cast<size_t>(angle_bin(k.angle))] : cell.unturned)
        .push_back({size, static_cast<int>(i)});
  }
  const auto by_size_then_index = [](const Entry& a, const Entry& b) {
    return a.size < b.size || (a.size == b.size && a.index < b.index);
  };
  for (auto& [key, cell] : cells_) {
    for (std::vector<Entry>& in : cell.turned)
      std::sort(in.begin(), in.end(), by_size_then_index);
    std::sort(cell.unturned.begin(), cell.unturned.end(), by_size_then_index);
  }
}

long KeypointGrid::cell_index(double v) const {
  return PointGrid::cell_of(v, cell_);
}

long long KeypointGrid::pack(long x, long y) {
  return PointGrid::pack(x, y);
}

int KeypointGrid::angle_bin(double angle) {
  double a = std::fmod(angle, 360.0);
  if (a < 0.0)
    a += 360.0;
  if (!(a >= 0.0)) // Not finite: kept apart (keypoints) or asking for every turn (searches).
    return 0;
  return std::min(kAngleBins - 1, static_cast<int>(a / kAngleBinDeg));
}

} // namespace pickdetect::detail
