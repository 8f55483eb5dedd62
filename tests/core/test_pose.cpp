// SPDX-License-Identifier: LGPL-2.1-or-later
// Pose fits: similarities (Umeyama), homographies, weights and robust losses, angles.
#include <pickdetect/pose.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <vector>

using namespace pickdetect;

TEST(Pose, FitSimilarityRecoversAKnownTransform) {
  const Similarity truth{37.0, 1.2, {50.0, -20.0}};
  const std::vector<cv::Point2f> from = {{0, 0}, {100, 0}, {100, 60}, {0, 60}, {40, 30}};
  Similarity fit;
  ASSERT_TRUE(fit_similarity(from, truth.apply(from), true, fit));
  EXPECT_NEAR(fit.angle, 37.0, 1e-6);
  EXPECT_NEAR(fit.scale, 1.2, 1e-6); // float points
  EXPECT_NEAR(fit.translation.x, 50.0, 1e-6);
  ASSERT_TRUE(fit_similarity(from, truth.apply(from), false, fit));
  EXPECT_DOUBLE_EQ(fit.scale, 1.0);
  EXPECT_FALSE(fit_similarity({{1, 1}, {1, 1}}, {{2, 2}, {3, 3}}, true, fit));
}

TEST(Pose, PositiveAnglesTurnClockwiseOnScreen) {
  // With y down, turning the x axis by +90 degrees points it down the screen.
  const cv::Point2f p = Similarity{90.0, 1.0, {0.0, 0.0}}.apply(cv::Point2f(1.f, 0.f));
  EXPECT_NEAR(p.x, 0.f, 1e-6);
  EXPECT_NEAR(p.y, 1.f, 1e-6);
  EXPECT_DOUBLE_EQ(angle_difference(350.0, 10.0), 20.0);
}

TEST(Pose, SimilarityNearAHomographyMatchesItsAffinePart) {
  const Similarity s{120.0, 0.9, {300.0, 200.0}};
  const double r = s.angle * CV_PI / 180.0;
  const cv::Matx33d h(s.scale * std::cos(r), -s.scale * std::sin(r), s.translation.x,
                      s.scale * std::sin(r), s.scale * std::cos(r), s.translation.y, 0, 0, 1);
  const Similarity near = similarity_near(h, {20.f, 30.f});
  EXPECT_NEAR(near.angle, 120.0, 1e-6);
  EXPECT_NEAR(near.scale, 0.9, 1e-9);
  EXPECT_NEAR(near.translation.x, 300.0, 1e-4);
}

TEST(Pose, FitHomographyRecoversATiltFromANearbySimilarity) {
  // A model seen a little out of the picture plane, and the similarity closest to it.
  const cv::Matx33d truth(0.9, -0.25, 310.0, 0.3, 0.85, 190.0, 2e-4, -1.5e-4, 1.0);
  std::vector<cv::Point2f> from, to;
  for (int y = 0; y <= 200; y += 40)
    for (int x = 0; x <= 300; x += 50) {
      from.emplace_back(static_cast<float>(x), static_cast<float>(y));
      const cv::Vec3d p = truth * cv::Vec3d(x, y, 1.0);
      to.emplace_back(static_cast<float>(p[0] / p[2]), static_cast<float>(p[1] / p[2]));
    }
  Similarity start;
  ASSERT_TRUE(fit_similarity(from, to, true, start));
  cv::Matx33d fit;
  ASSERT_TRUE(fit_homography(from, to, to_matrix(start), fit));
  for (size_t i = 0; i < from.size(); ++i) {
    const cv::Vec3d p = fit * cv::Vec3d(from[i].x, from[i].y, 1.0);
    EXPECT_NEAR(p[0] / p[2], to[i].x, 1e-3);
    EXPECT_NEAR(p[1] / p[2], to[i].y, 1e-3);
  }
  EXPECT_NEAR(fit(2, 0), truth(2, 0), 1e-7);
  // Three points cannot fix a homography; collinear ones neither.
  cv::Matx33d unused;
  EXPECT_FALSE(fit_homography({from.begin(), from.begin() + 3}, {to.begin(), to.begin() + 3},
                              to_matrix(start), unused));
  const std::vector<cv::Point2f> line = {{0, 0}, {10, 0}, {20, 0}, {30, 0}, {40, 0}};
  EXPECT_FALSE(fit_homography(line, line, cv::Matx33d::eye(), unused));
}

TEST(Pose, WeightsDecideHowMuchEachPairCounts) {
  const Similarity truth{-25.0, 0.9, {300.0, 120.0}};
  const std::vector<cv::Point2f> from = {{0, 0},    {200, 0},  {200, 120}, {0, 120},
                                         {100, 60}, {50, 100}, {150, 20}};
  std::vector<cv::Point2f> to = truth.apply(from);
  to.back() += cv::Point2f(4.f, -3.f); // One pair off by 5 px.
  std::vector<double> weights(from.size(), 1.0);
  weights.back() = 0.0;

  Similarity plain, weighted;
  ASSERT_TRUE(fit_similarity(from, to, true, plain));
  ASSERT_TRUE(fit_similarity(from, to, true, weighted, weights));
  EXPECT_GT(cv::norm(plain.translation - truth.translation), 0.1);
  EXPECT_NEAR(weighted.angle, 335.0, 1e-4); // Float points: about 1e-6 off.
  EXPECT_NEAR(weighted.scale, 0.9, 1e-6);
  EXPECT_NEAR(cv::norm(weighted.translation - truth.translation), 0.0, 1e-4);

  cv::Matx33d h;
  ASSERT_TRUE(fit_homography(from, to, to_matrix(plain), h, weights));
  std::vector<cv::Point2f> mapped;
  cv::perspectiveTransform(from, mapped, cv::Mat(h));
  const std::vector<cv::Point2f> exact = truth.apply(from);
  for (size_t i = 0; i < from.size(); ++i)
    EXPECT_LT(cv::norm(mapped[i] - exact[i]), 1e-3) << "point " << i;

  // Weights must be one per pair and none negative.
  weights.back() = -1.0;
  EXPECT_FALSE(fit_similarity(from, to, true, weighted, weights));
  EXPECT_FALSE(fit_homography(from, to, to_matrix(plain), h, weights));
  weights.pop_back();
  EXPECT_FALSE(fit_similarity(from, to, true, weighted, weights));
  EXPECT_FALSE(fit_homography(from, to, to_matrix(plain), h, weights));
}

TEST(Pose, CauchyLossLetsAFewPairsFarOffPullLess) {
  // A tilted box's keypoints with 0.2 px noise, three of 40 pairs 4 px off (within the inlier
  // distance, so no inlier test removes them).
  const cv::Matx33d truth(0.95, -0.31, 400.0, 0.30, 0.96, 200.0, 2e-4, -1e-4, 1.0);
  const Similarity near{18.0, 1.0, {400.0, 200.0}};
  cv::RNG rng(7);
  std::vector<cv::Point2f> from, to;
  for (int i = 0; i < 40; ++i) {
    from.emplace_back(rng.uniform(0.f, 300.f), rng.uniform(0.f, 200.f));
    const cv::Vec3d p = truth * cv::Vec3d(from.back().x, from.back().y, 1.0);
    to.emplace_back(static_cast<float>(p[0] / p[2] + rng.gaussian(0.2)),
                    static_cast<float>(p[1] / p[2] + rng.gaussian(0.2)));
  }
  for (int i = 0; i < 3; ++i)
    to[i] += cv::Point2f(4.f, 0.f);
  auto centre_error = [&](const cv::Matx33d& h) {
    const cv::Vec3d a = h * cv::Vec3d(150, 100, 1), b = truth * cv::Vec3d(150, 100, 1);
    return std::hypot(a[0] / a[2] - b[0] / b[2], a[1] / a[2] - b[1] / b[2]);
  };
  cv::Matx33d plain, robust;
  ASSERT_TRUE(fit_homography(from, to, to_matrix(near), plain));
  ASSERT_TRUE(fit_homography(from, to, to_matrix(near), robust, {}, Loss::Cauchy));
  EXPECT_GT(centre_error(plain), 0.2);
  EXPECT_LT(centre_error(robust), 0.5 * centre_error(plain));

  // The same for a similarity (the points then carried by one, with its own noise).
  const Similarity pose{-40.0, 1.1, {300.0, 250.0}};
  std::vector<cv::Point2f> onto = pose.apply(from);
  for (size_t i = 0; i < onto.size(); ++i)
    onto[i] +=
        cv::Point2f(static_cast<float>(rng.gaussian(0.2)), static_cast<float>(rng.gaussian(0.2)));
  for (int i = 0; i < 3; ++i)
    onto[i] += cv::Point2f(4.f, 0.f);
  Similarity ls, cauchy;
  ASSERT_TRUE(fit_similarity(from, onto, true, ls));
  ASSERT_TRUE(fit_similarity(from, onto, true, cauchy, {}, Loss::Cauchy));
  const cv::Point2f centre(150, 100);
  const double ls_error = cv::norm(ls.apply(centre) - pose.apply(centre));
  EXPECT_GT(ls_error, 0.2);
  EXPECT_LT(cv::norm(cauchy.apply(centre) - pose.apply(centre)), 0.5 * ls_error);
}
