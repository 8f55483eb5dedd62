// SPDX-License-Identifier: LGPL-2.1-or-later
// A model whose picture repeats a part (a bundle of identical packs): every copy is a place a
// scene feature could mean, and the bundle is placed where all its packs agree.
#include "../support/box.hpp"
#include "common/scene.hpp"

#include <pickdetect/pickdetect.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <string>
#include <vector>

using namespace pickdetect;
using pickdetect::test_scene::bundle_model;
using pickdetect::test_scene::Pose;

namespace {

TEST(RepeatedDesign, ABundleOfIdenticalPacksIsFoundWhereAllItsPacksAgree) {
  const Model bundle = bundle_model(3);
  const Detector detector({bundle});
  const cv::Size frame(900, 480);
  cv::Mat scene = test_scene::plain_background(frame, 100);
  const std::vector<Pose> poses = {{{450.f, 240.f}, 20.0, 0.8}};
  test_scene::paste(scene, bundle.image, poses);
  const Detection d = detector.detect(scene);
  ASSERT_EQ(d.instances.size(), 1u) << "one bundle in view, one instance (no copies shifted by "
                                       "a pack, no packs on their own)";
  const Instance& inst = d.instances[0];
  EXPECT_LT(cv::norm(inst.center - poses[0].center), 1.0)
      << "expected the bundle's centre at (450, 240), got (" << inst.center.x << ", "
      << inst.center.y << ")";
  EXPECT_NEAR(inst.scale, 0.8, 0.02);
  EXPECT_GE(inst.matches, 60) << "the features of every pack support the one instance";
}

TEST(RepeatedDesign, TwoBundlesSideBySideAreEachFoundOnce) {
  const Model bundle = bundle_model(2);
  const Detector detector({bundle});
  const double scale = 0.5;
  const float width = static_cast<float>(bundle.image.cols * scale);
  const cv::Size frame(static_cast<int>(2 * width) + 120, 300);
  cv::Mat scene = test_scene::plain_background(frame, 100);
  const std::vector<Pose> poses = {{{60.f + width / 2, 150.f}, 0.0, scale},
                                   {{60.f + 1.5f * width, 150.f}, 0.0, scale}};
  test_scene::paste(scene, bundle.image, poses);
  const Detection d = detector.detect(scene);
  ASSERT_EQ(d.instances.size(), 2u)
      << "two touching bundles: four identical packs in a row, two instances";
  for (const Pose& p : poses) {
    bool found = false;
    for (const Instance& inst : d.instances)
      found = found || cv::norm(inst.center - p.center) < 1.5;
    EXPECT_TRUE(found) << "no instance at (" << p.center.x << ", " << p.center.y << ")";
  }
}

TEST(RepeatedDesign, ABundleRunningOutOfTheFrameIsPlacedWhereItsPacksAre) {
  // A bundle of four packs lying across the frame's left or right edge, one pack outside: the
  // three packs in view fit two places equally well, the true one and one shifted a pack
  // inwards, whose fourth pack would lie on the empty belt. The frame's pixels decide.
  const Model bundle = bundle_model(4);
  const Detector detector({bundle});
  const cv::Size frame(640, 480);
  for (double scale : {0.3, 0.36})
    for (double angle : {0.0, 200.0})
      for (bool left : {true, false}) {
        cv::Mat scene = test_scene::plain_background(frame, 100);
        const double along_x = bundle.image.cols * scale * std::abs(std::cos(angle * CV_PI / 180));
        // The centre a quarter of the bundle's width in from the edge: one pack outside.
        const float x = static_cast<float>(left ? 0.25 * along_x : frame.width - 0.25 * along_x);
        test_scene::paste(scene, bundle.image, {{{x, 240.f}, angle, scale}});
        const Detection d = detector.detect(scene);
        const std::string where = "scale " + std::to_string(scale) + ", angle " +
                                  std::to_string(angle) + (left ? ", left edge" : ", right edge");
        ASSERT_EQ(d.instances.size(), 1u) << where;
        const Instance& inst = d.instances[0];
        EXPECT_LT(std::hypot(inst.center.x - x, inst.center.y - 240.f), 1.5)
            << where << ": expected the centre at (" << x << ", 240), got (" << inst.center.x
            << ", " << inst.center.y << ")";
      }
}

} // namespace
