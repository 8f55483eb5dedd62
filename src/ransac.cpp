// SPDX-License-Identifier: LGPL-2.1-or-later
// The paper's baselines: RANSAC homographies over a set of matches.
#include <pickdetect/ransac.hpp>

#include "model_scene.hpp"

#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace pickdetect {
namespace {

constexpr int kRansacIterations = 2000;
constexpr double kRansacConfidence = 0.995;
/// Four pairs fix a homography, so any four matches fit one exactly: the baselines ask for
/// this many inliers at least, whatever min-matches says (at 4, ransac-clustered found boxes
/// in pictures of other textures).
constexpr int kMinHomographyInliers = 6;

} // namespace

bool fit_homography_ransac(const std::vector<Match>& matches,
                           const std::vector<cv::KeyPoint>& model_keypoints,
                           const std::vector<cv::KeyPoint>& scene_keypoints, double reprojection_px,
                           int min_inliers, HomographyFit& out) {
  if (matches.size() < 4 || static_cast<int>(matches.size()) < min_inliers)
    return false;
  std::vector<cv::Point2f> from, to;
  from.reserve(matches.size());
  to.reserve(matches.size());
  for (const Match& m : matches) {
    from.push_back(model_keypoints[m.model_point].pt);
    to.push_back(scene_keypoints[m.scene_point].pt);
  }
  std::vector<uchar> mask;
  // OpenCV's RANSAC draws its samples from a fixed seed: the same matches give the same result.
  cv::Mat h = cv::findHomography(from, to, cv::RANSAC, reprojection_px, mask, kRansacIterations,
                                 kRansacConfidence);
  if (h.empty() || !cv::checkRange(h))
    return false;
  cv::Matx33d hm(h);
  // A picture of the object keeps its handedness: a mirrored or collapsed map is no instance.
  if (hm(0, 0) * hm(1, 1) - hm(0, 1) * hm(1, 0) <= 0.0)
    return false;
  out.homography = hm;
  out.inliers.clear();
  for (size_t i = 0; i < mask.size(); ++i)
    if (mask[i])
      out.inliers.push_back(static_cast<int>(i));
  return static_cast<int>(out.inliers.size()) >= std::max(4, min_inliers);
}

namespace detail {
namespace {

std::vector<Match> subset(const std::vector<Match>& all, const std::vector<int>& idx) {
  std::vector<Match> out;
  out.reserve(idx.size());
  for (int i : idx)
    out.push_back(all[i]);
  return out;
}

} // namespace

std::vector<Instance> find_by_ransac(const ModelScene& ms, const Settings& s, bool clustered) {
  std::vector<Instance> found;
  std::vector<std::vector<int>> groups;
  if (clustered) {
    for (const Cluster& c : centre_clusters(ms))
      groups.push_back(c.members);
  } else {
    groups.emplace_back(ms.matches.size());
    std::iota(groups.back().begin(), groups.back().end(), 0);
  }
  for (const std::vector<int>& g : groups) {
    HomographyFit fit;
    if (!fit_homography_ransac(subset(ms.matches, g), ms.model_features.keypoints,
                               ms.scene.keypoints, s.ransac_reprojection_px,
                               std::max(s.min_matches, kMinHomographyInliers), fit))
      continue;
    Instance inst;
    place(inst, ms.model, fit.homography);
    inst.matches = static_cast<int>(fit.inliers.size());
    inst.distinct_matches = inst.matches;
    for (int k : fit.inliers)
      inst.support.push_back(ms.scene.keypoints[ms.matches[g[k]].scene_point].pt);
    found.push_back(std::move(inst));
  }
  return found;
}

} // namespace detail
} // namespace pickdetect
