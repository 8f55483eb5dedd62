// SPDX-License-Identifier: LGPL-2.1-or-later
// The detector: features, matching, then one of the three methods per model, then occlusion.
#include <pickdetect/detector.hpp>

#include "colour_decision.hpp"
#include "guided_matching.hpp"
#include "look_alikes.hpp"
#include "model_scene.hpp"
#include "repeat_placement.hpp"
#include "scene_explanation.hpp"
#include "stopwatch.hpp"

#include <pickdetect/error.hpp>
#include <pickdetect/matching.hpp>
#include <pickdetect/meanshift.hpp>
#include <pickdetect/occlusion.hpp>
#include <pickdetect/pose.hpp>
#include <pickdetect/ransac.hpp>
#include <pickdetect/voting.hpp>

#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

namespace pickdetect {
namespace {

/// Automatic mean-shift bandwidth: this share of the model's smaller side (scene pixels at
/// scale 1). Wide enough to gather one instance's scattered centre votes, narrow enough to keep
/// the centres of overlapping neighbours apart.
constexpr double kAutoBandwidthShare = 0.15;
/// Score: an instance with this many supporting matches scores 0.5.
constexpr double kHalfScoreMatches = 10.0;
/// Frames smaller than this on a side hold no instance worth a SIFT run.
constexpr int kMinFrameSide = 16;

using detail::Clock;
using detail::ms_since;

double score_for(int matches) {
  return matches / (matches + kHalfScoreMatches);
}

bool finite_instance(const Instance& inst) {
  auto ok = [](const cv::Point2f& p) { return std::isfinite(p.x) && std::isfinite(p.y); };
  return std::all_of(inst.points.begin(), inst.points.end(), ok) &&
         std::all_of(inst.outline.begin(), inst.outline.end(), ok) && std::isfinite(inst.angle) &&
         std::isfinite(inst.scale);
}

/// The frames detect takes: grey, and beside it, if given, the same frame in colour.
void check_frames(const cv::Mat& grey, const cv::Mat& colour) {
  if (!grey.empty() && grey.type() != CV_8UC1)
    throw Error("frames must be 8-bit single-channel (grey) pictures");
  if (!colour.empty() && (colour.type() != CV_8UC3 || colour.size() != grey.size()))
    throw Error("the colour frame must be 8-bit BGR (CV_8UC3) of the grey frame's size");
}

/// The instances of model `m` (`model`) among the frame's features and their matches.
std::vector<Instance> find_instances(const Model& model, int m, const Features& scene,
                                     const std::vector<Match>& matches, const Settings& s) {
  detail::ModelScene ms{model, model.features(s.features), m, scene, s.features, {}, {}, 0.0, {}};
  for (const Match& match : matches)
    if (match.model == m)
      ms.matches.push_back(match);
  // Voting completes hypotheses of fewer votes for a model of faint print (guided matching).
  const bool guided = s.method == Method::Voting && s.refine && model.faint_print();
  const size_t fewest =
      guided ? detail::kMinGuidedVotes : static_cast<size_t>(std::max(1, s.min_matches));
  if (ms.matches.size() < fewest)
    return {};
  detail::index_matches(ms);
  ms.votes = cast_votes(ms.matches, ms.model_features.keypoints, scene.keypoints,
                        ms.model.principal_points, s.allow_scale);
  ms.bandwidth =
      s.bandwidth > 0.0 ? s.bandwidth : kAutoBandwidthShare * detail::model_side(ms.model);

  std::vector<Instance> found;
  switch (s.method) {
  case Method::Voting:
    found = detail::find_by_voting(ms, s);
    break;
  case Method::RansacClustered:
    found = detail::find_by_ransac(ms, s, true);
    break;
  case Method::RansacAll:
    found = detail::find_by_ransac(ms, s, false);
    break;
  }
  std::vector<Instance> out;
  for (Instance& inst : found) {
    if (!finite_instance(inst))
      continue;
    inst.model = m;
    inst.model_name = ms.model.name;
    inst.view = ms.model.view;
    inst.score = score_for(inst.matches);
    detail::set_grasp(inst, ms.model);
    out.push_back(std::move(inst));
  }
  return out;
}

} // namespace

bool operator==(const Settings& a, const Settings& b) {
  return a.method == b.method && a.ratio == b.ratio && a.min_matches == b.min_matches &&
         a.bandwidth == b.bandwidth && a.max_instances == b.max_instances &&
         a.allow_scale == b.allow_scale && a.refine == b.refine && a.search == b.search &&
         a.features == b.features && a.detection_scale == b.detection_scale &&
         a.contrast_threshold == b.contrast_threshold &&
         a.ransac_reprojection_px == b.ransac_reprojection_px &&
         a.pick_whole_in_view == b.pick_whole_in_view && a.motion_blur_x == b.motion_blur_x &&
         a.motion_blur_y == b.motion_blur_y;
}

double frame_contrast_threshold(const cv::Mat& grey, const Settings& settings, double print_share) {
  // By default SIFT's contrast threshold follows the frame's exposure: a dim frame keeps its
  // weaker extrema. ORB has no use for it.
  if (settings.contrast_threshold > 0.0)
    return settings.contrast_threshold;
  if (settings.features != FeatureKind::Sift)
    return kSiftContrastThreshold;
  return kSiftContrastThreshold *
         std::max(kLeastFrameContrastShare, exposure_contrast_share(grey) * print_share);
}

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

struct Detector::Matchers {
  Matcher sift;
  Matcher orb;
};

Detector::Detector(std::vector<Model> models) : models_(std::move(models)) {
  if (models_.empty())
    throw Error("a detector needs at least one model");
  for (const Model& m : models_)
    if (m.sift.keypoints.empty() ||
        m.sift.descriptors.rows != static_cast<int>(m.sift.keypoints.size()) ||
        m.principal_points.empty() || m.outline.size() < 3)
      throw Error("model '" + m.name +
                  "' is incomplete (no features, principal points or outline)");
  // A model found at a lowered threshold has faint print (compute_model_features).
  if (std::any_of(models_.begin(), models_.end(), [](const Model& m) { return m.faint_print(); }))
    print_share_ = kFaintPrintFrameShare;
  matchers_ = std::make_shared<const Matchers>(
      Matchers{Matcher(models_, FeatureKind::Sift), Matcher(models_, FeatureKind::Orb)});
}

bool Detector::has_colour_models() const {
  return std::any_of(models_.begin(), models_.end(),
                     [](const Model& m) { return !m.colour.empty(); });
}

double Detector::frame_contrast_threshold(const cv::Mat& grey, const Settings& settings) const {
  return pickdetect::frame_contrast_threshold(grey, settings, print_share_);
}

Detection Detector::detect(const cv::Mat& grey, const Settings& settings) const {
  return detect(grey, cv::Mat(), settings);
}

Detection Detector::detect(const cv::Mat& grey, const cv::Mat& colour,
                           const Settings& settings) const {
  check_frames(grey, colour);
  Detection result;
  if (grey.cols < kMinFrameSide || grey.rows < kMinFrameSide)
    return result;
  const auto t0 = Clock::now();
  const Features scene = extract_features_scaled(grey, settings.detection_scale, settings.features,
                                                 frame_contrast_threshold(grey, settings));
  const double features_ms = ms_since(t0);
  result = detect_scene(scene, grey.size(), settings, grey, colour);
  result.timings.features_ms = features_ms;
  return result;
}

Detection Detector::detect(const Features& scene, const cv::Size& frame_size,
                           const Settings& settings) const {
  return detect_scene(scene, frame_size, settings, cv::Mat(), cv::Mat());
}

std::vector<Match> Detector::match(const Features& scene, const Settings& s) const {
  // The voting method with refinement shares a feature between look-alike models and decides
  // which product an object is from each instance's own evidence (drop_look_alikes); the
  // baselines and the paper's plain voting reject such features, as the paper does.
  const bool share = s.method == Method::Voting && s.refine;
  const double ratio = s.ratio > 0.0 ? s.ratio : share ? kVotingRatio : kBaselineRatio;
  return (s.features == FeatureKind::Orb ? matchers_->orb : matchers_->sift)
      .match(scene.descriptors, ratio, s.search, share ? Ambiguity::Share : Ambiguity::Reject);
}

Detection Detector::detect(const cv::Mat& grey, const Features& scene,
                           const std::vector<Match>& matches, const Settings& settings,
                           const cv::Mat& colour) const {
  check_frames(grey, colour);
  return detect_matched(scene, matches, grey.size(), settings, grey, colour);
}

Detection Detector::detect_scene(const Features& scene, const cv::Size& frame_size,
                                 const Settings& s, const cv::Mat& grey,
                                 const cv::Mat& colour) const {
  const auto t = Clock::now();
  const std::vector<Match> matches = match(scene, s);
  const double matching_ms = ms_since(t);
  Detection result = detect_matched(scene, matches, frame_size, s, grey, colour);
  result.timings.matching_ms = matching_ms;
  return result;
}

Detection Detector::detect_matched(const Features& scene, const std::vector<Match>& matches,
                                   const cv::Size& frame_size, const Settings& s,
                                   const cv::Mat& grey, const cv::Mat& colour) const {
  const double length = std::hypot(s.motion_blur_x, s.motion_blur_y);
  if (!(length <= kMaxMotionBlurPx))
    throw Error("Settings::motion_blur_x and motion_blur_y must be finite and at most " +
                std::to_string(static_cast<int>(kMaxMotionBlurPx)) + " pixels long together (got " +
                std::to_string(length) + ")");
  const cv::Point2f blur(static_cast<float>(s.motion_blur_x), static_cast<float>(s.motion_blur_y));
  Detection result;
  result.scene_keypoints = static_cast<int>(scene.keypoints.size());
  result.matches = static_cast<int>(matches.size());
  const bool share = s.method == Method::Voting && s.refine;
  const auto t = Clock::now();
  // Each model's instances on their own (the models in parallel), gathered in the models'
  // order: the result does not depend on the threads.
  std::vector<std::vector<Instance>> per_model(models_.size());
  cv::parallel_for_(cv::Range(0, static_cast<int>(models_.size())), [&](const cv::Range& range) {
    for (int m = range.start; m < range.end; ++m)
      per_model[static_cast<size_t>(m)] =
          find_instances(models_[static_cast<size_t>(m)], m, scene, matches, s);
  });
  for (std::vector<Instance>& found : per_model)
    for (Instance& inst : found)
      result.instances.push_back(std::move(inst));
  if (share) {
    const int fewest = std::max(1, s.min_matches);
    // Look-alikes that differ in colour share every feature: the frame's colour names them
    // before they compete for the frame's keypoints.
    if (!colour.empty())
      detail::decide_by_colour(result.instances, models_, colour);
    detail::explain_scene(result.instances, models_, scene, s.features, fewest, grey, blur);
    detail::place_repeated_designs(
        result.instances, models_,
        s.features == FeatureKind::Orb ? matchers_->orb : matchers_->sift, grey, blur);
    detail::drop_look_alikes(result.instances, fewest / 2 + fewest % 2); // half, rounded up
    drop_hidden_instances(result.instances, models_, s.features);
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
  assess_occlusion(result.instances, models_, frame_size, grey, colour, s.features,
                   s.pick_whole_in_view, blur);
  result.timings.clustering_ms = ms_since(t);
  return result;
}

} // namespace pickdetect
