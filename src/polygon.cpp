// SPDX-License-Identifier: LGPL-2.1-or-later
#include "polygon.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>

namespace pickdetect::detail {
namespace {

template <typename Points, typename Position>
int count_in(const Points& points, const std::vector<cv::Point2f>& polygon, Position position) {
  if (polygon.empty())
    return 0;
  const cv::Rect2f box = bounds(polygon);
  int n = 0;
  for (const auto& item : points) {
    const cv::Point2f p = position(item);
    n += in_box(box, p) && cv::pointPolygonTest(polygon, p, false) >= 0;
  }
  return n;
}

} // namespace

cv::Rect2f bounds(const std::vector<cv::Point2f>& points) {
  if (points.empty())
    return {};
  float x0 = points[0].x, y0 = points[0].y, x1 = x0, y1 = y0;
  for (const cv::Point2f& p : points) {
    x0 = std::min(x0, p.x), y0 = std::min(y0, p.y);
    x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
  }
  return {x0, y0, x1 - x0, y1 - y0};
}

bool in_box(const cv::Rect2f& box, const cv::Point2f& p) {
  return p.x >= box.x && p.x <= box.x + box.width && p.y >= box.y && p.y <= box.y + box.height;
}

bool touch(const cv::Rect2f& a, const cv::Rect2f& b) {
  return a.x <= b.x + b.width && b.x <= a.x + a.width && a.y <= b.y + b.height &&
         b.y <= a.y + a.height;
}

int count_inside(const std::vector<cv::Point2f>& points, const std::vector<cv::Point2f>& polygon) {
  return count_in(points, polygon, [](const cv::Point2f& p) { return p; });
}

int count_inside(const std::vector<cv::KeyPoint>& points, const std::vector<cv::Point2f>& polygon) {
  return count_in(points, polygon, [](const cv::KeyPoint& k) { return k.pt; });
}

} // namespace pickdetect::detail
