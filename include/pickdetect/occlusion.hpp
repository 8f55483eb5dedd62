// SPDX-License-Identifier: LGPL-2.1-or-later
#pragma once

#include <pickdetect/detector.hpp>
#include <pickdetect/model.hpp>

#include <opencv2/core.hpp>

#include <vector>

namespace pickdetect {

/// Share of an outline's area that another outline must cover for the two to count as
/// overlapping (absorbs the pose noise of two instances that only touch).
constexpr double kOverlapTolerance = 0.005;
/// An instance counts as covered when the instances on top of it hide more than this share of
/// its outline: a sliver that thin under another object's edge does not hold it down. Kept well
/// under the benchmark's 2 % safety line, because what truly lies on an object also includes
/// what no outline shows (shadows, undetected objects), measured at up to 1 % more.
constexpr double kCoverTolerance = 0.01;
/// An instance is pickable only when at least this share of its outline is seen...
constexpr double kMinPickableVisibility = 0.5;
/// ...and its grasp point lies at least this many pixels inside the frame: one on the frame's
/// edge, where a fraction of a pixel decides, is not known to be in view.
constexpr float kGraspMarginPx = 2.f;

/// Area of the intersection of two outlines, in square pixels (outlines are taken as convex).
double overlap_area(const std::vector<cv::Point2f>& a, const std::vector<cv::Point2f>& b);

/// Area of an outline taken as convex (its convex hull), in square pixels; 0 below 3 points.
double hull_area(const std::vector<cv::Point2f>& outline);

/// Which of two overlapping instances lies on top where they overlap: +1 for `a`, -1 for `b`,
/// 0 when it cannot be told. The upper one keeps its features in the shared area while the
/// lower one loses them; where features are too few to tell, the frame's pixels in the shared
/// area are compared with each model's picture carried there (normalised cross-correlation),
/// when `grey` (the frame) is given.
int which_on_top(const Instance& a, const Model& model_a, const Instance& b, const Model& model_b,
                 const cv::Mat& grey = cv::Mat(), FeatureKind kind = FeatureKind::Sift);

/// Drops the instances whose own evidence lies hidden: when most of an instance's supporting
/// keypoints lie where the features show another instance on top of it (which_on_top without
/// the pixels), they cannot show this instance; a few of its features matched that other
/// object's surface (letters of a box's print matching other letters, say). A box truly lying
/// under another keeps its evidence outside the one on top, and one lying on top hides the
/// other's features. Run before assess_occlusion; `models` and `kind` as there.
void drop_hidden_instances(std::vector<Instance>& instances, const std::vector<Model>& models,
                           FeatureKind kind = FeatureKind::Sift);

/// For every instance: `covered` (instances on it hide more than kCoverTolerance of its
/// outline, counting those of which it cannot be told which one is on top; or, when `grey` is
/// given, the frame shows something else than the model's picture over a connected patch of
/// it: an object that is no instance lying on it),
/// `visibility` (share of its outline inside the frame and under no instance on top of it),
/// `pickable` (not covered, not `guided` nor `place_unsure`, grasp point kGraspMarginPx inside
/// the frame,
/// visibility at least kMinPickableVisibility) and `pick_order` (1 = first, by score, among the
/// pickable). `models` are indexed by Instance::model; `grey`, the frame, is optional; `kind` names
/// the features the instances were found with.
void assess_occlusion(std::vector<Instance>& instances, const std::vector<Model>& models,
                      const cv::Size& frame_size, const cv::Mat& grey = cv::Mat(),
                      FeatureKind kind = FeatureKind::Sift);

/// The same, with the frame also in colour (`colour`, 8-bit BGR of the frame size; empty: as
/// above): where a model's picture has colour (Model::colour), a patch of the instance whose
/// colour is another than its print's is something else lying on it, also where the print is
/// plain. With `whole_in_view`, an instance is also pickable only when no more than
/// kCoverTolerance of its outline lies outside the frame: what lies on a part the camera does not
/// see is not known (Settings::pick_whole_in_view). With the frame's `motion_blur`
/// (Settings::motion_blur_x, motion_blur_y), each model's picture is compared with the frame
/// blurred the same way. Throws Error when `colour` is given without `grey` or is not 8-bit BGR of
/// the frame size.
void assess_occlusion(std::vector<Instance>& instances, const std::vector<Model>& models,
                      const cv::Size& frame_size, const cv::Mat& grey, const cv::Mat& colour,
                      FeatureKind kind = FeatureKind::Sift, bool whole_in_view = false,
                      const cv::Point2f& motion_blur = cv::Point2f());

} // namespace pickdetect
