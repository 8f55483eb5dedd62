// SPDX-License-Identifier: LGPL-2.1-or-later
// Packed rows and tilted faces: one visible surface is one object, and a face seen far off its
// normal is placed by all of its evidence.
#include "../../src/scene_explanation.hpp"
#include "../support/box.hpp"
#include "../support/tilted_face.hpp"
#include "common/scene.hpp"

#include <pickdetect/matching.hpp>
#include <pickdetect/meanshift.hpp>
#include <pickdetect/occlusion.hpp>
#include <pickdetect/pickdetect.hpp>
#include <pickdetect/pose.hpp>
#include <pickdetect/ransac.hpp>
#include <pickdetect/voting.hpp>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <vector>

using namespace pickdetect;
using pickdetect::test_scene::box_detector;
using pickdetect::test_scene::box_model;
using pickdetect::test_scene::Pose;

namespace {

/// `count` boxes side by side along x, touching, upright, at `scale`, centred in the frame.
cv::Mat packed_row(int count, double scale, std::vector<Pose>& poses) {
  const cv::Mat& box = box_model().image;
  const double width = box.cols * scale;
  const cv::Size frame(static_cast<int>(width * count) + 160,
                       static_cast<int>(box.rows * scale) + 160);
  cv::Mat scene = test_scene::plain_background(frame, 90);
  poses.clear();
  for (int k = 0; k < count; ++k)
    poses.push_back({{static_cast<float>(80 + width * (k + 0.5)), frame.height / 2.f}, 0.0, scale});
  test_scene::paste(scene, box, poses);
  return scene;
}

/// The instance whose centre lies nearest `at`, or nullptr.
const Instance* nearest(const std::vector<Instance>& instances, cv::Point2f at) {
  const Instance* best = nullptr;
  for (const Instance& inst : instances)
    if (!best || cv::norm(inst.center - at) < cv::norm(best->center - at))
      best = &inst;
  return best;
}

/// A copy of `inst` carried by `move` (scene pixels to scene pixels) after its own pose.
Instance moved(const Instance& inst, const cv::Matx33d& move) {
  Instance copy = inst;
  copy.homography = move * inst.homography;
  std::vector<cv::Point2f> points;
  cv::perspectiveTransform(box_model().principal_points, copy.points, cv::Mat(copy.homography));
  cv::perspectiveTransform(box_model().outline, copy.outline, cv::Mat(copy.homography));
  copy.center = copy.points[0];
  return copy;
}

TEST(SceneExplanation, TouchingIdenticalBoxesAreEachFoundOnce) {
  std::vector<Pose> poses;
  const cv::Mat scene = packed_row(4, 0.5, poses);
  const Detection d = box_detector().detect(scene);
  ASSERT_EQ(d.instances.size(), poses.size()) << "four touching boxes, one instance each";
  for (const Pose& p : poses) {
    const Instance* inst = nearest(d.instances, p.center);
    ASSERT_NE(inst, nullptr);
    EXPECT_LT(cv::norm(inst->center - p.center), 1.5)
        << "expected a box at (" << p.center.x << ", " << p.center.y << "), nearest at ("
        << inst->center.x << ", " << inst->center.y << ")";
  }
}

TEST(SceneExplanation, ShiftedAndTurnedCopiesLoseToTheTrueInstances) {
  std::vector<Pose> poses;
  const cv::Mat scene = packed_row(3, 0.5, poses);
  const Features features = extract_features(scene);
  std::vector<Instance> instances = box_detector().detect(features, scene.size()).instances;
  ASSERT_EQ(instances.size(), poses.size());
  const Instance first = instances[0];
  const double half = 0.5 * box_model().image.cols * 0.5;
  const cv::Point2f c = first.center;
  // Half a box along the row (spanning two neighbours), and the box turned half a turn.
  const cv::Matx33d shift(1, 0, half, 0, 1, 0, 0, 0, 1);
  const cv::Matx33d turn(-1, 0, 2 * c.x, 0, -1, 2 * c.y, 0, 0, 1);
  instances.push_back(moved(first, shift));
  instances.push_back(moved(first, turn));
  for (Instance& inst : instances)
    inst.matches = 40; // the copies claim as much evidence as any true instance
  detail::explain_scene(instances, box_detector().models(), features, FeatureKind::Sift, 4);
  ASSERT_EQ(instances.size(), poses.size()) << "the shifted and the turned copy must be dropped";
  for (const Pose& p : poses) {
    const Instance* inst = nearest(instances, p.center);
    EXPECT_LT(cv::norm(inst->center - p.center), 1.5)
        << "expected a box at (" << p.center.x << ", " << p.center.y << "), nearest at ("
        << inst->center.x << ", " << inst->center.y << ")";
    EXPECT_LT(std::abs(inst->homography(0, 0) - first.homography(0, 0)), 0.05)
        << "a kept instance is turned: the turned copy survived";
  }
}

TEST(SceneExplanation, AFaceTiltedFarFromTheCameraIsPlacedByAllItsEvidence) {
  // The box's face turned 55 degrees about its horizontal axis, seen from 600 px away:
  // foreshortened to about 0.6 of its height, the far edge smaller.
  cv::Matx33d h;
  const cv::Mat scene =
      test_scene::tilted_face(box_model().image, 55.0, 0.9, 600.0, cv::Size(640, 480), h);
  const Detection d = box_detector().detect(scene);
  ASSERT_EQ(d.instances.size(), 1u) << "one tilted box, one instance";
  const Instance& inst = d.instances[0];
  std::vector<cv::Point2f> truth;
  cv::perspectiveTransform(box_model().principal_points, truth, cv::Mat(h));
  for (size_t k = 0; k < truth.size(); ++k)
    EXPECT_LT(cv::norm(inst.points[k] - truth[k]), 3.0)
        << "principal point " << k << ": expected (" << truth[k].x << ", " << truth[k].y
        << "), got (" << inst.points[k].x << ", " << inst.points[k].y << ")";
}

TEST(SceneExplanation, AFewAgreeingKeypointsInClutterDoNotMakeAnInstance) {
  // Left: one box. Right: dense print of no model (OpenCV's baboon) where a few small pieces
  // of the box's print lie just where one pose of the box would put them: a handful of
  // keypoints agree with that pose, as a few do by chance in clutter, among the hundreds the
  // clutter holds there.
  const Model& model = box_model();
  const double scale = 1.0;
  const cv::Size frame(2 * model.image.cols + 240, model.image.rows + 160);
  cv::Mat scene = test_scene::plain_background(frame, 90);
  const std::vector<Pose> poses = {
      {{80.f + model.image.cols / 2.f, frame.height / 2.f}, 0.0, scale}};
  test_scene::paste(scene, model.image, poses);
  const cv::Mat print = cv::imread(test_scene::kData + "/baboon.jpg", cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(print.empty());
  const cv::Rect clutter(160 + model.image.cols, 40, model.image.cols + 60, model.image.rows + 80);
  cv::resize(print, scene(clutter), clutter.size(), 0, 0, cv::INTER_AREA);
  // The ghost's pose: the box moved into the middle of the clutter, unturned.
  const cv::Point offset(clutter.x + 30, clutter.y + 40);
  const int piece = 40;
  for (const cv::Point corner : {cv::Point(20, 20), cv::Point(model.image.cols - 60, 20),
                                 cv::Point(20, model.image.rows - 60),
                                 cv::Point(model.image.cols - 60, model.image.rows - 60)}) {
    const cv::Rect from(corner, cv::Size(piece, piece));
    model.image(from).copyTo(scene(from + offset));
  }
  const Features features = extract_features(scene);
  std::vector<Instance> instances = box_detector().detect(features, scene.size()).instances;
  const Instance* box = nearest(instances, poses[0].center);
  ASSERT_NE(box, nullptr);
  ASSERT_LT(cv::norm(box->center - poses[0].center), 1.5);
  Instance truth = *box;
  const cv::Point2f ghost_centre(offset.x + model.image.cols / 2.f,
                                 offset.y + model.image.rows / 2.f);
  const cv::Point2f shift = ghost_centre - truth.center;
  const Instance ghost = moved(truth, cv::Matx33d(1, 0, shift.x, 0, 1, shift.y, 0, 0, 1));
  truth.matches = 4; // both rest on as few matches as an instance may
  instances = {truth, ghost};
  instances[1].matches = 4;
  detail::explain_scene(instances, box_detector().models(), features, FeatureKind::Sift, 4);
  ASSERT_EQ(instances.size(), 1u) << "the pose over the clutter must be dropped, the box kept";
  EXPECT_LT(cv::norm(instances[0].center - poses[0].center), 1.5)
      << "kept: (" << instances[0].center.x << ", " << instances[0].center.y << ")";
}

} // namespace
