// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: one model's view of a frame, shared by the voting method, the RANSAC
// baselines and the pose refinement.
#pragma once

#include <pickdetect/detector.hpp>
#include <pickdetect/meanshift.hpp>
#include <pickdetect/pose.hpp>
#include <pickdetect/voting.hpp>

#include "keypoint_grid.hpp"
#include "point_grid.hpp"

#include <opencv2/core.hpp>

#include <utility>
#include <vector>

namespace pickdetect::detail {

/// What every method shares for one model: its matches, the keypoints on both sides and votes.
struct ModelScene {
  const Model& model;
  /// The model's and the frame's features of the kind matched (descriptors included: guided
  /// matching compares them again).
  const Features& model_features;
  int index;
  const Features& scene;
  FeatureKind kind = FeatureKind::Sift;
  std::vector<Match> matches;
  std::vector<Vote> votes;
  double bandwidth = 0.0;
  /// The matches' scene positions on a grid (see index_matches): match_grid.inside(box)
  /// gives the matches whose scene keypoints lie in a box, in increasing order.
  PointGrid match_grid;
};

/// Fills the match grid of `ms` from its matches (cells of half the model's smaller side).
void index_matches(ModelScene& ms);

/// The model's smaller side (of its outline's bounding box), in model pixels.
double model_side(const Model& model);

/// Fills an instance's geometry (points, outline, centre, angle, scale, homography) from a
/// similarity pose or from a homography.
void place(Instance& inst, const Model& model, const Similarity& pose);
void place(Instance& inst, const Model& model, const cv::Matx33d& h);

/// Sets an instance's grasp point (its principal point Model::grasp_point) and gripper angle (its
/// angle) from its placed geometry.
void set_grasp(Instance& inst, const Model& model);

/// Scene positions of the given matches' scene keypoints.
std::vector<cv::Point2f> scene_points(const ModelScene& ms, const std::vector<int>& idx);
/// Model positions of the given matches' model keypoints.
std::vector<cv::Point2f> model_points(const ModelScene& ms, const std::vector<int>& idx);

/// Mean-shift clusters of the centre votes, strongest first.
std::vector<Cluster> centre_clusters(const ModelScene& ms);

/// The voting method (voting.cpp) and the RANSAC baselines (ransac.cpp) on one model.
std::vector<Instance> find_by_voting(const ModelScene& ms, const Settings& s);
std::vector<Instance> find_by_ransac(const ModelScene& ms, const Settings& s, bool clustered);

/// Refinement (refine.cpp): how far, in scene pixels, an inlier's scene keypoint may lie from
/// where a pose of the given scale puts its model keypoint.
double inlier_distance(const ModelScene& ms, double scale);
/// A pair of keypoints agrees with a pose (the refinement's inliers, guided matching) when its
/// rotation lies within this many degrees of the pose's...
constexpr double kInlierAngleDeg = 30.0;
/// ...and its size ratio within this factor of the pose's scale.
constexpr double kInlierScaleFactor = 1.5;
static_assert(KeypointGrid::kAngleBinDeg >= kInlierAngleDeg,
              "a model keypoint grid's searches must reach every rotation placed_alike takes");
/// Whether model keypoint `km` lies within `radius` model pixels of `at` (where a pose carries
/// scene keypoint `ks` back into the model) with the rotation and size the pose (`angle`,
/// `scale`) predicts there, within kInlierAngleDeg and kInlierScaleFactor.
bool placed_alike(const cv::KeyPoint& ks, const cv::KeyPoint& km, cv::Point2d at, double radius,
                  double angle, double scale);
/// Calls visit(k) for every keypoint of `grid` (a model's) that may be placed_alike with scene
/// keypoint `ks` carried back to `at` by a pose (`angle`, `scale`), within `radius` no wider
/// than the grid's cell (and for some that are not: placed_alike decides).
template <typename F>
void for_alike(const KeypointGrid& grid, const cv::KeyPoint& ks, cv::Point2d at, double angle,
               double scale, F&& visit) {
  // The sizes kInlierScaleFactor allows, a hair wider than placed_alike's own rounding.
  const double size = ks.size / scale, slack = 1.0 + 1e-4;
  grid.for_neighbours(at, ks.angle - angle, static_cast<float>(size / kInlierScaleFactor / slack),
                      static_cast<float>(size * kInlierScaleFactor * slack),
                      std::forward<F>(visit));
}
/// A face seen up to about 70 degrees off its normal: the smaller scale of a map's linear part
/// is at least this share of the larger.
constexpr double kMaxForeshortening = 0.35;
/// Whether the linear part of `map` (an affine map, or a homography near its origin) shows a
/// face from its front side (no mirror), foreshortened at most kMaxForeshortening.
bool front_view(const cv::Matx33d& map);
/// An affine map carrying `from` onto `to`, fitted by RANSAC (inlier distance `tol` scene
/// pixels, at most `samples` draws), as a 3x3 `map`; false when none is found or it shows no
/// front view (front_view).
bool fit_front_affine(const std::vector<cv::Point2f>& from, const std::vector<cv::Point2f>& to,
                      double tol, int samples, cv::Matx33d& map);
/// Refits a similarity pose on its own inlier matches (those not yet
/// `claimed` by a stronger instance) until they settle; returns the inliers.
std::vector<int> refine_pose(const ModelScene& ms, Similarity& pose, bool allow_scale,
                             const std::vector<char>& claimed);
/// Root mean square distance, in scene pixels, between the inliers' scene keypoints and where
/// `map` carries their model keypoints.
double inlier_rms(const ModelScene& ms, const std::vector<int>& in, const cv::Matx33d& map);
/// The similarity refitted on settled inliers `in` with a robust loss (Loss::Cauchy): the few
/// wrong or badly placed pairs within the inlier distance pull it less.
void refine_robustly(const ModelScene& ms, const std::vector<int>& in, bool allow_scale,
                     Similarity& pose);
/// Homography fitted robustly (Loss::Cauchy) on the inliers of a similarity pose, refitted until
/// its inliers settle, kept when it is well supported and stays close to the similarity; `in`
/// becomes its own inlier set.
bool refine_perspective(const ModelScene& ms, const Similarity& pose, bool allow_scale,
                        const std::vector<char>& claimed, std::vector<int>& in, cv::Matx33d& h);

/// Fewest inliers the affine pose of a foreshortened face (refine_foreshortened) rests on
/// beside a similarity that holds, and the fewest from which a homography is fitted to them...
constexpr size_t kMinForeshortenedMatches = 8;
/// ...and where the similarity holds too few inliers to stand by itself (a small or partly seen
/// face far off the picture plane, its votes scattered along the foreshortened axis).
constexpr size_t kMinForeshortenedFewest = 5;

/// A face tilted away from the camera (refine.cpp): an affine pose found by RANSAC among the
/// hypothesis' `members` and the unclaimed matches around the similarity `pose`, then refitted
/// as a homography on its inliers when they are kMinForeshortenedMatches or more; true (with
/// `in` its inliers and `h` the map) when it gathers clearly more inliers than the similarity's
/// `in`, and at least `fewest`.
bool refine_foreshortened(const ModelScene& ms, const Similarity& pose, bool allow_scale,
                          const std::vector<int>& members, const std::vector<char>& claimed,
                          std::vector<int>& in, cv::Matx33d& h, size_t fewest);

} // namespace pickdetect::detail
