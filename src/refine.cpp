// SPDX-License-Identifier: LGPL-2.1-or-later
// Refinement beyond the paper: each instance's pose refitted on its own inlier matches, and a
// homography where enough well-spread inliers allow it (objects tilted out of the plane).
#include "model_scene.hpp"

#include "polygon.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cfloat>
#include <cmath>

namespace pickdetect::detail {
namespace {

/// Refinement: a match is an inlier of a pose when its scene keypoint lies within this share of
/// the model's smaller side (at least kMinInlierPx) of where the pose puts its model keypoint...
constexpr double kInlierShare = 0.02;
constexpr double kMinInlierPx = 3.0;
/// ...its orientation agrees with the pose's within kInlierAngleDeg and, with allow_scale, its
/// size ratio lies within kInlierScaleFactor of the pose's scale (model_scene.hpp).
constexpr int kRefineRounds = 4;
/// Perspective refinement (objects tilted a little out of the picture plane): a homography is
/// fitted on an instance's inliers when there are this many...
constexpr size_t kMinPerspectiveMatches = 16;
/// ...and their model points span this share of the outline's area (no collinear few, the
/// paper's objection to homographies)...
constexpr double kMinPerspectiveSpread = 0.2;
/// ...and it is kept only if no outline point moves farther than this share of the model's
/// smaller side from where the similarity puts it.
constexpr double kMaxPerspectiveShift = 0.15;
/// A face tilted away from the camera is foreshortened along one axis: a similarity then fits
/// only a part of it, and its votes scatter along that axis. Its pose is searched as an affine
/// map (RANSAC) over the hypothesis' votes and the matches on its outline grown by this factor,
/// when they are at least kMinForeshortenedMatches (model_scene.hpp)...
constexpr double kForeshortenedReach = 1.5;
/// ...kept when it shows the face from its front (front_view, model_scene.hpp) and it gathers
/// at least kForeshortenedGain times the similarity's inliers.
constexpr double kForeshortenedGain = 1.2;
/// The affine map's RANSAC draws at most this many samples (it stops sooner once it is 99.5 %
/// sure): where a fifth of the pool are its inliers, it finds them 98 times in 100 (the faces it
/// finds on the real tote and the hard sets hold 18 % of their pool and more; none is lost). A
/// dense print of chance matches (a graffiti: 3,800 matches, 2,000 fruitless calls in 15
/// frames) no longer draws 2,000 samples each time.
constexpr int kForeshortenedSamples = 500;

/// Matches (indices into ms.matches, not yet claimed) consistent with a pose: `map` (the pose
/// itself, or a homography close to it) carries the model keypoint to within the inlier distance
/// of the scene keypoint, and the match's own rotation (and, with allow_scale, size ratio)
/// agrees with the pose's.
std::vector<int> inliers_of(const ModelScene& ms, const Similarity& pose, const cv::Matx33d& map,
                            bool allow_scale, const std::vector<char>& claimed) {
  const double tol = inlier_distance(ms, pose.scale);
  // Only matches whose scene keypoints lie where the map puts the model picture can be inliers.
  const cv::Size2f picture(static_cast<float>(ms.model.image.cols),
                           static_cast<float>(ms.model.image.rows));
  const std::vector<cv::Point2f> corners = {
      {0.f, 0.f}, {picture.width, 0.f}, {picture.width, picture.height}, {0.f, picture.height}};
  float x0 = FLT_MAX, y0 = FLT_MAX, x1 = -FLT_MAX, y1 = -FLT_MAX;
  for (const cv::Point2f& c : corners) {
    const cv::Vec3d p = map * cv::Vec3d(c.x, c.y, 1.0);
    // No picture to place, or it reaches behind the camera: look everywhere.
    if (ms.model.image.empty() || !(p[2] > 0.0)) {
      x0 = y0 = -FLT_MAX / 4;
      x1 = y1 = FLT_MAX / 4;
      break;
    }
    x0 = std::min(x0, static_cast<float>(p[0] / p[2]));
    y0 = std::min(y0, static_cast<float>(p[1] / p[2]));
    x1 = std::max(x1, static_cast<float>(p[0] / p[2]));
    y1 = std::max(y1, static_cast<float>(p[1] / p[2]));
  }
  const float margin = static_cast<float>(tol) + 1.f;
  const cv::Rect2f box(x0 - margin, y0 - margin, x1 - x0 + 2.f * margin, y1 - y0 + 2.f * margin);
  std::vector<int> in;
  for (const int i : ms.match_grid.inside(box)) {
    if (claimed[i])
      continue;
    const Vote& v = ms.votes[i];
    if (angle_difference(v.angle, pose.angle) > kInlierAngleDeg)
      continue;
    if (allow_scale && (v.scale / pose.scale > kInlierScaleFactor ||
                        v.scale / pose.scale < 1.0 / kInlierScaleFactor))
      continue;
    const Match& m = ms.matches[i];
    const cv::Point2f model = ms.model_features.keypoints[m.model_point].pt;
    const cv::Vec3d p = map * cv::Vec3d(model.x, model.y, 1.0);
    if (!(p[2] > 0.0)) // Behind the camera: no inlier.
      continue;
    const cv::Point2f seen = ms.scene.keypoints[m.scene_point].pt;
    const double dx = p[0] / p[2] - seen.x, dy = p[1] / p[2] - seen.y;
    if (dx * dx + dy * dy <= tol * tol)
      in.push_back(static_cast<int>(i));
  }
  return in;
}

} // namespace

bool placed_alike(const cv::KeyPoint& ks, const cv::KeyPoint& km, cv::Point2d at, double radius,
                  double angle, double scale) {
  const cv::Point2d d(km.pt.x - at.x, km.pt.y - at.y);
  if (d.dot(d) > radius * radius || angle_difference(ks.angle - km.angle, angle) > kInlierAngleDeg)
    return false;
  const double ratio = km.size > 0.f ? ks.size / km.size / scale : 1.0;
  return ratio <= kInlierScaleFactor && ratio >= 1.0 / kInlierScaleFactor;
}

bool front_view(const cv::Matx33d& map) {
  const double det = map(0, 0) * map(1, 1) - map(0, 1) * map(1, 0);
  if (!(det > 0.0))
    return false;
  cv::Mat sv;
  cv::SVD::compute(cv::Mat(cv::Matx22d(map(0, 0), map(0, 1), map(1, 0), map(1, 1))), sv);
  return sv.at<double>(1) >= kMaxForeshortening * sv.at<double>(0);
}

bool fit_front_affine(const std::vector<cv::Point2f>& from, const std::vector<cv::Point2f>& to,
                      double tol, int samples, cv::Matx33d& map) {
  const cv::Mat a =
      cv::estimateAffine2D(from, to, cv::noArray(), cv::RANSAC, tol, samples, 0.995, 10);
  if (a.empty())
    return false;
  map = cv::Matx33d(a.at<double>(0, 0), a.at<double>(0, 1), a.at<double>(0, 2), a.at<double>(1, 0),
                    a.at<double>(1, 1), a.at<double>(1, 2), 0, 0, 1);
  return front_view(map);
}

double inlier_distance(const ModelScene& ms, double scale) {
  return std::max(kMinInlierPx, kInlierShare * model_side(ms.model) * scale);
}

/// Refits the pose on its own inlier matches until the inlier set settles.
std::vector<int> refine_pose(const ModelScene& ms, Similarity& pose, bool allow_scale,
                             const std::vector<char>& claimed) {
  std::vector<int> in = inliers_of(ms, pose, to_matrix(pose), allow_scale, claimed);
  for (int round = 0; round < kRefineRounds && in.size() >= 2; ++round) {
    Similarity next;
    if (!fit_similarity(model_points(ms, in), scene_points(ms, in), allow_scale, next))
      break;
    std::vector<int> again = inliers_of(ms, next, to_matrix(next), allow_scale, claimed);
    if (again.size() < 2)
      break;
    pose = next;
    if (again == in)
      break;
    in = std::move(again);
  }
  return in;
}

double inlier_rms(const ModelScene& ms, const std::vector<int>& in, const cv::Matx33d& map) {
  if (in.empty())
    return 0.0;
  std::vector<cv::Point2f> mapped;
  cv::perspectiveTransform(model_points(ms, in), mapped, cv::Mat(map));
  const std::vector<cv::Point2f> seen = scene_points(ms, in);
  double sum = 0.0;
  for (size_t k = 0; k < in.size(); ++k) {
    const cv::Point2f d = mapped[k] - seen[k];
    sum += d.dot(d);
  }
  return std::sqrt(sum / static_cast<double>(in.size()));
}

void refine_robustly(const ModelScene& ms, const std::vector<int>& in, bool allow_scale,
                     Similarity& pose) {
  Similarity robust;
  if (in.size() >= 3 && fit_similarity(model_points(ms, in), scene_points(ms, in), allow_scale,
                                       robust, {}, Loss::Cauchy))
    pose = robust;
}

/// Homography fitted robustly (Loss::Cauchy) on the inliers of a similarity pose, refitted until
/// its inliers settle, kept when it is well supported and stays close to the similarity; `in`
/// becomes its own inlier set.
bool refine_perspective(const ModelScene& ms, const Similarity& pose, bool allow_scale,
                        const std::vector<char>& claimed, std::vector<int>& in, cv::Matx33d& h) {
  if (in.size() < kMinPerspectiveMatches)
    return false;
  {
    std::vector<cv::Point2f> hull;
    cv::convexHull(model_points(ms, in), hull);
    if (cv::contourArea(hull) < kMinPerspectiveSpread * std::abs(cv::contourArea(ms.model.outline)))
      return false;
  }
  const double side = model_side(ms.model) * pose.scale;
  const std::vector<cv::Point2f> similar = pose.apply(ms.model.outline);
  std::vector<int> current = in;
  bool found = false;
  cv::Matx33d candidate = to_matrix(pose);
  for (int round = 0; round < kRefineRounds; ++round) {
    if (!fit_homography(model_points(ms, current), scene_points(ms, current), candidate, candidate,
                        {}, Loss::Cauchy))
      break;
    std::vector<cv::Point2f> outline;
    cv::perspectiveTransform(ms.model.outline, outline, cv::Mat(candidate));
    bool close = true;
    for (size_t k = 0; k < outline.size() && close; ++k)
      close = cv::norm(outline[k] - similar[k]) <= kMaxPerspectiveShift * side;
    if (!close)
      break;
    std::vector<int> again = inliers_of(ms, pose, candidate, allow_scale, claimed);
    if (again.size() < kMinPerspectiveMatches)
      break;
    h = candidate;
    found = true;
    if (again == current)
      break;
    current = std::move(again);
  }
  if (!found)
    return false;
  in = std::move(current);
  return true;
}

bool refine_foreshortened(const ModelScene& ms, const Similarity& pose, bool allow_scale,
                          const std::vector<int>& members, const std::vector<char>& claimed,
                          std::vector<int>& in, cv::Matx33d& h, size_t fewest) {
  if (!allow_scale)
    return false;
  // Candidates: the hypothesis' own votes and every unclaimed match of the same rotation on
  // the similarity's outline grown by half (the far end of a foreshortened face).
  const std::vector<cv::Point2f> outline = pose.apply(ms.model.outline);
  const cv::Point2f c = pose.apply(ms.model.principal_points[0]);
  std::vector<cv::Point2f> grown;
  for (const cv::Point2f& p : outline)
    grown.push_back(c + (p - c) * kForeshortenedReach);
  std::vector<char> candidate(ms.matches.size(), 0);
  for (int i : members)
    candidate[i] = !claimed[i];
  for (const int i : ms.match_grid.inside(bounds(grown))) {
    if (claimed[i] || angle_difference(ms.votes[i].angle, pose.angle) > kInlierAngleDeg)
      continue;
    if (cv::pointPolygonTest(grown, ms.scene.keypoints[ms.matches[i].scene_point].pt, false) >= 0)
      candidate[i] = 1;
  }
  std::vector<int> pool;
  for (size_t i = 0; i < candidate.size(); ++i)
    if (candidate[i])
      pool.push_back(static_cast<int>(i));
  if (pool.size() < fewest || pool.size() <= in.size())
    return false;
  const double tol = inlier_distance(ms, pose.scale);
  cv::Matx33d map;
  if (!fit_front_affine(model_points(ms, pool), scene_points(ms, pool), tol, kForeshortenedSamples,
                        map))
    return false;
  // Beside a similarity that holds, the matches must agree with its rotation and scale; where
  // none held (fewer than kMinForeshortenedMatches asked for: the similarity kept too few
  // inliers to stand), with the affine map's own (its nearest similarity).
  const Similarity own =
      fewest < kMinForeshortenedMatches ? similarity_near(map, ms.model.principal_points[0]) : pose;
  std::vector<int> current = inliers_of(ms, own, map, allow_scale, claimed);
  if (current.size() < fewest ||
      static_cast<double>(current.size()) < kForeshortenedGain * static_cast<double>(in.size()))
    return false;
  // Then a homography on those inliers (the far end smaller), while it gathers more; on fewer
  // than kMinForeshortenedMatches its eight parameters would follow the keypoints' own errors:
  // the affine map stays.
  for (int round = 0; round < kRefineRounds && current.size() >= kMinForeshortenedMatches;
       ++round) {
    cv::Matx33d next;
    if (!fit_homography(model_points(ms, current), scene_points(ms, current), map, next, {},
                        Loss::Cauchy))
      break;
    std::vector<int> again = inliers_of(ms, own, next, allow_scale, claimed);
    if (again.size() < current.size())
      break;
    map = next;
    if (again == current)
      break;
    current = std::move(again);
  }
  // Foreshortening shrinks a face along one axis, never enlarges it: a map that shows the face
  // larger than its inliers' keypoint sizes say (beyond their tolerance, kInlierScaleFactor)
  // gathers matches of a repeated part spread over neighbouring faces (a band that a packed row
  // of one product shares).
  if (similarity_near(map, ms.model.principal_points[0]).scale > own.scale * kInlierScaleFactor)
    return false;
  h = map;
  in = std::move(current);
  return true;
}

} // namespace pickdetect::detail
