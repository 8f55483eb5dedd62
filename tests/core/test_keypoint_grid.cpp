// SPDX-License-Identifier: LGPL-2.1-or-later
// The keypoint grid: a search visits every keypoint near a place, turned and sized about as
// asked, once, and passes over those turned or sized far otherwise.
#include "../../src/keypoint_grid.hpp"

#include <pickdetect/pose.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

using namespace pickdetect;
using detail::KeypointGrid;

TEST(KeypointGrid, VisitsEveryKeypointNearOfTheTurnAndSizeAskedOnce) {
  cv::RNG rng(11);
  std::vector<cv::KeyPoint> keypoints;
  for (int i = 0; i < 3000; ++i)
    keypoints.emplace_back(static_cast<float>(rng.uniform(-50.0, 450.0)),
                           static_cast<float>(rng.uniform(-50.0, 350.0)),
                           static_cast<float>(rng.uniform(1.0, 40.0)),
                           static_cast<float>(rng.uniform(0.0, 360.0)));
  keypoints[0].angle = 359.9f; // Beside 0 degrees, across the turn's seam.
  keypoints[0].pt = {200.f, 150.f};
  keypoints[0].size = 35.f;
  keypoints[1].size = 0.f; // Unsized: visited whatever the size asked.
  keypoints[1].pt = {201.f, 151.f};
  keypoints[1].angle = 1.f;
  keypoints[2].pt = {199.f, 149.f}; // A turn that is no number: placed_alike lets any through.
  keypoints[2].angle = std::nanf("");
  keypoints[2].size = 10.f;
  const double cell = 24.0;
  const KeypointGrid grid(keypoints, cell);
  for (int q = 0; q < 400; ++q) {
    const cv::Point2d at = q == 0 ? cv::Point2d(200.0, 150.0)
                                  : cv::Point2d(rng.uniform(0.0, 400.0), rng.uniform(0.0, 300.0));
    const double angle = q == 0 ? 0.5 : rng.uniform(-720.0, 720.0); // Any turn.
    const float min_size = q == 0 ? 30.f : static_cast<float>(rng.uniform(1.0, 30.0));
    const float max_size = min_size * 2.25f;
    std::vector<int> visits(keypoints.size(), 0);
    grid.for_neighbours(at, angle, min_size, max_size, [&](int i) { ++visits[i]; });
    for (size_t i = 0; i < keypoints.size(); ++i) {
      const cv::KeyPoint& k = keypoints[i];
      const double turn = std::isnan(k.angle) ? 0.0 : angle_difference(k.angle, angle);
      const bool sized = k.size >= min_size && k.size <= max_size;
      const bool near = std::hypot(k.pt.x - at.x, k.pt.y - at.y) <= cell;
      ASSERT_LE(visits[i], 1) << "keypoint " << i << " visited twice";
      if (near && turn <= KeypointGrid::kAngleBinDeg && (sized || k.size == 0.f)) {
        EXPECT_EQ(visits[i], 1) << "query " << q << " missed keypoint " << i << " turned by "
                                << turn << ", size " << k.size;
      }
      if (visits[i]) {
        // Only the bins beside the one asked, and only sizes asked.
        EXPECT_LE(turn, 2 * KeypointGrid::kAngleBinDeg) << "query " << q << ", keypoint " << i;
        EXPECT_TRUE(sized || k.size == 0.f) << "query " << q << ", keypoint " << i;
      }
    }
    if (q == 0) {
      EXPECT_EQ(visits[0], 1); // Across the seam, of the size asked.
      EXPECT_EQ(visits[1], 1);
    }
  }
  // A keypoint whose turn is no number is found at any turn asked.
  for (const double angle : {0.0, 123.0, 250.0}) {
    int found = 0;
    grid.for_neighbours({200.0, 150.0}, angle, 5.f, 20.f, [&](int i) { found += i == 2; });
    EXPECT_EQ(found, 1) << "a keypoint turned by no number, searched at " << angle << " degrees";
  }
  // A pose whose turn is no number: every turn is asked for.
  std::vector<int> visits(keypoints.size(), 0);
  const cv::Point2d at(200.0, 150.0);
  grid.for_neighbours(at, std::nan(""), 1.f, 40.f, [&](int i) { ++visits[i]; });
  for (size_t i = 0; i < keypoints.size(); ++i)
    if (std::hypot(keypoints[i].pt.x - at.x, keypoints[i].pt.y - at.y) <= cell) {
      EXPECT_EQ(visits[i], 1) << "a turn that is no number missed keypoint " << i;
    }
  int none = 0;
  KeypointGrid().for_neighbours({10.0, 10.0}, 0.0, 0.f, 100.f, [&](int) { ++none; });
  EXPECT_EQ(none, 0);
}
