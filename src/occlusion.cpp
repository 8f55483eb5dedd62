// SPDX-License-Identifier: LGPL-2.1-or-later
// Occlusion: which instances overlap others, how much of each is in view, and the pick order.
#include <pickdetect/occlusion.hpp>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <numeric>

namespace pickdetect {
namespace {

std::vector<cv::Point2f> hull_of(const std::vector<cv::Point2f>& outline) {
  std::vector<cv::Point2f> hull;
  if (outline.size() >= 3)
    cv::convexHull(outline, hull);
  return hull;
}

double area_of(const std::vector<cv::Point2f>& polygon) {
  return polygon.size() >= 3 ? std::abs(cv::contourArea(polygon)) : 0.0;
}

} // namespace

double overlap_area(const std::vector<cv::Point2f>& a, const std::vector<cv::Point2f>& b) {
  const std::vector<cv::Point2f> ha = hull_of(a), hb = hull_of(b);
  if (ha.size() < 3 || hb.size() < 3)
    return 0.0;
  std::vector<cv::Point2f> both;
  return std::max(0.0, static_cast<double>(cv::intersectConvexConvex(ha, hb, both, true)));
}

void assess_occlusion(std::vector<Instance>& instances, const cv::Size& frame_size) {
  const std::vector<cv::Point2f> frame = {
      {0.f, 0.f},
      {static_cast<float>(frame_size.width), 0.f},
      {static_cast<float>(frame_size.width), static_cast<float>(frame_size.height)},
      {0.f, static_cast<float>(frame_size.height)}};
  const size_t n = instances.size();
  std::vector<double> area(n);
  for (size_t i = 0; i < n; ++i) {
    area[i] = area_of(instances[i].outline);
    instances[i].visibility =
        area[i] > 0.0 ? std::min(1.0, overlap_area(instances[i].outline, frame) / area[i]) : 0.0;
    instances[i].pickable = area[i] > 0.0;
    instances[i].pick_order = 0;
  }
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j) {
      const double shared = overlap_area(instances[i].outline, instances[j].outline);
      if (shared > kOverlapTolerance * area[i])
        instances[i].pickable = false;
      if (shared > kOverlapTolerance * area[j])
        instances[j].pickable = false;
    }
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return instances[a].score > instances[b].score; });
  int rank = 0;
  for (size_t i : order)
    if (instances[i].pickable)
      instances[i].pick_order = ++rank;
}

} // namespace pickdetect
