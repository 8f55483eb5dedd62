// SPDX-License-Identifier: LGPL-2.1-or-later
// The point grid: box queries find what a scan finds.
#include "../../src/point_grid.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <vector>

using namespace pickdetect;

TEST(PointGrid, BoxQueriesFindWhatAScanFinds) {
  cv::RNG rng(5);
  std::vector<cv::Point2f> points;
  for (int i = 0; i < 500; ++i)
    points.emplace_back(static_cast<float>(rng.uniform(-300.0, 1500.0)),
                        static_cast<float>(rng.uniform(-200.0, 1100.0)));
  points.emplace_back(1e7f, -1e7f); // far out: clamped into the last cell, still found
  const detail::PointGrid grid(points, 64.0);
  const std::vector<cv::Rect2f> boxes = {{100.f, 100.f, 200.f, 150.f},
                                         {-1000.f, -1000.f, 5000.f, 5000.f},
                                         {-1e8f, -1e8f, 2e8f, 2e8f},
                                         {points[7].x, points[7].y, 0.f, 0.f},
                                         {5000.f, 5000.f, 10.f, 10.f}};
  for (const cv::Rect2f& box : boxes) {
    std::vector<int> scan;
    for (size_t i = 0; i < points.size(); ++i)
      if (points[i].x >= box.x && points[i].y >= box.y && points[i].x <= box.x + box.width &&
          points[i].y <= box.y + box.height)
        scan.push_back(static_cast<int>(i));
    EXPECT_EQ(grid.inside(box), scan) << box;
  }
  EXPECT_TRUE(detail::PointGrid().inside(boxes[1]).empty());
  // Neighbours: every point within one cell width of a location is visited.
  const cv::Point2d at(400.0, 300.0);
  std::vector<char> seen(points.size(), 0);
  grid.for_neighbours(at, [&](int i) { seen[i] = 1; });
  for (size_t i = 0; i < points.size(); ++i) {
    if (std::hypot(points[i].x - at.x, points[i].y - at.y) <= 64.0) {
      EXPECT_TRUE(seen[i]) << i;
    }
  }
}
