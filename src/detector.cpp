// SPDX-License-Identifier: LGPL-2.1-or-later
// The detector: features, matching, then one of the three methods per model, then occlusion.
#include <pickdetect/detector.hpp>
#include <pickdetect/error.hpp>
#include <pickdetect/meanshift.hpp>
#include <pickdetect/occlusion.hpp>
#include <pickdetect/pose.hpp>
#include <pickdetect/ransac.hpp>
#include <pickdetect/voting.hpp>

#include <opencv2/core.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

namespace pickdetect {
namespace {

/// Automatic mean-shift bandwidth: this share of the model's smaller side (scene pixels at
/// scale 1). Wide enough to gather one instance's scattered centre votes, narrow enough to keep
/// the centres of overlapping neighbours apart.
constexpr double kAutoBandwidthShare = 0.15;
/// Refinement: a match is an inlier of a pose when its scene keypoint lies within this share of
/// the model's smaller side (at least kMinInlierPx) of where the pose puts its model keypoint...
constexpr double kInlierShare = 0.02;
constexpr double kMinInlierPx = 3.0;
/// ...its orientation agrees with the pose's within this many degrees...
constexpr double kInlierAngleDeg = 30.0;
/// ...and, with allow_scale, its size ratio lies within this factor of the pose's scale.
constexpr double kInlierScaleFactor = 1.5;
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
/// Score: an instance with this many supporting matches scores 0.5.
constexpr double kHalfScoreMatches = 10.0;
/// Frames smaller than this on a side hold no instance worth a SIFT run.
constexpr int kMinFrameSide = 16;

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double model_side(const Model& model) {
  const cv::Rect2f box = cv::boundingRect(model.outline);
  return std::max(1.0f, std::min(box.width, box.height));
}

double score_for(int matches) {
  return matches / (matches + kHalfScoreMatches);
}

/// Fills an instance's geometry from a similarity pose.
void place(Instance& inst, const Model& model, const Similarity& pose) {
  const double rad = pose.angle * CV_PI / 180.0;
  const double c = std::cos(rad) * pose.scale, sn = std::sin(rad) * pose.scale;
  inst.homography = cv::Matx33d(c, -sn, pose.translation.x, sn, c, pose.translation.y, 0, 0, 1);
  inst.points = pose.apply(model.principal_points);
  inst.outline = pose.apply(model.outline);
  inst.center = inst.points[0];
  inst.angle = pose.angle;
  inst.scale = pose.scale;
}

/// Fills an instance's geometry from a homography (the RANSAC baselines).
void place(Instance& inst, const Model& model, const cv::Matx33d& h) {
  inst.homography = h;
  cv::perspectiveTransform(model.principal_points, inst.points, cv::Mat(h));
  cv::perspectiveTransform(model.outline, inst.outline, cv::Mat(h));
  inst.center = inst.points[0];
  const Similarity local = similarity_near(h, model.principal_points[0]);
  inst.angle = local.angle;
  inst.scale = local.scale;
}

/// What every method shares for one model: its matches, the keypoints on both sides and votes.
struct ModelScene {
  const Model& model;
  const std::vector<cv::KeyPoint>& model_keypoints;
  int index;
  const std::vector<cv::KeyPoint>& scene_keypoints;
  std::vector<Match> matches;
  std::vector<Vote> votes;
  double bandwidth = 0.0;
};

std::vector<Cluster> centre_clusters(const ModelScene& ms) {
  std::vector<cv::Point2f> centres;
  centres.reserve(ms.votes.size());
  for (const Vote& v : ms.votes)
    centres.push_back(v.points[0]);
  return mean_shift_clusters(centres, ms.bandwidth);
}

/// The paper's step 3-5: per principal point, the mode of the cluster's votes; then the
/// similarity that best carries the model's principal points onto those modes.
bool pose_from_principal_points(const ModelScene& ms, const std::vector<int>& members,
                                bool allow_scale, Similarity& pose) {
  const size_t n_points = ms.model.principal_points.size();
  std::vector<cv::Point2f> modes(n_points);
  std::vector<cv::Point2f> estimates(members.size());
  for (size_t j = 0; j < n_points; ++j) {
    cv::Point2d sum(0, 0);
    for (size_t k = 0; k < members.size(); ++k) {
      estimates[k] = ms.votes[members[k]].points[j];
      sum += cv::Point2d(estimates[k].x, estimates[k].y);
    }
    const cv::Point2f mean(static_cast<float>(sum.x / members.size()),
                           static_cast<float>(sum.y / members.size()));
    modes[j] = mean_shift_mode(estimates, mean, ms.bandwidth);
  }
  if (n_points >= 2)
    return fit_similarity(ms.model.principal_points, modes, allow_scale, pose);
  // A single principal point fixes the position only: take the votes' median rotation/scale.
  std::vector<float> angles, scales;
  for (int i : members) {
    angles.push_back(ms.votes[i].angle);
    scales.push_back(ms.votes[i].scale);
  }
  std::nth_element(angles.begin(), angles.begin() + angles.size() / 2, angles.end());
  std::nth_element(scales.begin(), scales.begin() + scales.size() / 2, scales.end());
  pose.angle = angles[angles.size() / 2];
  pose.scale = scales[scales.size() / 2];
  const cv::Point2f at =
      Similarity{pose.angle, pose.scale, {0, 0}}.apply(ms.model.principal_points[0]);
  pose.translation = cv::Point2d(modes[0].x - at.x, modes[0].y - at.y);
  return true;
}

/// Matches (indices into ms.matches, not yet claimed) consistent with a pose.
std::vector<int> inliers_of(const ModelScene& ms, const Similarity& pose, bool allow_scale,
                            const std::vector<char>& claimed) {
  const double tol = std::max(kMinInlierPx, kInlierShare * model_side(ms.model) * pose.scale);
  std::vector<int> in;
  for (size_t i = 0; i < ms.matches.size(); ++i) {
    if (claimed[i])
      continue;
    const Match& m = ms.matches[i];
    const cv::Point2f predicted = pose.apply(ms.model_keypoints[m.model_point].pt);
    const cv::Point2f seen = ms.scene_keypoints[m.scene_point].pt;
    if (std::hypot(predicted.x - seen.x, predicted.y - seen.y) > tol)
      continue;
    if (angle_difference(ms.votes[i].angle, pose.angle) > kInlierAngleDeg)
      continue;
    if (allow_scale) {
      const double r = ms.votes[i].scale / pose.scale;
      if (r > kInlierScaleFactor || r < 1.0 / kInlierScaleFactor)
        continue;
    }
    in.push_back(static_cast<int>(i));
  }
  return in;
}

/// Refits the pose on its own inlier matches until the inlier set settles.
std::vector<int> refine_pose(const ModelScene& ms, Similarity& pose, bool allow_scale,
                             const std::vector<char>& claimed) {
  std::vector<int> in = inliers_of(ms, pose, allow_scale, claimed);
  for (int round = 0; round < kRefineRounds && in.size() >= 2; ++round) {
    std::vector<cv::Point2f> from, to;
    for (int i : in) {
      from.push_back(ms.model_keypoints[ms.matches[i].model_point].pt);
      to.push_back(ms.scene_keypoints[ms.matches[i].scene_point].pt);
    }
    Similarity next;
    if (!fit_similarity(from, to, allow_scale, next))
      break;
    std::vector<int> again = inliers_of(ms, next, allow_scale, claimed);
    if (again.size() < 2)
      break;
    pose = next;
    if (again == in)
      break;
    in = std::move(again);
  }
  return in;
}

/// Homography fitted by least squares on the inliers of a similarity pose, kept when it is well
/// supported and stays close to the similarity; `in` becomes its own inlier set.
bool refine_perspective(const ModelScene& ms, const Similarity& pose, bool allow_scale,
                        const std::vector<char>& claimed, std::vector<int>& in, cv::Matx33d& h) {
  if (in.size() < kMinPerspectiveMatches)
    return false;
  auto model_point = [&](int i) { return ms.model_keypoints[ms.matches[i].model_point].pt; };
  auto scene_point = [&](int i) { return ms.scene_keypoints[ms.matches[i].scene_point].pt; };
  {
    std::vector<cv::Point2f> spread, hull;
    for (int i : in)
      spread.push_back(model_point(i));
    cv::convexHull(spread, hull);
    if (cv::contourArea(hull) < kMinPerspectiveSpread * std::abs(cv::contourArea(ms.model.outline)))
      return false;
  }
  const double side = model_side(ms.model) * pose.scale;
  const double tol = std::max(kMinInlierPx, kInlierShare * side);
  const std::vector<cv::Point2f> similar = pose.apply(ms.model.outline);
  std::vector<int> current = in;
  bool found = false;
  for (int round = 0; round < kRefineRounds; ++round) {
    std::vector<cv::Point2f> from, to;
    for (int i : current) {
      from.push_back(model_point(i));
      to.push_back(scene_point(i));
    }
    const cv::Mat fit = cv::findHomography(from, to, 0);
    if (fit.empty() || !cv::checkRange(fit))
      break;
    const cv::Matx33d candidate(fit);
    std::vector<cv::Point2f> outline;
    cv::perspectiveTransform(ms.model.outline, outline, fit);
    bool close = true;
    for (size_t k = 0; k < outline.size() && close; ++k)
      close = cv::norm(outline[k] - similar[k]) <= kMaxPerspectiveShift * side;
    if (!close)
      break;
    std::vector<int> again;
    std::vector<cv::Point2f> predicted;
    for (size_t i = 0; i < ms.matches.size(); ++i) {
      if (claimed[i])
        continue;
      const Vote& v = ms.votes[i];
      if (angle_difference(v.angle, pose.angle) > kInlierAngleDeg)
        continue;
      if (allow_scale && (v.scale / pose.scale > kInlierScaleFactor ||
                          v.scale / pose.scale < 1.0 / kInlierScaleFactor))
        continue;
      cv::perspectiveTransform(std::vector<cv::Point2f>{model_point(static_cast<int>(i))},
                               predicted, fit);
      if (cv::norm(predicted[0] - scene_point(static_cast<int>(i))) <= tol)
        again.push_back(static_cast<int>(i));
    }
    if (again.size() < kMinPerspectiveMatches)
      break;
    h = candidate;
    found = true;
    if (again == current)
      break;
    current = std::move(again);
  }
  if (found)
    in = std::move(current);
  return found;
}

std::vector<cv::Point2f> scene_points(const ModelScene& ms, const std::vector<int>& idx) {
  std::vector<cv::Point2f> out;
  out.reserve(idx.size());
  for (int i : idx)
    out.push_back(ms.scene_keypoints[ms.matches[i].scene_point].pt);
  return out;
}

std::vector<Instance> detect_voting(ModelScene& ms, const Settings& s) {
  std::vector<Instance> found;
  std::vector<char> claimed(ms.matches.size(), 0);
  for (const Cluster& c : centre_clusters(ms)) {
    if (static_cast<int>(c.members.size()) < s.min_matches)
      break; // clusters come strongest first
    Similarity pose;
    if (!pose_from_principal_points(ms, c.members, s.allow_scale, pose))
      continue;
    Instance inst;
    inst.matches = static_cast<int>(c.members.size());
    place(inst, ms.model, pose);
    if (s.refine) {
      std::vector<int> in = refine_pose(ms, pose, s.allow_scale, claimed);
      if (static_cast<int>(in.size()) < s.min_matches)
        continue;
      cv::Matx33d h;
      // Without allow_scale the objects keep the model's size: the pose stays rigid.
      if (s.allow_scale && refine_perspective(ms, pose, s.allow_scale, claimed, in, h))
        place(inst, ms.model, h);
      else
        place(inst, ms.model, pose);
      for (int i : in)
        claimed[i] = 1;
      inst.matches = static_cast<int>(in.size());
      inst.support = scene_points(ms, in);
    } else {
      inst.support = scene_points(ms, c.members);
    }
    found.push_back(std::move(inst));
  }
  return found;
}

std::vector<Match> subset(const std::vector<Match>& all, const std::vector<int>& idx) {
  std::vector<Match> out;
  out.reserve(idx.size());
  for (int i : idx)
    out.push_back(all[i]);
  return out;
}

std::vector<Instance> detect_ransac(ModelScene& ms, const Settings& s, bool clustered) {
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
    if (!fit_homography_ransac(subset(ms.matches, g), ms.model_keypoints, ms.scene_keypoints,
                               s.ransac_reprojection_px, s.min_matches, fit))
      continue;
    Instance inst;
    place(inst, ms.model, fit.homography);
    inst.matches = static_cast<int>(fit.inliers.size());
    for (int k : fit.inliers)
      inst.support.push_back(ms.scene_keypoints[ms.matches[g[k]].scene_point].pt);
    found.push_back(std::move(inst));
  }
  return found;
}

bool finite_instance(const Instance& inst) {
  auto ok = [](const cv::Point2f& p) { return std::isfinite(p.x) && std::isfinite(p.y); };
  return std::all_of(inst.points.begin(), inst.points.end(), ok) &&
         std::all_of(inst.outline.begin(), inst.outline.end(), ok) && std::isfinite(inst.angle) &&
         std::isfinite(inst.scale);
}

} // namespace

const char* method_name(Method method) {
  switch (method) {
  case Method::Voting:
    return "voting";
  case Method::RansacClustered:
    return "ransac-clustered";
  case Method::RansacAll:
    return "ransac-all";
  }
  return "voting";
}

Method parse_method(const std::string& name) {
  for (Method m : {Method::Voting, Method::RansacClustered, Method::RansacAll})
    if (name == method_name(m))
      return m;
  throw Error("unknown method '" + name + "' (expected voting, ransac-clustered or ransac-all)");
}

Detector::Detector(std::vector<Model> models) : models_(std::move(models)) {
  if (models_.empty())
    throw Error("a detector needs at least one model");
  for (const Model& m : models_)
    if (m.sift.keypoints.empty() ||
        m.sift.descriptors.rows != static_cast<int>(m.sift.keypoints.size()) ||
        m.principal_points.empty() || m.outline.size() < 3)
      throw Error("model '" + m.name +
                  "' is incomplete (no features, principal points or outline)");
  sift_matcher_ = Matcher(models_, FeatureKind::Sift);
  orb_matcher_ = Matcher(models_, FeatureKind::Orb);
}

Detection Detector::detect(const cv::Mat& grey, const Settings& settings) const {
  if (!grey.empty() && grey.type() != CV_8UC1)
    throw Error("frames must be 8-bit single-channel (grey) pictures");
  Detection result;
  if (grey.cols < kMinFrameSide || grey.rows < kMinFrameSide)
    return result;
  const auto t0 = Clock::now();
  const Features scene = extract_features_scaled(grey, settings.detection_scale, settings.features);
  const double features_ms = ms_since(t0);
  result = detect_scene(scene, grey.size(), settings, grey);
  result.timings.features_ms = features_ms;
  return result;
}

Detection Detector::detect(const Features& scene, const cv::Size& frame_size,
                           const Settings& settings) const {
  return detect_scene(scene, frame_size, settings, cv::Mat());
}

Detection Detector::detect_scene(const Features& scene, const cv::Size& frame_size,
                                 const Settings& s, const cv::Mat& grey) const {
  Detection result;
  result.scene_keypoints = static_cast<int>(scene.keypoints.size());
  auto t = Clock::now();
  const std::vector<Match> matches = (s.features == FeatureKind::Orb ? orb_matcher_ : sift_matcher_)
                                         .match(scene.descriptors, s.ratio, s.search);
  result.matches = static_cast<int>(matches.size());
  result.timings.matching_ms = ms_since(t);

  t = Clock::now();
  for (size_t m = 0; m < models_.size(); ++m) {
    ModelScene ms{models_[m],
                  models_[m].features(s.features).keypoints,
                  static_cast<int>(m),
                  scene.keypoints,
                  {},
                  {},
                  0.0};
    for (const Match& match : matches)
      if (match.model == static_cast<int>(m))
        ms.matches.push_back(match);
    if (static_cast<int>(ms.matches.size()) < std::max(1, s.min_matches))
      continue;
    ms.votes = cast_votes(ms.matches, ms.model_keypoints, scene.keypoints,
                          ms.model.principal_points, s.allow_scale);
    ms.bandwidth = s.bandwidth > 0.0 ? s.bandwidth : kAutoBandwidthShare * model_side(ms.model);

    std::vector<Instance> found;
    switch (s.method) {
    case Method::Voting:
      found = detect_voting(ms, s);
      break;
    case Method::RansacClustered:
      found = detect_ransac(ms, s, true);
      break;
    case Method::RansacAll:
      found = detect_ransac(ms, s, false);
      break;
    }
    for (Instance& inst : found) {
      if (!finite_instance(inst))
        continue;
      inst.model = static_cast<int>(m);
      inst.model_name = ms.model.name;
      inst.score = score_for(inst.matches);
      inst.grasp = inst.points[ms.model.grasp_point];
      inst.grasp_angle = inst.angle;
      result.instances.push_back(std::move(inst));
    }
  }
  // Best first; the order depends only on the instances, never on timing.
  std::stable_sort(result.instances.begin(), result.instances.end(),
                   [](const Instance& a, const Instance& b) {
                     if (a.score != b.score)
                       return a.score > b.score;
                     if (a.center.x != b.center.x)
                       return a.center.x < b.center.x;
                     return a.center.y < b.center.y;
                   });
  if (s.max_instances > 0 && static_cast<int>(result.instances.size()) > s.max_instances)
    result.instances.resize(s.max_instances);
  assess_occlusion(result.instances, models_, frame_size, grey, s.features);
  result.timings.clustering_ms = ms_since(t);
  return result;
}

} // namespace pickdetect
