// SPDX-License-Identifier: LGPL-2.1-or-later
// Guided matching: a pose of few votes or matches (a hypothesis of two or three votes, a found
// face's neighbour in a packed row, a face found on a bunch of matches), completed from the
// keypoints it predicts.
#include "guided_matching.hpp"

#include "descriptor_distance.hpp"
#include "polygon.hpp"

#include <pickdetect/pose.hpp>

#include <opencv2/imgproc.hpp>

#include <cmath>

namespace pickdetect::detail {
namespace {

/// The first pass searches this share of the model's size (the square root of its outline's
/// area) around where the hypothesis' similarity carries each scene keypoint: a similarity
/// from two or three votes is that far off at the ends of a face tilted 50-70 degrees.
constexpr double kReachShare = 0.1;
/// Scene keypoints are searched on the pose's outline grown by this factor about its centre.
constexpr double kOutlineGrowth = 1.25;
/// Rounds of pairing and refitting.
constexpr int kRounds = 3;
/// The first affine map's RANSAC draws at most this many samples.
constexpr int kAffineSamples = 2000;

std::vector<cv::Point2f> grown(const std::vector<cv::Point2f>& outline, cv::Point2f centre) {
  std::vector<cv::Point2f> out;
  out.reserve(outline.size());
  for (const cv::Point2f& p : outline)
    out.push_back(centre + (p - centre) * kOutlineGrowth);
  return out;
}

std::vector<cv::Point2f> carried(const std::vector<cv::Point2f>& points, const cv::Matx33d& map) {
  std::vector<cv::Point2f> out;
  cv::perspectiveTransform(points, out, cv::Mat(map));
  return out;
}

} // namespace

GuidedMatcher::GuidedMatcher(const ModelScene& ms) : ms_(ms) {
  reach_ = kReachShare * std::sqrt(std::abs(cv::contourArea(ms.model.outline)));
  model_grid_ = KeypointGrid(ms.model_features.keypoints, std::max(1.0, reach_));
  std::vector<cv::Point2f> at;
  at.reserve(ms.scene.keypoints.size());
  for (const cv::KeyPoint& k : ms.scene.keypoints)
    at.push_back(k.pt);
  scene_grid_ = PointGrid(std::move(at), std::max(8.0, 0.5 * model_side(ms.model)));
}

std::vector<GuidedMatcher::Pair> GuidedMatcher::pairs(const cv::Matx33d& map,
                                                      const Similarity& near,
                                                      const std::vector<cv::Point2f>& outline,
                                                      double radius) const {
  std::vector<Pair> out;
  cv::Matx33d back;
  if (!cv::invert(map, back, cv::DECOMP_LU))
    return out;
  const double limit = agree_distance(ms_.kind);
  for (int s : scene_grid_.inside(bounds(outline))) {
    const cv::KeyPoint& ks = ms_.scene.keypoints[s];
    if (cv::pointPolygonTest(outline, ks.pt, false) < 0)
      continue;
    const cv::Vec3d q = back * cv::Vec3d(ks.pt.x, ks.pt.y, 1.0);
    if (!(q[2] > 0.0))
      continue;
    const cv::Point2d at(q[0] / q[2], q[1] / q[2]);
    int best = -1;
    double best_d = 0.0;
    for_alike(model_grid_, ks, at, near.angle, near.scale, [&](int k) {
      if (!placed_alike(ks, ms_.model_features.keypoints[k], at, radius, near.angle, near.scale))
        return;
      const double dist = distance_within(ms_.scene.descriptors, s, ms_.model_features.descriptors,
                                          k, limit, ms_.kind);
      // Ties go to the lower index: the grid visits in no set order.
      if (dist >= 0.0 && (best < 0 || dist < best_d || (dist == best_d && k < best))) {
        best = k;
        best_d = dist;
      }
    });
    if (best >= 0)
      out.push_back({ms_.model_features.keypoints[best].pt, ks.pt});
  }
  return out;
}

bool GuidedMatcher::complete(const Similarity& pose, cv::Matx33d& h,
                             std::vector<cv::Point2f>& support, bool keep_affine) const {
  const cv::Point2f centre = ms_.model.principal_points[0];
  const std::vector<Pair> first = pairs(
      to_matrix(pose), pose, grown(pose.apply(ms_.model.outline), pose.apply(centre)), reach_);
  if (first.size() < kMinGuidedMatches)
    return false;
  std::vector<cv::Point2f> from, to;
  for (const Pair& p : first) {
    from.push_back(p.model);
    to.push_back(p.scene);
  }
  // The RANSAC threshold and the second pass's radius: the refinement's inlier distance.
  const double tol = inlier_distance(ms_, pose.scale);
  cv::Matx33d map;
  if (!fit_front_affine(from, to, tol, kAffineSamples, map))
    return false;
  // Paired again, tightly, where the map carries them; a homography fitted on them while they
  // are enough for its eight parameters.
  std::vector<Pair> in;
  for (int round = 0; round < kRounds; ++round) {
    const Similarity near = similarity_near(map, centre);
    std::vector<Pair> again =
        pairs(map, near, carried(ms_.model.outline, map), tol / std::max(near.scale, 1e-3));
    if (again.size() < kMinGuidedMatches) // Unsteady: a refit that loses its pairs.
      return false;
    in = std::move(again);
    h = map;
    if (in.size() < kMinForeshortenedMatches)
      break;
    from.clear();
    to.clear();
    for (const Pair& p : in) {
      from.push_back(p.model);
      to.push_back(p.scene);
    }
    cv::Matx33d next;
    if (!fit_homography(from, to, map, next, {}, Loss::Cauchy))
      break;
    // A homography that turns the face over or foreshortens it past kMaxForeshortening: from
    // a hypothesis of a few votes it is no face; pairs bunched in one part of a found face
    // cannot bear it out, and the map before it stands (keep_affine).
    if (!front_view(next)) {
      if (!keep_affine)
        return false;
      break;
    }
    map = next;
    h = map;
  }
  if (in.empty())
    return false;
  support.clear();
  for (const Pair& p : in)
    support.push_back(p.scene);
  return true;
}

} // namespace pickdetect::detail
