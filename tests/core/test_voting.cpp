// SPDX-License-Identifier: LGPL-2.1-or-later
// Votes and mean shift: each match carries the principal points into the scene; mean shift
// gathers the centre votes.
#include "common/scene.hpp"

#include <pickdetect/matching.hpp>
#include <pickdetect/meanshift.hpp>
#include <pickdetect/pickdetect.hpp>
#include <pickdetect/pose.hpp>
#include <pickdetect/voting.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <vector>

using namespace pickdetect;

TEST(MeanShift, SeparatesTwoBlobsAndLeavesFarOutliersAlone) {
  std::vector<cv::Point2f> pts;
  cv::RNG rng(3);
  for (int i = 0; i < 40; ++i)
    pts.emplace_back(100.f + rng.gaussian(2.0), 100.f + rng.gaussian(2.0));
  for (int i = 0; i < 25; ++i)
    pts.emplace_back(160.f + rng.gaussian(2.0), 120.f + rng.gaussian(2.0));
  pts.emplace_back(600.f, 600.f);
  const std::vector<Cluster> c = mean_shift_clusters(pts, 15.0);
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c[0].members.size(), 40u);
  EXPECT_EQ(c[1].members.size(), 25u);
  EXPECT_NEAR(c[0].mode.x, 100.f, 1.0);
  EXPECT_NEAR(c[1].mode.x, 160.f, 1.0);
  EXPECT_EQ(c[2].members, std::vector<int>{65});
}

TEST(MeanShift, ModeIgnoresVotesOutsideTheWindow) {
  std::vector<cv::Point2f> pts = {{10, 10}, {11, 10}, {10, 11}, {11, 11}, {80, 80}};
  const cv::Point2f mode = mean_shift_mode(pts, {24.4f, 24.4f}, 20.0);
  EXPECT_NEAR(mode.x, 10.5f, 1e-4);
  EXPECT_NEAR(mode.y, 10.5f, 1e-4);
}

TEST(Voting, VotesCarryPrincipalPointsThroughTheKeypointPose) {
  // A model keypoint at (10, 0) with angle 0 seen at (100, 100), turned 90 degrees, twice as big.
  const std::vector<cv::KeyPoint> model = {cv::KeyPoint(10.f, 0.f, 4.f, 0.f)};
  const std::vector<cv::KeyPoint> scene = {cv::KeyPoint(100.f, 100.f, 8.f, 90.f)};
  const std::vector<Match> matches = {Match{0, 0, 0, 1.f, 0.5f}};
  const std::vector<cv::Point2f> pp = {{0.f, 0.f}, {10.f, 5.f}};
  std::vector<Vote> v = cast_votes(matches, model, scene, pp, true);
  ASSERT_EQ(v.size(), 1u);
  EXPECT_FLOAT_EQ(v[0].angle, 90.f);
  EXPECT_FLOAT_EQ(v[0].scale, 2.f);
  // (0,0) is 10 px left of the keypoint: turned 90 degrees and doubled, 20 px above it.
  EXPECT_NEAR(v[0].points[0].x, 100.f, 1e-4);
  EXPECT_NEAR(v[0].points[0].y, 80.f, 1e-4);
  EXPECT_NEAR(v[0].points[1].x, 90.f, 1e-4);
  EXPECT_NEAR(v[0].points[1].y, 100.f, 1e-4);
  v = cast_votes(matches, model, scene, pp, false);
  EXPECT_FLOAT_EQ(v[0].scale, 1.f);
  EXPECT_NEAR(v[0].points[0].y, 90.f, 1e-4);
}

TEST(Voting, SiftAnglesFollowTheSceneRotation) {
  // SIFT's own keypoint angles must grow with a clockwise turn on screen, as votes assume.
  const cv::Mat box =
      cv::imread(std::string(PICKDETECT_TEST_DATA) + "/box.png", cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(box.empty());
  const Model model = load_model(std::string(PICKDETECT_TEST_DATA) + "/box.png");
  cv::Mat scene = test_scene::plain_background({600, 600});
  test_scene::paste(scene, box, {{{300.f, 300.f}, 40.0, 1.0}});
  const Features f = extract_features(scene);
  const std::vector<Match> matches = Matcher({model}).match(f.descriptors, 0.7);
  ASSERT_GE(matches.size(), 20u);
  const std::vector<Vote> votes =
      cast_votes(matches, model.sift.keypoints, f.keypoints, model.principal_points, true);
  int near_truth = 0;
  for (const Vote& v : votes)
    near_truth += angle_difference(v.angle, 40.0) < 10.0 &&
                  std::hypot(v.points[0].x - 300.f, v.points[0].y - 300.f) < 15.f;
  EXPECT_GT(near_truth, static_cast<int>(votes.size()) * 3 / 4);
}
