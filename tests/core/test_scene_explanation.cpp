// SPDX-License-Identifier: LGPL-2.1-or-later
// Packed rows and tilted faces: one visible surface is one object, and a face seen far off its
// normal is placed by all of its evidence.
#include "../../src/scene_explanation.hpp"
#include "../support/box.hpp"
#include "../support/model_keypoints.hpp"
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
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

using namespace pickdetect;
using pickdetect::test_scene::box_detector;
using pickdetect::test_scene::box_model;
using pickdetect::test_scene::own_keypoints;
using pickdetect::test_scene::Pose;
using pickdetect::test_scene::strongest_own_keypoint;

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

// Two identical boxes seen at half their picture's size, the lower one 60 % under the upper one,
// their centres 48 px apart: within the automatic bandwidth at the picture's size (0.15 of its
// smaller side, 33 px) of where the lower one's votes climb, so that they joined the upper
// one's denser mode and the lower box made no hypothesis of its own. Clustered again at the
// bandwidth narrowed by the scale the votes show, what the upper one leaves is the lower box.
TEST(SceneExplanation, ABoxMostlyUnderAnIdenticalOneSeenSmallIsFound) {
  const cv::Mat& box = box_model().image;
  cv::Mat scene = test_scene::plain_background({420, 340}, 90);
  const Pose lower{{190.f, 180.f}, 182.0, 0.47};
  const Pose upper{{236.f, 164.f}, 212.0, 0.5};
  test_scene::paste(scene, box, {lower});
  test_scene::paste(scene, box, {upper});
  const Detection d = box_detector().detect(scene);
  ASSERT_EQ(d.instances.size(), 2u) << "the upper box and the one mostly under it";
  for (const Pose& p : {lower, upper}) {
    const Instance* inst = nearest(d.instances, p.center);
    ASSERT_NE(inst, nullptr);
    EXPECT_LT(cv::norm(inst->center - p.center), 2.0)
        << "expected a box at (" << p.center.x << ", " << p.center.y << "), nearest at ("
        << inst->center.x << ", " << inst->center.y << ")";
  }
  const Instance* under = nearest(d.instances, lower.center);
  EXPECT_FALSE(under->pickable) << "the lower box is covered";
}

/// A packed row of three boxes (`poses`), its features, and the three instances found there with
/// two false copies of the first: shifted half a box along the row (spanning two neighbours) and
/// turned half a turn, each claiming as much evidence as any true instance.
std::vector<Instance> row_and_copies(std::vector<Pose>& poses, Features& features) {
  const cv::Mat scene = packed_row(3, 0.5, poses);
  features = extract_features(scene);
  std::vector<Instance> instances = box_detector().detect(features, scene.size()).instances;
  if (instances.size() != poses.size())
    return instances;
  const Instance first = instances[0];
  const double half = 0.5 * box_model().image.cols * 0.5;
  const cv::Point2f c = first.center;
  instances.push_back(moved(first, cv::Matx33d(1, 0, half, 0, 1, 0, 0, 0, 1)));
  instances.push_back(moved(first, cv::Matx33d(-1, 0, 2 * c.x, 0, -1, 2 * c.y, 0, 0, 1)));
  for (Instance& inst : instances)
    inst.matches = 40;
  return instances;
}

TEST(SceneExplanation, ShiftedAndTurnedCopiesLoseToTheTrueInstances) {
  std::vector<Pose> poses;
  Features features;
  std::vector<Instance> instances = row_and_copies(poses, features);
  ASSERT_EQ(instances.size(), poses.size() + 2) << "three boxes found, two copies added";
  const Instance first = instances[0];
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

TEST(SceneExplanation, KeepsTheSameInstancesOnOneThreadAsOnSeveral) {
  // What each instance explains is found in parallel: the instances kept, and their order, must
  // not depend on the threads.
  std::vector<Pose> poses;
  Features features;
  const std::vector<Instance> found = row_and_copies(poses, features);
  ASSERT_EQ(found.size(), poses.size() + 2);
  const int threads = cv::getNumThreads();
  std::vector<std::vector<Instance>> kept;
  for (int n : {1, 4}) {
    cv::setNumThreads(n);
    std::vector<Instance> instances = found;
    detail::explain_scene(instances, box_detector().models(), features, FeatureKind::Sift, 4);
    kept.push_back(std::move(instances));
  }
  cv::setNumThreads(threads);
  ASSERT_EQ(kept[0].size(), poses.size());
  ASSERT_EQ(kept[1].size(), kept[0].size()) << "one thread and four keep different instances";
  for (size_t i = 0; i < kept[0].size(); ++i)
    EXPECT_EQ(kept[1][i].center, kept[0][i].center)
        << "instance " << i << " differs between one thread and four";
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

TEST(SceneExplanation, AFewMatchesOfAFaceFarOffThePicturePlaneMakeItsInstance) {
  // Eight keypoints of the box's own picture, away from the middle row, seen on a face turned
  // 20 degrees in the frame and foreshortened to 0.5 of its height (about 60 degrees off its
  // normal): each keypoint's own similarity puts the centre 15-50 px off along the short axis,
  // so no similarity gathers four of them, while one affine map carries them all. As a small
  // or partly seen face far off the picture plane gives: found, where it is.
  const Model& model = box_model();
  const size_t own = own_keypoints(model);
  const cv::Point2f centre = model.principal_points[0];
  const double scale = 0.8, squeeze = 0.5, turn = 20.0;
  const double rad = turn * CV_PI / 180.0;
  const cv::Matx22d map = cv::Matx22d(std::cos(rad), -std::sin(rad), std::sin(rad), std::cos(rad)) *
                          cv::Matx22d(scale, 0.0, 0.0, scale * squeeze);
  const cv::Point2f at(320.f, 240.f);
  // The strongest keypoint in each of eight columns, above and below the middle by turns.
  const int columns = 8;
  Features scene;
  for (int column = 0; column < columns; ++column) {
    const float x0 = static_cast<float>(model.image.cols * column) / columns;
    const float x1 = static_cast<float>(model.image.cols * (column + 1)) / columns;
    const float side = column % 2 == 0 ? -1.f : 1.f;
    const int best = strongest_own_keypoint(model, own, [&](int, const cv::KeyPoint& k) {
      return k.pt.x >= x0 && k.pt.x < x1 && side * (k.pt.y - centre.y) >= 0.25f * model.image.rows;
    });
    ASSERT_GE(best, 0) << "column " << column;
    cv::KeyPoint k = model.sift.keypoints[static_cast<size_t>(best)];
    const cv::Vec2d p = map * cv::Vec2d(k.pt.x - centre.x, k.pt.y - centre.y);
    k.pt = at + cv::Point2f(static_cast<float>(p[0]), static_cast<float>(p[1]));
    k.angle = std::fmod(k.angle + static_cast<float>(turn), 360.f);
    k.size *= static_cast<float>(scale);
    scene.keypoints.push_back(k);
    scene.descriptors.push_back(model.sift.descriptors.row(best));
  }
  const Detection d = box_detector().detect(scene, cv::Size(640, 480), Settings());
  ASSERT_EQ(d.instances.size(), 1u) << "one face, one instance, from " << d.matches << " matches";
  const Instance& inst = d.instances[0];
  EXPECT_EQ(inst.matches, columns);
  for (size_t k = 0; k < model.principal_points.size(); ++k) {
    const cv::Point2f& p = model.principal_points[k];
    const cv::Vec2d q = map * cv::Vec2d(p.x - centre.x, p.y - centre.y);
    const cv::Point2f truth = at + cv::Point2f(static_cast<float>(q[0]), static_cast<float>(q[1]));
    EXPECT_LT(cv::norm(inst.points[k] - truth), 1.0)
        << "principal point " << k << ": expected (" << truth.x << ", " << truth.y << "), got ("
        << inst.points[k].x << ", " << inst.points[k].y << ")";
  }
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

TEST(SceneExplanation, AnAffineMapLargerThanItsKeypointsSizesDoesNotPlaceAFace) {
  // A face of the box at scale 0.6: six of its picture's keypoints where its similarity puts
  // them. Among them, nine more keypoints of the picture of this face's size (a band the
  // box shares with its neighbours in a packed row) lie where a map 1.67 times as large puts
  // them: more than the face's own, and one affine map carries them all. A face is never seen
  // larger than its keypoints' sizes say (foreshortening shrinks one axis): the similarity of
  // the six places it.
  const Model& model = box_model();
  const size_t own = own_keypoints(model);
  const cv::Point2f centre = model.principal_points[0];
  const cv::Point2f at(320.f, 240.f);
  const float scale = 0.6f, larger = 1.0f;
  // The strongest keypoint in each cell of a grid over the picture's inner part, `columns` by
  // `rows`, each kept once.
  std::vector<int> taken;
  auto strongest = [&](int columns, int rows, float part) {
    std::vector<int> out;
    const float w = model.image.cols * part, h = model.image.rows * part;
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < columns; ++c) {
        const float x0 = centre.x - w / 2 + w * c / columns, y0 = centre.y - h / 2 + h * r / rows;
        const int best = strongest_own_keypoint(model, own, [&](int i, const cv::KeyPoint& k) {
          return k.pt.x >= x0 && k.pt.x < x0 + w / columns && k.pt.y >= y0 &&
                 k.pt.y < y0 + h / rows && std::find(taken.begin(), taken.end(), i) == taken.end();
        });
        if (best >= 0) {
          out.push_back(best);
          taken.push_back(best);
        }
      }
    return out;
  };
  const std::vector<int> face = strongest(3, 2, 0.9f);
  const std::vector<int> band = strongest(3, 3, 0.8f);
  ASSERT_EQ(face.size(), 6u);
  ASSERT_EQ(band.size(), 9u);
  Features scene;
  auto place_at = [&](int i, float spread) {
    cv::KeyPoint k = model.sift.keypoints[static_cast<size_t>(i)];
    k.pt = at + (k.pt - centre) * spread;
    k.size *= scale;
    scene.keypoints.push_back(k);
    scene.descriptors.push_back(model.sift.descriptors.row(i));
  };
  for (int i : face)
    place_at(i, scale);
  for (int i : band)
    place_at(i, larger);

  const Detection d = box_detector().detect(scene, cv::Size(640, 480), Settings());
  const Instance* inst = nearest(d.instances, at);
  ASSERT_NE(inst, nullptr) << "the face, from " << d.matches << " matches";
  EXPECT_NEAR(inst->scale, scale, 0.05);
  for (size_t k = 0; k < model.principal_points.size(); ++k) {
    const cv::Point2f truth = at + (model.principal_points[k] - centre) * scale;
    EXPECT_LT(cv::norm(inst->points[k] - truth), 1.0)
        << "principal point " << k << ": expected (" << truth.x << ", " << truth.y << "), got ("
        << inst->points[k].x << ", " << inst->points[k].y << ")";
  }
}

} // namespace

TEST(SceneExplanation, AFewKeypointsOnPlainGroundAreJudgedByTheFramesDetail) {
  // Left: one box. Right: plain ground where four pieces of the box's print (50 px) lie just
  // where one pose of the box would put them: a pose on a handful of keypoints with nothing of
  // the box between them. In the frame's pixels the pieces are faint (0.3 of their contrast,
  // as a chance likeness is): measured on them alone, the frame would keep so little of
  // the print's detail that the plain ground under the pose denies nothing. The box beside it
  // shows how much the frame keeps, and that the ground is no print.
  const Model& model = box_model();
  const cv::Size frame(2 * model.image.cols + 240, model.image.rows + 160);
  cv::Mat scene = test_scene::plain_background(frame, 90);
  const std::vector<Pose> poses = {{{80.f + model.image.cols / 2.f, frame.height / 2.f}, 0.0, 1.0}};
  test_scene::paste(scene, model.image, poses);
  const cv::Point offset(200 + model.image.cols, 80);
  const int piece = 50;
  std::vector<cv::Rect> pieces;
  for (const cv::Point corner : {cv::Point(10, 10), cv::Point(model.image.cols - 80, 10),
                                 cv::Point(10, model.image.rows - 80),
                                 cv::Point(model.image.cols - 80, model.image.rows - 80)}) {
    const cv::Rect from(corner, cv::Size(piece, piece));
    model.image(from).copyTo(scene(from + offset));
    pieces.push_back(from + offset);
  }
  const Features features = extract_features(scene);
  cv::Mat grey = scene.clone();
  for (const cv::Rect& r : pieces) {
    cv::Mat faint;
    scene(r).convertTo(faint, CV_8U, 0.3, 0.7 * 90);
    faint.copyTo(grey(r));
  }
  std::vector<Instance> found = box_detector().detect(features, scene.size()).instances;
  const Instance* box = nearest(found, poses[0].center);
  ASSERT_NE(box, nullptr);
  ASSERT_LT(cv::norm(box->center - poses[0].center), 1.5);
  const cv::Point2f ghost_centre(offset.x + model.image.cols / 2.f,
                                 offset.y + model.image.rows / 2.f);
  const cv::Point2f shift = ghost_centre - box->center;
  Instance ghost = moved(*box, cv::Matx33d(1, 0, shift.x, 0, 1, shift.y, 0, 0, 1));
  ghost.matches = 6;
  // Alone, the pose is kept: nothing in the frame says how much detail it keeps.
  std::vector<Instance> alone = {ghost};
  detail::explain_scene(alone, box_detector().models(), features, FeatureKind::Sift, 4, grey);
  ASSERT_EQ(alone.size(), 1u) << "the pose alone must stand for this test to tell anything";
  std::vector<Instance> instances = {*box, ghost};
  detail::explain_scene(instances, box_detector().models(), features, FeatureKind::Sift, 4, grey);
  ASSERT_EQ(instances.size(), 1u) << "the pose over plain ground must be dropped, the box kept";
  EXPECT_LT(cv::norm(instances[0].center - poses[0].center), 1.5);
}
