// SPDX-License-Identifier: LGPL-2.1-or-later
// Occlusion: which of two overlapping instances lies on top, how much of each is seen, which
// can be picked and in what order.
#include <pickdetect/occlusion.hpp>

#include <pickdetect/error.hpp>

#include "foreign_cover.hpp"
#include "polygon.hpp"

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <numeric>

namespace pickdetect {
namespace {

using detail::bounds;
using detail::count_inside;
using detail::touch;

/// Feature evidence: the upper instance needs at least this many supporting keypoints in the
/// shared area...
constexpr int kMinTopFeatures = 3;
/// ...and a share of the model's keypoints there at least this many times the lower one's.
constexpr double kTopFeatureDominance = 3.0;
/// Pixel evidence: the upper instance's picture must correlate at least this well with the
/// frame in the shared area, and this much better than the lower one's.
constexpr double kMinTopCorrelation = 0.4;
constexpr double kTopCorrelationMargin = 0.15;
/// Fewest shared-area pixels worth correlating.
constexpr int kMinCorrelationPixels = 50;

std::vector<cv::Point2f> hull_of(const std::vector<cv::Point2f>& outline) {
  std::vector<cv::Point2f> hull;
  if (outline.size() >= 3)
    cv::convexHull(outline, hull);
  return hull;
}

double area_of(const std::vector<cv::Point2f>& polygon) {
  return polygon.size() >= 3 ? std::abs(cv::contourArea(polygon)) : 0.0;
}

std::vector<cv::Point2f> shared_area(const Instance& a, const Instance& b) {
  const std::vector<cv::Point2f> ha = hull_of(a.outline), hb = hull_of(b.outline);
  std::vector<cv::Point2f> both;
  if (ha.size() >= 3 && hb.size() >= 3)
    cv::intersectConvexConvex(ha, hb, both, true);
  return both;
}

/// Share of the model's keypoints lying in `region` (scene pixels) that the instance kept.
double kept_share(const Instance& inst, const Features& model,
                  const std::vector<cv::Point2f>& region, int& kept) {
  kept = count_inside(inst.support, region);
  std::vector<cv::Point2f> in_model;
  cv::perspectiveTransform(region, in_model, cv::Mat(inst.homography.inv()));
  const int expected = count_inside(model.keypoints, in_model);
  return expected > 0 ? static_cast<double>(kept) / expected : 0.0;
}

/// Normalised cross-correlation, over the shared area, of the frame with the model's picture
/// carried there by the instance's pose. Returns -1 when it cannot be computed.
double correlation(const Instance& inst, const Model& model, const cv::Mat& grey,
                   const cv::Rect& box, const cv::Mat& region_mask) {
  const cv::Matx33d shift(1, 0, -box.x, 0, 1, -box.y, 0, 0, 1);
  cv::Mat warped, warped_mask;
  cv::warpPerspective(model.image, warped, cv::Mat(shift * inst.homography), box.size(),
                      cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  cv::warpPerspective(model.mask, warped_mask, cv::Mat(shift * inst.homography), box.size(),
                      cv::INTER_NEAREST, cv::BORDER_CONSTANT);
  cv::Mat mask = region_mask & warped_mask;
  if (cv::countNonZero(mask) < kMinCorrelationPixels)
    return -1.0;
  cv::Mat frame, model_pixels;
  grey(box).convertTo(frame, CV_32F);
  warped.convertTo(model_pixels, CV_32F);
  cv::Scalar mf, sf, mm, sm;
  cv::meanStdDev(frame, mf, sf, mask);
  cv::meanStdDev(model_pixels, mm, sm, mask);
  if (sf[0] < 1e-3 || sm[0] < 1e-3)
    return -1.0;
  cv::Mat product = (frame - mf[0]).mul(model_pixels - mm[0]);
  return cv::mean(product, mask)[0] / (sf[0] * sm[0]);
}

/// Whether instance `i` is covered and pickable, and how much of it is seen: `above` the
/// instances lying on it, `hidden` the area they hide, `area` its own (pixels); with
/// `whole_in_view`, what lies outside the frame counts as hidden for the pick flag; `motion_blur`
/// the frame's (assess_occlusion). Writes only instance `i`, reads the others' outlines.
void assess_one(std::vector<Instance>& instances, size_t i, const std::vector<Model>& models,
                const cv::Rect& frame, const cv::Mat& grey, const cv::Mat& colour,
                const std::vector<size_t>& above, double hidden, double area, bool whole_in_view,
                const cv::Point2f& motion_blur) {
  Instance& inst = instances[i];
  inst.covered = area <= 0.0 || hidden > kCoverTolerance * area;
  if (!inst.covered && !grey.empty()) {
    std::vector<const Instance*> on_it;
    for (size_t j : above)
      on_it.push_back(&instances[j]);
    inst.covered =
        detail::foreign_cover_cells(inst, models[inst.model], grey, on_it, colour, motion_blur) > 0;
  }
  inst.visibility = 0.0;
  double in_frame = 0.0; // Share of the outline inside the frame.
  const cv::Rect box = cv::boundingRect(inst.outline) & frame;
  if (area > 0.0 && box.area() > 0) {
    cv::Mat seen = cv::Mat::zeros(box.size(), CV_8UC1);
    auto fill = [&](const std::vector<cv::Point2f>& outline, uchar value) {
      std::vector<cv::Point> polygon;
      for (const cv::Point2f& p : outline)
        polygon.emplace_back(cvRound(p.x - box.x), cvRound(p.y - box.y));
      cv::fillPoly(seen, std::vector<std::vector<cv::Point>>{polygon}, cv::Scalar(value));
    };
    fill(inst.outline, 255);
    if (whole_in_view)
      in_frame = std::min(1.0, cv::countNonZero(seen) / area);
    for (size_t j : above)
      fill(instances[j].outline, 0);
    inst.visibility = std::min(1.0, cv::countNonZero(seen) / area);
  }
  const bool grasp_in_frame = inst.grasp.x >= kGraspMarginPx && inst.grasp.y >= kGraspMarginPx &&
                              inst.grasp.x < frame.width - kGraspMarginPx &&
                              inst.grasp.y < frame.height - kGraspMarginPx;
  // A pose completed by guided matching rests on a few pairs without the ratio test, and a
  // repeated design the frame does not place may be a copy off: too little evidence to send a
  // gripper to.
  inst.pickable = !inst.covered && !inst.guided && !inst.place_unsure && grasp_in_frame &&
                  inst.visibility >= kMinPickableVisibility &&
                  (!whole_in_view || 1.0 - in_frame <= kCoverTolerance);
  inst.pick_order = 0;
}

} // namespace

double overlap_area(const std::vector<cv::Point2f>& a, const std::vector<cv::Point2f>& b) {
  const std::vector<cv::Point2f> ha = hull_of(a), hb = hull_of(b);
  if (ha.size() < 3 || hb.size() < 3)
    return 0.0;
  std::vector<cv::Point2f> both;
  return std::max(0.0, static_cast<double>(cv::intersectConvexConvex(ha, hb, both, true)));
}

double hull_area(const std::vector<cv::Point2f>& outline) {
  return area_of(hull_of(outline));
}

int which_on_top(const Instance& a, const Model& model_a, const Instance& b, const Model& model_b,
                 const cv::Mat& grey, FeatureKind kind) {
  const std::vector<cv::Point2f> region = shared_area(a, b);
  if (region.size() < 3)
    return 0;
  int kept_a = 0, kept_b = 0;
  const double share_a = kept_share(a, model_a.features(kind), region, kept_a);
  const double share_b = kept_share(b, model_b.features(kind), region, kept_b);
  if (kept_a >= kMinTopFeatures && share_a >= kTopFeatureDominance * share_b)
    return +1;
  if (kept_b >= kMinTopFeatures && share_b >= kTopFeatureDominance * share_a)
    return -1;
  if (grey.empty())
    return 0;

  cv::Rect box = cv::boundingRect(region) & cv::Rect(0, 0, grey.cols, grey.rows);
  if (box.area() < kMinCorrelationPixels)
    return 0;
  cv::Mat region_mask = cv::Mat::zeros(box.size(), CV_8UC1);
  std::vector<cv::Point> polygon;
  for (const cv::Point2f& p : region)
    polygon.emplace_back(cvRound(p.x - box.x), cvRound(p.y - box.y));
  cv::fillConvexPoly(region_mask, polygon, cv::Scalar(255));
  const double ca = correlation(a, model_a, grey, box, region_mask);
  const double cb = correlation(b, model_b, grey, box, region_mask);
  if (ca >= kMinTopCorrelation && ca >= cb + kTopCorrelationMargin)
    return +1;
  if (cb >= kMinTopCorrelation && cb >= ca + kTopCorrelationMargin)
    return -1;
  return 0;
}

void drop_hidden_instances(std::vector<Instance>& instances, const std::vector<Model>& models,
                           FeatureKind kind) {
  const size_t n = instances.size();
  // Bounding boxes: of each instance's evidence and of its outline.
  std::vector<cv::Rect2f> evidence(n), extent(n);
  for (size_t i = 0; i < n; ++i) {
    evidence[i] = bounds(instances[i].support);
    extent[i] = bounds(instances[i].outline);
  }
  std::vector<char> drop(n, 0);
  for (size_t w = 0; w < n; ++w) {
    const Instance& weak = instances[w];
    if (weak.support.empty())
      continue;
    for (size_t s = 0; s < n && !drop[w]; ++s) {
      const Instance& other = instances[s];
      if (s == w || drop[s] || !touch(evidence[w], extent[s]))
        continue;
      // Then most of w's evidence must lie where the two overlap.
      const std::vector<cv::Point2f> region = shared_area(other, weak);
      if (region.size() < 3 ||
          2 * count_inside(weak.support, region) < static_cast<int>(weak.support.size()))
        continue;
      // Features only: the pixel comparison, made for pick safety, errs both ways.
      if (which_on_top(other, models[other.model], weak, models[weak.model], cv::Mat(), kind) > 0)
        drop[w] = 1;
    }
  }
  std::vector<Instance> kept;
  for (size_t i = 0; i < n; ++i)
    if (!drop[i])
      kept.push_back(std::move(instances[i]));
  instances = std::move(kept);
}

void assess_occlusion(std::vector<Instance>& instances, const std::vector<Model>& models,
                      const cv::Size& frame_size, const cv::Mat& grey, FeatureKind kind) {
  assess_occlusion(instances, models, frame_size, grey, cv::Mat(), kind);
}

void assess_occlusion(std::vector<Instance>& instances, const std::vector<Model>& models,
                      const cv::Size& frame_size, const cv::Mat& grey, const cv::Mat& colour,
                      FeatureKind kind, bool whole_in_view, const cv::Point2f& motion_blur) {
  if (!grey.empty() && (grey.type() != CV_8UC1 || grey.size() != frame_size))
    throw Error("assess_occlusion: the frame must be an 8-bit grey picture of the frame size");
  if (!colour.empty() && (grey.empty() || colour.type() != CV_8UC3 || colour.size() != frame_size))
    throw Error("assess_occlusion: the colour frame must be 8-bit BGR of the frame size, beside "
                "the grey one");
  const size_t n = instances.size();
  // above[i]: the instances lying on instance i; hidden[i]: the area they hide, in pixels.
  std::vector<std::vector<size_t>> above(n);
  std::vector<double> hidden(n, 0.0);
  std::vector<double> area(n);
  for (size_t i = 0; i < n; ++i) {
    area[i] = area_of(instances[i].outline);
    instances[i].covered = false;
  }
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j) {
      const double shared = overlap_area(instances[i].outline, instances[j].outline);
      if (shared <= kOverlapTolerance * std::min(area[i], area[j]))
        continue;
      const int top = which_on_top(instances[i], models[instances[i].model], instances[j],
                                   models[instances[j].model], grey, kind);
      if (top >= 0) { // j is under i, or nobody can tell: then neither is safe to pick
        above[j].push_back(i);
        hidden[j] += shared;
      }
      if (top <= 0) {
        above[i].push_back(j);
        hidden[i] += shared;
      }
    }

  const cv::Rect frame(0, 0, frame_size.width, frame_size.height);
  // Each instance on its own (the instances in parallel): it reads only the others' outlines.
  cv::parallel_for_(cv::Range(0, static_cast<int>(n)), [&](const cv::Range& range) {
    for (int k = range.start; k < range.end; ++k)
      assess_one(instances, static_cast<size_t>(k), models, frame, grey, colour, above[k],
                 hidden[k], area[k], whole_in_view, motion_blur);
  });

  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return instances[a].score > instances[b].score; });
  int rank = 0;
  for (size_t i : order)
    if (instances[i].pickable)
      instances[i].pick_order = ++rank;
}

} // namespace pickdetect
