// SPDX-License-Identifier: LGPL-2.1-or-later
// The detector on scenes built from OpenCV's box.png at known poses.
#include "../support/box.hpp"
#include "common/scene.hpp"

#include <pickdetect/pickdetect.hpp>
#include <pickdetect/pose.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <sstream>

using namespace pickdetect;
using pickdetect::test_scene::box_detector;
using pickdetect::test_scene::box_model;
using pickdetect::test_scene::box_picture;
using pickdetect::test_scene::kData;
using pickdetect::test_scene::Pose;

namespace {

double distance(cv::Point2f a, cv::Point2f b) {
  return std::hypot(a.x - b.x, a.y - b.y);
}

std::string describe(const std::vector<Instance>& found) {
  std::ostringstream out;
  for (const Instance& i : found)
    out << " (" << i.center.x << ", " << i.center.y << ", " << i.angle << " deg, " << i.matches
        << " matches)";
  return found.empty() ? " none" : out.str();
}

/// The detection nearest to `truth`, or nullptr.
const Instance* nearest(const std::vector<Instance>& found, cv::Point2f truth) {
  const Instance* best = nullptr;
  for (const Instance& i : found)
    if (!best || distance(i.center, truth) < distance(best->center, truth))
      best = &i;
  return best;
}

void expect_found(const std::vector<Instance>& found, const Pose& pose, double tolerance_px) {
  const Instance* hit = nearest(found, pose.center);
  ASSERT_NE(hit, nullptr) << "expected an instance at (" << pose.center.x << ", " << pose.center.y
                          << "), found none";
  EXPECT_LE(distance(hit->center, pose.center), tolerance_px)
      << "expected centre (" << pose.center.x << ", " << pose.center.y << "), got ("
      << hit->center.x << ", " << hit->center.y << ")";
  EXPECT_LE(angle_difference(hit->angle, pose.angle), 2.0)
      << "expected angle " << pose.angle << ", got " << hit->angle;
  EXPECT_NEAR(hit->scale, pose.scale, 0.03);
}

} // namespace

TEST(Detector, FindsOneToEightSeparateInstancesAtRandomAngles) {
  const cv::Mat picture = box_picture();
  const cv::Size frame(1320, 990);
  cv::RNG rng(2024);
  for (int n = 1; n <= 8; ++n) {
    // Cells of 330 px hold one box at scale 0.8 (diagonal 315 px) whatever its angle.
    std::vector<Pose> poses;
    for (int k = 0; k < n; ++k) {
      const int cx = k % 4, cy = k / 4;
      poses.push_back({{165.f + 330.f * cx + rng.uniform(-4.f, 4.f),
                        165.f + 330.f * cy + rng.uniform(-4.f, 4.f)},
                       rng.uniform(0.0, 360.0),
                       0.8 + rng.uniform(-0.03, 0.03)});
    }
    cv::Mat scene = test_scene::plain_background(frame, 110, n);
    test_scene::paste(scene, picture, poses);
    const Detection d = box_detector().detect(scene);
    EXPECT_EQ(d.instances.size(), poses.size())
        << n << " boxes placed, found:" << describe(d.instances);
    for (const Pose& p : poses)
      expect_found(d.instances, p, 1.5);
  }
}

TEST(Detector, OverlappingInstancesComeOutSeparately) {
  const cv::Mat picture = box_picture();
  // The second box lies over a third of the first one.
  const std::vector<Pose> poses = {{{300.f, 260.f}, 20.0, 1.0}, {{460.f, 330.f}, 115.0, 1.0}};
  cv::Mat scene = test_scene::plain_background({800, 600});
  test_scene::paste(scene, picture, poses);
  const Detection d = box_detector().detect(scene);
  ASSERT_EQ(d.instances.size(), 2u) << "found:" << describe(d.instances);
  for (const Pose& p : poses)
    expect_found(d.instances, p, 1.5);
  // The second box, pasted last, lies on top: it alone may be picked.
  for (const Instance& i : d.instances) {
    const bool upper = std::hypot(i.center.x - 460.f, i.center.y - 330.f) < 3.0;
    EXPECT_EQ(i.pickable, upper) << "at (" << i.center.x << ", " << i.center.y << ")";
  }
}

TEST(Detector, SeparateInstancesArePickableInScoreOrder) {
  const cv::Mat picture = box_picture();
  const std::vector<Pose> poses = {{{220.f, 220.f}, 0.0, 1.0}, {{600.f, 380.f}, 200.0, 1.0}};
  cv::Mat scene = test_scene::plain_background({800, 600});
  test_scene::paste(scene, picture, poses);
  const Detection d = box_detector().detect(scene);
  ASSERT_EQ(d.instances.size(), 2u) << "found:" << describe(d.instances);
  EXPECT_TRUE(d.instances[0].pickable && d.instances[1].pickable);
  EXPECT_EQ(d.instances[0].pick_order + d.instances[1].pick_order, 3);
  EXPECT_GE(d.instances[0].score, d.instances[1].score);
  EXPECT_EQ(d.instances[0].pick_order, 1);
}

TEST(Detector, TheAutomaticRatioIsLooserForVotingThanForTheBaselines) {
  // Settings::ratio 0: voting with refine, which checks every instance against the frame, takes
  // the 2NN test at kVotingRatio; the RANSAC baselines and plain voting at kBaselineRatio.
  const cv::Mat scene = cv::imread(kData + "/box_in_scene.png", cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(scene.empty());
  const Features features = extract_features(scene);
  auto matches = [&](Method method, bool refine, double ratio) {
    Settings s;
    s.method = method;
    s.refine = refine;
    s.ratio = ratio;
    return box_detector().detect(features, scene.size(), s).matches;
  };
  EXPECT_EQ(Settings().ratio, 0.0);
  const int loose = matches(Method::Voting, true, kVotingRatio);
  const int strict = matches(Method::Voting, true, kBaselineRatio);
  ASSERT_GT(loose, strict) << "the two ratios must differ on this frame for the test to tell";
  EXPECT_EQ(matches(Method::Voting, true, 0.0), loose);
  EXPECT_EQ(matches(Method::Voting, false, 0.0), matches(Method::Voting, false, kBaselineRatio));
  EXPECT_EQ(matches(Method::RansacClustered, true, 0.0),
            matches(Method::RansacClustered, true, kBaselineRatio));
  EXPECT_EQ(matches(Method::RansacAll, true, 0.0),
            matches(Method::RansacAll, true, kBaselineRatio));
}

TEST(Detector, SettingsAreEqualOnlyWhenEveryFieldIs) {
  const Settings base;
  EXPECT_TRUE(base == Settings());
  std::vector<Settings> changed(13, base);
  changed[0].method = Method::RansacAll;
  changed[1].ratio = 0.7;
  changed[2].min_matches = 6;
  changed[3].bandwidth = 20.0;
  changed[4].max_instances = 3;
  changed[5].allow_scale = false;
  changed[6].refine = false;
  changed[7].search = Search::BruteForce;
  changed[8].features = FeatureKind::Orb;
  changed[9].detection_scale = 0.5;
  changed[10].contrast_threshold = 0.02;
  changed[11].ransac_reprojection_px = 3.0;
  changed[12].pick_whole_in_view = true;
  for (size_t i = 0; i < changed.size(); ++i)
    EXPECT_TRUE(changed[i] != base) << "field " << i;
}

TEST(Detector, EmptyFrameGivesNoInstance) {
  const Detection d = box_detector().detect(test_scene::plain_background({640, 480}));
  EXPECT_TRUE(d.instances.empty()) << "found:" << describe(d.instances);
  const cv::Mat black = cv::Mat::zeros(480, 640, CV_8UC1);
  EXPECT_TRUE(box_detector().detect(black).instances.empty());
}

TEST(Detector, FrameOfAnotherTextureGivesNoInstance) {
  for (const char* name : {"graf1.png", "baboon.jpg", "building.jpg"}) {
    const cv::Mat other = cv::imread(kData + "/" + name, cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(other.empty()) << name;
    for (Method m : {Method::Voting, Method::RansacClustered}) {
      Settings s;
      s.method = m;
      const Detection d = box_detector().detect(other, s);
      EXPECT_TRUE(d.instances.empty())
          << name << " with " << method_name(m) << " found:" << describe(d.instances);
    }
  }
}

TEST(Detector, TinyFramesGiveNoInstance) {
  for (cv::Size size : {cv::Size(1, 1), cv::Size(7, 5), cv::Size(15, 40)})
    EXPECT_TRUE(box_detector().detect(cv::Mat(size, CV_8UC1, cv::Scalar(128))).instances.empty());
}

TEST(Detector, RefusesColourFrames) {
  EXPECT_THROW(box_detector().detect(cv::Mat(100, 100, CV_8UC3)), Error);
}

TEST(Detector, SameFrameGivesTheSameResultEveryRun) {
  const cv::Mat picture = box_picture();
  cv::Mat scene = test_scene::plain_background({900, 700});
  test_scene::paste(
      scene, picture,
      {{{250.f, 250.f}, 33.0, 1.0}, {{420.f, 330.f}, 290.0, 0.95}, {{650.f, 480.f}, 170.0, 1.05}});
  const Detector other({box_model()});
  for (Method m : {Method::Voting, Method::RansacClustered, Method::RansacAll}) {
    Settings s;
    s.method = m;
    const Detection a = box_detector().detect(scene, s);
    for (int run = 0; run < 3; ++run) {
      const Detection b = (run % 2 ? other : box_detector()).detect(scene, s);
      ASSERT_EQ(a.instances.size(), b.instances.size()) << method_name(m);
      for (size_t i = 0; i < a.instances.size(); ++i) {
        EXPECT_EQ(a.instances[i].center, b.instances[i].center) << method_name(m);
        EXPECT_EQ(a.instances[i].points, b.instances[i].points) << method_name(m);
        EXPECT_EQ(a.instances[i].matches, b.instances[i].matches) << method_name(m);
      }
    }
  }
}

TEST(Detector, FindsTheBoxInOpenCVsRealScene) {
  // OpenCV's box_in_scene.png: the box is tilted out of the picture plane and partly hidden.
  // Its corners, read off the photograph: the centre lies near (187.0, 223.9).
  const cv::Mat scene = cv::imread(kData + "/box_in_scene.png", cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(scene.empty());
  const Detection d = box_detector().detect(scene);
  ASSERT_EQ(d.instances.size(), 1u) << "found:" << describe(d.instances);
  EXPECT_LE(distance(d.instances[0].center, {187.04f, 223.9f}), 5.0)
      << "got (" << d.instances[0].center.x << ", " << d.instances[0].center.y << ")";
}

TEST(Detector, RansacAllFindsOneInstanceAndRansacClusteredFindsEach) {
  const cv::Mat picture = box_picture();
  const std::vector<Pose> poses = {{{220.f, 220.f}, 10.0, 1.0}, {{620.f, 420.f}, 250.0, 1.0}};
  cv::Mat scene = test_scene::plain_background({850, 650});
  test_scene::paste(scene, picture, poses);
  Settings s;
  s.method = Method::RansacAll;
  EXPECT_EQ(box_detector().detect(scene, s).instances.size(), 1u);
  s.method = Method::RansacClustered;
  const Detection d = box_detector().detect(scene, s);
  ASSERT_EQ(d.instances.size(), 2u) << "found:" << describe(d.instances);
  for (const Pose& p : poses)
    expect_found(d.instances, p, 3.0);
}

TEST(Detector, WithoutAllowScaleTheScaleStaysOne) {
  const cv::Mat picture = box_picture();
  cv::Mat scene = test_scene::plain_background({700, 600});
  test_scene::paste(scene, picture, {{{330.f, 300.f}, 75.0, 1.0}});
  Settings s;
  s.allow_scale = false;
  const Detection d = box_detector().detect(scene, s);
  ASSERT_EQ(d.instances.size(), 1u);
  EXPECT_DOUBLE_EQ(d.instances[0].scale, 1.0);
  expect_found(d.instances, {{330.f, 300.f}, 75.0, 1.0}, 1.5);
}

TEST(Detector, MaxInstancesKeepsTheBest) {
  const cv::Mat picture = box_picture();
  cv::Mat scene = test_scene::plain_background({900, 500});
  test_scene::paste(scene, picture, {{{220.f, 240.f}, 0.0, 1.0}, {{650.f, 240.f}, 90.0, 1.0}});
  Settings s;
  s.max_instances = 1;
  EXPECT_EQ(box_detector().detect(scene, s).instances.size(), 1u);
}

TEST(Method, NamesRoundTripAndUnknownNamesAreRefused) {
  for (Method m : {Method::Voting, Method::RansacClustered, Method::RansacAll})
    EXPECT_EQ(parse_method(method_name(m)), m);
  EXPECT_THROW(parse_method("hough"), Error);
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
