// SPDX-License-Identifier: LGPL-2.1-or-later
// Polygons: points in polygons, as OpenCV's polygon test counts them.
#include "../../src/polygon.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <vector>

using namespace pickdetect;

TEST(Polygon, CountsWhatThePolygonTestCounts) {
  cv::RNG rng(9);
  std::vector<cv::Point2f> points;
  for (int i = 0; i < 400; ++i)
    points.emplace_back(static_cast<float>(rng.uniform(0.0, 400.0)),
                        static_cast<float>(rng.uniform(0.0, 300.0)));
  // A concave polygon, and points on its corners and edges (they count as inside).
  const std::vector<cv::Point2f> polygon = {
      {50.f, 50.f}, {350.f, 60.f}, {200.f, 120.f}, {330.f, 250.f}, {60.f, 240.f}};
  points.insert(points.end(), polygon.begin(), polygon.end());
  points.emplace_back(200.f, 55.f);
  int scan = 0;
  for (const cv::Point2f& p : points)
    scan += cv::pointPolygonTest(polygon, p, false) >= 0;
  EXPECT_EQ(detail::count_inside(points, polygon), scan);
  EXPECT_GT(scan, 5 + static_cast<int>(polygon.size()));
  EXPECT_LT(scan, static_cast<int>(points.size()) - 5);
  std::vector<cv::KeyPoint> keypoints;
  cv::KeyPoint::convert(points, keypoints);
  EXPECT_EQ(detail::count_inside(keypoints, polygon), scan);
  EXPECT_EQ(detail::count_inside(points, {}), 0);
  EXPECT_EQ(detail::bounds(polygon), cv::Rect2f(50.f, 50.f, 300.f, 200.f));
  EXPECT_TRUE(detail::touch({0.f, 0.f, 10.f, 10.f}, {10.f, 10.f, 5.f, 5.f}));
  EXPECT_FALSE(detail::touch({0.f, 0.f, 10.f, 10.f}, {10.5f, 0.f, 5.f, 5.f}));
}
