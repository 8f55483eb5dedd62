// SPDX-License-Identifier: LGPL-2.1-or-later
// A model whose picture repeats a part (a bundle of identical packs): every copy is a place a
// scene feature could mean, and the bundle is placed where all its packs agree.
#include "../../src/repeat_placement.hpp"
#include "../support/box.hpp"
#include "common/scene.hpp"

#include <pickdetect/matching.hpp>
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

/// `inst` moved along its design by `packs` copies of a pack `pack_width` model pixels wide,
/// keeping only the support its moved outline holds: an instance of a repeated design found
/// shifted along it, as its votes can leave it.
Instance shifted_by_packs(const Instance& inst, const Model& model, int packs, double pack_width) {
  Instance out =
      detail::shifted(inst, model, cv::Point2f(static_cast<float>(packs * pack_width), 0.f));
  out.support.clear();
  for (const cv::Point2f& p : inst.support)
    if (cv::pointPolygonTest(out.outline, p, false) >= 0)
      out.support.push_back(p);
  return out;
}

/// A bundle of seven packs lying in a frame of plain belt at `center`, seen straight (the model
/// without tilted views: its matcher's search for copies grows with the square of its
/// keypoints), and the instance the detector finds for it (expected at its place).
struct SevenPacks {
  Model model = test_scene::bundle_model(7, 0.0);
  double pack_width = test_scene::box_model().image.cols;
  Matcher matcher{{model}};
  cv::Mat scene;
  Instance found;

  SevenPacks(const cv::Size& frame, const cv::Point2f& center, double scale) {
    scene = test_scene::plain_background(frame, 100);
    test_scene::paste(scene, model.image, {{center, 0.0, scale}});
    const Detection d = Detector({model}).detect(scene);
    if (d.instances.size() == 1)
      found = d.instances[0];
  }
};

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

TEST(RepeatedDesign, ABundleFoundAPackPastItsEndIntoTheFramesEdgeIsMovedOntoItsPacks) {
  // Seven packs wholly in view, their end 5 px from the frame's right edge. Found a pack to the
  // right, the instance's extra pack lies outside the frame, where nothing denies it, and its
  // other six packs show the print as the true place's do: only the true place's own first
  // pack, which shows the print, tells them apart.
  const double scale = 0.3;
  const cv::Size frame(800, 240);
  const float half = static_cast<float>(test_scene::box_model().image.cols * 3.5 * scale);
  const cv::Point2f truth(frame.width - 5 - half, 120.f);
  const SevenPacks bundle(frame, truth, scale);
  ASSERT_LT(cv::norm(bundle.found.center - truth), 1.5) << "the bundle itself is found in place";
  for (int packs : {1, 2}) {
    std::vector<Instance> instances = {
        shifted_by_packs(bundle.found, bundle.model, packs, bundle.pack_width)};
    ASSERT_GT(cv::norm(instances[0].center - truth), 90.0);
    detail::place_repeated_designs(instances, {bundle.model}, bundle.matcher, bundle.scene);
    EXPECT_LT(cv::norm(instances[0].center - truth), 1.5)
        << "found " << packs << " pack(s) to the right: expected the centre moved back to ("
        << truth.x << ", " << truth.y << "), got (" << instances[0].center.x << ", "
        << instances[0].center.y << ")";
  }
}

TEST(RepeatedDesign, ABundleFoundAPackPastItsEndOntoTheBeltIsMovedOntoItsPacks) {
  // The same seven packs in the middle of the frame, found a pack to either side: the extra
  // pack lies on the plain belt, which shows none of its print.
  const double scale = 0.3;
  const cv::Size frame(1000, 240);
  const cv::Point2f truth(500.f, 120.f);
  const SevenPacks bundle(frame, truth, scale);
  ASSERT_LT(cv::norm(bundle.found.center - truth), 1.5) << "the bundle itself is found in place";
  for (int packs : {-1, 1}) {
    std::vector<Instance> instances = {
        shifted_by_packs(bundle.found, bundle.model, packs, bundle.pack_width)};
    detail::place_repeated_designs(instances, {bundle.model}, bundle.matcher, bundle.scene);
    EXPECT_LT(cv::norm(instances[0].center - truth), 1.5)
        << "found " << packs << " pack(s) along: expected the centre moved back to (" << truth.x
        << ", " << truth.y << "), got (" << instances[0].center.x << ", " << instances[0].center.y
        << ")";
  }
}

TEST(RepeatedDesign, ABundleRunningOutOfOneEdgeAndNearTheOtherStaysWhereItIs) {
  // Seven packs, the first outside the frame's left edge and the last ending a third of a pack
  // from its right edge. Moved a pack to the right, the instance would lose the packs outside
  // and put its extra pack mostly outside the frame too: no better explanation of what is seen,
  // though it would take in the print along the bundle's end that the true outline's edge
  // leaves uncompared.
  const double scale = 0.3;
  const float pack = static_cast<float>(test_scene::box_model().image.cols * scale);
  const float half = 3.5f * pack;
  const cv::Point2f truth(half - pack, 120.f);
  const cv::Size frame(static_cast<int>(truth.x + half + pack / 3), 240);
  const SevenPacks bundle(frame, truth, scale);
  ASSERT_LT(cv::norm(bundle.found.center - truth), 1.5) << "the bundle itself is found in place";
  std::vector<Instance> instances = {bundle.found};
  detail::place_repeated_designs(instances, {bundle.model}, bundle.matcher, bundle.scene);
  EXPECT_LT(cv::norm(instances[0].center - truth), 1.5)
      << "expected the centre left at (" << truth.x << ", " << truth.y << "), got ("
      << instances[0].center.x << ", " << instances[0].center.y << ")";
}

TEST(RepeatedDesign, ABundleLongerThanTheFrameIsNeverPickable) {
  // Seven packs running out of the frame at both ends: every place a whole number of packs
  // along fits what is seen, and a gripper sent to the chosen one may grasp a pack or more off
  // its centre. Wholly in view, the same bundle is placed for sure and pickable.
  const double scale = 0.3;
  const SevenPacks inside(cv::Size(800, 240), {400.f, 120.f}, scale);
  ASSERT_LT(cv::norm(inside.found.center - cv::Point2f(400.f, 120.f)), 1.5);
  EXPECT_FALSE(inside.found.place_unsure);
  EXPECT_TRUE(inside.found.pickable);
  const SevenPacks across(cv::Size(480, 240), {240.f, 120.f}, scale);
  ASSERT_GE(across.found.matches, 20) << "the packs in view are found as one bundle";
  EXPECT_TRUE(across.found.place_unsure);
  EXPECT_FALSE(across.found.pickable)
      << "placed at (" << across.found.center.x << ", " << across.found.center.y << ")";
}

} // namespace
