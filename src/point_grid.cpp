// SPDX-License-Identifier: LGPL-2.1-or-later
#include "point_grid.hpp"

#include "polygon.hpp"

#include <algorithm>
#include <cmath>

namespace pickdetect::detail {

long PointGrid::cell_of(double v, double cell) {
  constexpr double kLast = 1 << 30;
  const double c = std::floor(v / cell);
  return static_cast<long>(c > -kLast && c < kLast ? c : c > 0 ? kLast : -kLast);
}

long long PointGrid::pack(long x, long y) {
  // Shifted unsigned: a left shift of a negative number is undefined.
  return static_cast<long long>(static_cast<unsigned long long>(x) << 32 ^
                                static_cast<unsigned>(y));
}

PointGrid::PointGrid(std::vector<cv::Point2f> points, double cell)
    : points_(std::move(points)), cell_(cell) {
  for (size_t i = 0; i < points_.size(); ++i) {
    const long cx = cell_index(points_[i].x), cy = cell_index(points_[i].y);
    cells_[pack(cx, cy)].push_back(static_cast<int>(i));
    min_x_ = i == 0 ? cx : std::min(min_x_, cx);
    max_x_ = i == 0 ? cx : std::max(max_x_, cx);
    min_y_ = i == 0 ? cy : std::min(min_y_, cy);
    max_y_ = i == 0 ? cy : std::max(max_y_, cy);
  }
}

std::vector<int> PointGrid::inside(const cv::Rect2f& box) const {
  std::vector<int> out;
  if (points_.empty() || !(box.width >= 0.f) || !(box.height >= 0.f))
    return out;
  const long x0 = std::max(min_x_, cell_index(box.x)),
             x1 = std::min(max_x_, cell_index(static_cast<double>(box.x) + box.width));
  const long y0 = std::max(min_y_, cell_index(box.y)),
             y1 = std::min(max_y_, cell_index(static_cast<double>(box.y) + box.height));
  if (x0 > x1 || y0 > y1)
    return out;
  auto take = [&](const std::vector<int>& cell) {
    for (int i : cell)
      if (in_box(box, points_[i]))
        out.push_back(i);
  };
  // Few cells in the box: look them up; else walk the occupied ones.
  if (static_cast<double>(x1 - x0 + 1) * static_cast<double>(y1 - y0 + 1) <=
      static_cast<double>(cells_.size())) {
    for (long y = y0; y <= y1; ++y)
      for (long x = x0; x <= x1; ++x)
        if (const auto it = cells_.find(pack(x, y)); it != cells_.end())
          take(it->second);
  } else {
    for (const auto& cell : cells_)
      take(cell.second);
  }
  std::sort(out.begin(), out.end());
  return out;
}

} // namespace pickdetect::detail
