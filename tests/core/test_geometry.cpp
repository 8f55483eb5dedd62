// SPDX-License-Identifier: LGPL-2.1-or-later
// The building blocks: votes, mean shift, similarity fits, RANSAC, occlusion.
#include "../../src/look_alikes.hpp"
#include "../../src/point_grid.hpp"
#include "../../src/polygon.hpp"
#include "common/scene.hpp"

#include <pickdetect/matching.hpp>
#include <pickdetect/meanshift.hpp>
#include <pickdetect/occlusion.hpp>
#include <pickdetect/pickdetect.hpp>
#include <pickdetect/pose.hpp>
#include <pickdetect/ransac.hpp>
#include <pickdetect/voting.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>

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

TEST(Matcher, AFeatureThatFitsTwoModelsEquallyDecidesForNeither) {
  const Model a = load_model(std::string(PICKDETECT_TEST_DATA) + "/box.png");
  Model twin = a;
  twin.name = "twin";
  const Features scene = [&] {
    Features f;
    f.keypoints = a.sift.keypoints;
    f.descriptors = a.sift.descriptors.clone();
    return f;
  }();
  EXPECT_GT(Matcher({a}).match(scene.descriptors, 0.8).size(), a.sift.keypoints.size() / 2);
  EXPECT_TRUE(Matcher({a, twin}).match(scene.descriptors, 0.8).empty());
}

TEST(Matcher, SharingGivesAFeatureToEveryLookAlike) {
  const Model a = load_model(std::string(PICKDETECT_TEST_DATA) + "/box.png");
  Model twin = a;
  twin.name = "twin";
  const Model other = load_model(std::string(PICKDETECT_TEST_DATA) + "/graf1.png");
  const cv::Mat scene = a.sift.descriptors;
  const std::vector<Match> matches =
      Matcher({a, twin, other}).match(scene, 0.8, Search::BruteForce, Ambiguity::Share);
  size_t per_model[3] = {0, 0, 0};
  for (const Match& m : matches) {
    ++per_model[m.model];
    EXPECT_TRUE(m.shared || m.model == 2);
  }
  EXPECT_GT(per_model[0], a.sift.keypoints.size() / 2);
  EXPECT_EQ(per_model[0], per_model[1]);
  EXPECT_LT(per_model[2], per_model[0] / 20);
  // With one model, sharing changes nothing.
  const Matcher alone({a});
  const std::vector<Match> reject = alone.match(scene, 0.8, Search::BruteForce);
  const std::vector<Match> share = alone.match(scene, 0.8, Search::BruteForce, Ambiguity::Share);
  ASSERT_EQ(reject.size(), share.size());
  for (size_t i = 0; i < reject.size(); ++i) {
    EXPECT_EQ(reject[i].model_point, share[i].model_point);
    EXPECT_FALSE(share[i].shared);
  }
}

TEST(Occlusion, OverlapAreaOfCrossingAndTouchingOutlines) {
  const std::vector<cv::Point2f> a = {{0, 0}, {100, 0}, {100, 100}, {0, 100}};
  const std::vector<cv::Point2f> b = {{50, 50}, {150, 50}, {150, 150}, {50, 150}};
  const std::vector<cv::Point2f> touching = {{100, 0}, {200, 0}, {200, 100}, {100, 100}};
  EXPECT_NEAR(overlap_area(a, b), 2500.0, 1e-3);
  EXPECT_NEAR(overlap_area(a, touching), 0.0, 1e-3);
}

TEST(Features, KeypointsSitWhereTheBlobIs) {
  // A dark Gaussian blob centred exactly on (80, 90), pixel centres on integers.
  cv::Mat grey(180, 160, CV_8UC1);
  for (int y = 0; y < grey.rows; ++y)
    for (int x = 0; x < grey.cols; ++x)
      grey.at<uchar>(y, x) = cv::saturate_cast<uchar>(
          200.0 - 150.0 * std::exp(-((x - 80.0) * (x - 80.0) + (y - 90.0) * (y - 90.0)) / 50.0));
  const Features f = extract_features(grey);
  ASSERT_FALSE(f.keypoints.empty());
  const cv::KeyPoint* best = &f.keypoints[0];
  for (const cv::KeyPoint& k : f.keypoints)
    if (k.response > best->response)
      best = &k;
  EXPECT_NEAR(best->pt.x, 80.f, 0.1f);
  EXPECT_NEAR(best->pt.y, 90.f, 0.1f);
}

TEST(Features, TheContrastThresholdFollowsTheFramesExposure) {
  // A ramp over every grey level spans about 250 of them: well lit. Dimmed or flattened to 30 %
  // of that span, 76 of them: 76 / 200 of the threshold. Uniform grey: the least share.
  cv::Mat ramp(64, 256, CV_8UC1);
  for (int x = 0; x < ramp.cols; ++x)
    ramp.col(x).setTo(x);
  cv::Mat dim, flat;
  ramp.convertTo(dim, CV_8UC1, 0.3);
  ramp.convertTo(flat, CV_8UC1, 0.3, 120.0);
  EXPECT_DOUBLE_EQ(exposure_contrast_share(ramp), 1.0);
  EXPECT_NEAR(exposure_contrast_share(dim), 76.0 / 200, 0.02);
  EXPECT_NEAR(exposure_contrast_share(flat), exposure_contrast_share(dim), 0.01);
  EXPECT_DOUBLE_EQ(exposure_contrast_share(cv::Mat(64, 64, CV_8UC1, cv::Scalar(90))), 0.25);
  // A plain, noisy belt with one small printed object (1 % of the frame) is well lit: the
  // object's print sets the span, not the belt.
  cv::Mat belt(400, 400, CV_8UC1);
  cv::randn(belt, 110, 4);
  cv::Mat object = belt(cv::Rect(180, 180, 40, 40));
  for (int y = 0; y < object.rows; ++y)
    for (int x = 0; x < object.cols; ++x)
      object.at<uchar>(y, x) = ((x / 5 + y / 5) % 2) ? 230 : 15;
  EXPECT_DOUBLE_EQ(exposure_contrast_share(belt), 1.0);
  // The lower threshold keeps many more of a dim picture's keypoints.
  const cv::Mat graf =
      cv::imread(std::string(PICKDETECT_TEST_DATA) + "/graf1.png", cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(graf.empty());
  cv::Mat dim_graf;
  graf.convertTo(dim_graf, CV_8UC1, 0.25);
  const Features fixed = extract_features(dim_graf);
  const Features followed =
      extract_features(dim_graf, cv::Mat(), FeatureKind::Sift,
                       kSiftContrastThreshold * exposure_contrast_share(dim_graf));
  EXPECT_GT(followed.keypoints.size(), fixed.keypoints.size() * 3 / 2)
      << followed.keypoints.size() << " against " << fixed.keypoints.size();
}

TEST(Matcher, KdTreeSearchKeepsWhatBruteForceFinds) {
  const Model model = load_model(std::string(PICKDETECT_TEST_DATA) + "/box.png");
  const cv::Mat box =
      cv::imread(std::string(PICKDETECT_TEST_DATA) + "/box.png", cv::IMREAD_GRAYSCALE);
  cv::Mat scene = test_scene::plain_background({800, 600});
  test_scene::paste(scene, box, {{{250.f, 250.f}, 30.0, 1.0}, {{560.f, 360.f}, 200.0, 0.9}});
  const Features f = extract_features(scene);
  const Matcher matcher({model});
  const std::vector<Match> exact = matcher.match(f.descriptors, 0.8, Search::BruteForce);
  const std::vector<Match> fast = matcher.match(f.descriptors, 0.8, Search::KdTree);
  ASSERT_GT(exact.size(), 100u);
  size_t shared = 0;
  for (const Match& e : exact)
    shared += std::any_of(fast.begin(), fast.end(), [&](const Match& k) {
      return k.scene_point == e.scene_point && k.model_point == e.model_point;
    });
  EXPECT_GE(shared, exact.size() * 9 / 10)
      << shared << " of " << exact.size() << " exact matches kept";
  EXPECT_EQ(fast.size(), matcher.match(f.descriptors, 0.8, Search::KdTree).size());
}

TEST(Features, OrbAndReducedPicturesKeepPositionsInFramePixels) {
  // The same blob as above, found by ORB and by SIFT on a picture shrunk by 0.5.
  cv::Mat grey(240, 320, CV_8UC1);
  for (int y = 0; y < grey.rows; ++y)
    for (int x = 0; x < grey.cols; ++x)
      grey.at<uchar>(y, x) = cv::saturate_cast<uchar>(
          200.0 -
          150.0 * std::exp(-((x - 160.0) * (x - 160.0) + (y - 120.0) * (y - 120.0)) / 200.0));
  const Features half = extract_features_scaled(grey, 0.5);
  ASSERT_FALSE(half.keypoints.empty());
  const cv::KeyPoint* best = &half.keypoints[0];
  for (const cv::KeyPoint& k : half.keypoints)
    if (k.response > best->response)
      best = &k;
  EXPECT_NEAR(best->pt.x, 160.f, 0.25f);
  EXPECT_NEAR(best->pt.y, 120.f, 0.25f);
  EXPECT_EQ(parse_features("orb"), FeatureKind::Orb);
  EXPECT_THROW(parse_features("surf"), Error);
}

TEST(Detector, OrbAndReducedDetectionFindTheBoxes) {
  const Model model = load_model(std::string(PICKDETECT_TEST_DATA) + "/box.png");
  const Detector detector({model});
  const cv::Mat box =
      cv::imread(std::string(PICKDETECT_TEST_DATA) + "/box.png", cv::IMREAD_GRAYSCALE);
  cv::Mat scene = test_scene::plain_background({900, 700});
  const std::vector<test_scene::Pose> poses = {{{250.f, 250.f}, 30.0, 1.0},
                                               {{620.f, 430.f}, 200.0, 0.9}};
  test_scene::paste(scene, box, poses);
  Settings orb;
  orb.features = FeatureKind::Orb;
  Settings reduced;
  reduced.detection_scale = 0.6;
  for (const Settings& s : {orb, reduced}) {
    const Detection d = detector.detect(scene, s);
    ASSERT_EQ(d.instances.size(), 2u) << feature_name(s.features) << " at " << s.detection_scale;
    for (const test_scene::Pose& p : poses) {
      double best = 1e9;
      for (const Instance& i : d.instances)
        best = std::min(best, static_cast<double>(
                                  std::hypot(i.center.x - p.center.x, i.center.y - p.center.y)));
      EXPECT_LE(best, 1.5) << feature_name(s.features) << " at " << s.detection_scale;
    }
  }
}

namespace {

/// An instance of `model` with the given outline and supporting keypoints.
Instance placed(int model, std::vector<cv::Point2f> outline, std::vector<cv::Point2f> support) {
  Instance inst;
  inst.model = model;
  inst.model_name = "m" + std::to_string(model);
  inst.outline = std::move(outline);
  inst.support = std::move(support);
  inst.matches = static_cast<int>(inst.support.size());
  inst.distinct_matches = inst.matches;
  return inst;
}

std::vector<cv::Point2f> square(float x, float y, float side) {
  return {{x, y}, {x + side, y}, {x + side, y + side}, {x, y + side}};
}

std::vector<cv::Point2f> spread(float x, float y, int n) {
  std::vector<cv::Point2f> p;
  for (int i = 0; i < n; ++i)
    p.emplace_back(x + 7.f * (i % 10), y + 9.f * static_cast<float>(i / 10));
  return p;
}

} // namespace

TEST(LookAlikes, TheWeakerOfTwoModelsInTheSamePlaceGoes) {
  // Model 1 found where model 0 is, nearly the same outline, its 5 keypoints on model 0's.
  std::vector<Instance> found = {placed(0, square(100, 100, 200), spread(120, 120, 60)),
                                 placed(1, square(103, 98, 200), spread(150, 150, 5))};
  detail::drop_look_alikes(found, 3);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].model, 0);
  // Whichever comes first: the stronger one stays.
  found = {placed(1, square(103, 98, 200), spread(150, 150, 5)),
           placed(0, square(100, 100, 200), spread(120, 120, 60))};
  detail::drop_look_alikes(found, 3);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].model, 0);
}

/// `inst` with `distinct` of its matches its own.
Instance with_distinct(Instance inst, int distinct) {
  inst.distinct_matches = distinct;
  return inst;
}

TEST(LookAlikes, TheProductIsNamedByItsDistinctMatches) {
  // Two models on the same keypoints (a shared design): model 1 has more matches, model 0
  // more of its own.
  std::vector<Instance> found = {
      with_distinct(placed(0, square(100, 100, 200), spread(120, 120, 60)), 40),
      with_distinct(placed(1, square(101, 99, 200), spread(120, 120, 62)), 2)};
  detail::drop_look_alikes(found, 3);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].model, 0);
  // The same on the same keypoints elsewhere: the shared design placed differently in model 1.
  found = {with_distinct(placed(0, square(100, 100, 200), spread(120, 120, 60)), 40),
           with_distinct(placed(1, square(90, 40, 150), spread(120, 120, 30)), 4)};
  detail::drop_look_alikes(found, 3);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].model, 0);
}

TEST(LookAlikes, NoProductIsNamedWhenNoneStandsOut) {
  // Own evidence too close to a rival's, or too little of it: which product lies there is not
  // known.
  for (const auto& [first, second] : {std::pair{7, 5}, std::pair{5, 0}}) {
    std::vector<Instance> found = {
        with_distinct(placed(0, square(100, 100, 200), spread(120, 120, 40)), first),
        with_distinct(placed(1, square(101, 99, 200), spread(120, 120, 40)), second)};
    detail::drop_look_alikes(found, 3);
    EXPECT_TRUE(found.empty()) << first << " against " << second << " distinct matches";
  }
  // Alone, an instance needs the given number of distinct matches.
  std::vector<Instance> found = {
      with_distinct(placed(0, square(100, 100, 200), spread(120, 120, 20)), 2)};
  detail::drop_look_alikes(found, 3);
  EXPECT_TRUE(found.empty());
  found = {with_distinct(placed(0, square(100, 100, 200), spread(120, 120, 20)), 3)};
  detail::drop_look_alikes(found, 3);
  EXPECT_EQ(found.size(), 1u);
}

TEST(LookAlikes, OverlappingProductsAndTwoOfOneProductStay) {
  // The same model twice in the same place is not a look-alike (mean shift keeps those apart).
  std::vector<Instance> found = {placed(0, square(100, 100, 200), spread(120, 120, 60)),
                                 placed(0, square(103, 98, 200), spread(150, 150, 5))};
  detail::drop_look_alikes(found, 3);
  EXPECT_EQ(found.size(), 2u);
  // A product lying half over another: outlines overlap, but far from the same place.
  found = {placed(0, square(100, 100, 200), spread(120, 120, 60)),
           placed(1, square(200, 100, 200), spread(310, 120, 20))};
  detail::drop_look_alikes(found, 3);
  EXPECT_EQ(found.size(), 2u);
  // Nearly the same outline, but the weaker one's keypoints lie outside the stronger one's:
  // its evidence is its own.
  found = {placed(0, square(100, 100, 200), spread(120, 120, 60)),
           placed(1, square(100, 110, 200), spread(150, 303, 6))};
  detail::drop_look_alikes(found, 3);
  EXPECT_EQ(found.size(), 2u);
}

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
