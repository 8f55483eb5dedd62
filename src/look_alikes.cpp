// SPDX-License-Identifier: LGPL-2.1-or-later
// Instances of different models in one place: the product is named by its distinct matches.
#include "look_alikes.hpp"

#include "polygon.hpp"

#include <pickdetect/occlusion.hpp>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace pickdetect::detail {
namespace {

/// Outlines of two instances of different models overlapping this much (intersection over
/// union) show the same object. Different products lying on each other measured at most 0.62
/// on the development sets, look-alike ghosts at least 0.96.
constexpr double kSamePlaceIoU = 0.8;
/// Look-alike models found in one place gather a few distinct matches each by chance (0-5 on
/// a nine-product family): the product's own instance must have at least kMinDistinct and
/// kDistinctMargin more than any of them.
constexpr int kMinDistinct = 6;
constexpr int kDistinctMargin = 3;

double outline_area(const Instance& inst) {
  return inst.outline.size() >= 3 ? std::abs(cv::contourArea(inst.outline)) : 0.0;
}

/// Whether `strong` explains `weak`: same place, and most of weak's support lies on it.
bool explains(const Instance& strong, const Instance& weak) {
  const double shared = overlap_area(strong.outline, weak.outline);
  const double joint = outline_area(strong) + outline_area(weak) - shared;
  if (!(joint > 0.0) || shared < kSamePlaceIoU * joint)
    return false;
  return 2 * static_cast<size_t>(count_inside(weak.support, strong.outline)) >= weak.support.size();
}

bool by_position(const cv::Point2f& a, const cv::Point2f& b) {
  return a.x < b.x || (a.x == b.x && a.y < b.y);
}

/// Whether at least half of the smaller of two sorted supports are keypoints of the other:
/// one scene feature shows one object.
bool rest_on_the_same_features(const std::vector<cv::Point2f>& a,
                               const std::vector<cv::Point2f>& b) {
  size_t common = 0;
  for (size_t i = 0, j = 0; i < a.size() && j < b.size();) {
    if (by_position(a[i], b[j]))
      ++i;
    else if (by_position(b[j], a[i]))
      ++j;
    else {
      ++common;
      ++i;
      ++j;
    }
  }
  return common > 0 && 2 * common >= std::min(a.size(), b.size());
}

} // namespace

void drop_look_alikes(std::vector<Instance>& instances, int min_distinct_alone) {
  const size_t n = instances.size();
  // Evidence for the product: distinct matches first, then all matches, then the order.
  auto stronger = [&](size_t a, size_t b) {
    const Instance& x = instances[a];
    const Instance& y = instances[b];
    if (x.distinct_matches != y.distinct_matches)
      return x.distinct_matches > y.distinct_matches;
    return x.matches > y.matches || (x.matches == y.matches && a < b);
  };
  // Sorted support of each instance, to find the scene keypoints two instances both rest on.
  std::vector<std::vector<cv::Point2f>> support(n);
  for (size_t i = 0; i < n; ++i) {
    support[i] = instances[i].support;
    std::sort(support[i].begin(), support[i].end(), by_position);
  }
  auto shared = [&](size_t a, size_t b) {
    return rest_on_the_same_features(support[a], support[b]);
  };
  std::vector<char> drop(n, 0);
  for (size_t w = 0; w < n; ++w) {
    const Instance& weak = instances[w];
    int best_rival = -1;
    for (size_t r = 0; r < n && !drop[w]; ++r) {
      const Instance& other = instances[r];
      if (r == w || other.model == weak.model)
        continue;
      // `other` takes w's place when it explains w's evidence and is stronger.
      const bool same_features = shared(r, w);
      const bool on_w = same_features || explains(other, weak);
      // Two views of one product in one place: the product is known, the view with more
      // matches is the one seen. They are no rivals for naming the product.
      if (other.model_name == weak.model_name) {
        if (on_w && (other.matches > weak.matches || (other.matches == weak.matches && r < w)))
          drop[w] = 1;
        continue;
      }
      if (on_w && stronger(r, w))
        drop[w] = 1;
      // Rivals for w's place: each explains the other (a box lying on another does not).
      if (same_features || (on_w && explains(weak, other)))
        best_rival = std::max(best_rival, other.distinct_matches);
    }
    // The strongest of look-alikes in one place names the product only when its own evidence
    // is an instance's worth and stands out from theirs.
    if (!drop[w] && best_rival >= 0)
      drop[w] = weak.distinct_matches < kMinDistinct ||
                weak.distinct_matches < best_rival + kDistinctMargin;
    // Without rivals (they fell below min-matches), a shared design still needs some evidence
    // of this product.
    if (!drop[w])
      drop[w] = weak.distinct_matches < min_distinct_alone;
  }
  std::vector<Instance> kept;
  for (size_t i = 0; i < n; ++i)
    if (!drop[i])
      kept.push_back(std::move(instances[i]));
  instances = std::move(kept);
}

} // namespace pickdetect::detail

namespace pickdetect::detail {
namespace {

/// Points of the model's mask sampled for its colour, about this many.
constexpr double kColourSamples = 2000.0;
/// Fewest points seen in the frame for a colour misfit.
constexpr int kMinColourPoints = 50;
/// Points darker than this (sum of the three channels, of 765) have no reliable chromaticity.
constexpr int kMinColourSum = 60;
/// Frame pixels with a channel this bright may be clipped (a highlight): their colour is not
/// the object's.
constexpr int kSaturated = 250;
/// Colour decides between look-alikes when the better fit's misfit is at most this (a fit at
/// all: chromaticity distances run from 0 to 4/3)...
constexpr double kMaxColourMisfit = 0.12;
/// ...and the worse one's is at least kColourRatio times and kColourMargin more than it. The
/// right edition measured 0.02-0.05 on the tests' scenes, the wrong one 0.6, and an edition of
/// no model (its hue turned by 120 degrees) 0.29 and 0.68. A colour cast raises the right
/// one's: 0.064, 0.114, 0.161 and 0.242 with blue divided and red multiplied by 1.1, 1.2, 1.3
/// and 1.5 (the wrong one's 0.67-0.85): colour decides up to a cast of about 1.2, leaves it to
/// the matches up to about 1.4, and beyond names neither.
constexpr double kColourRatio = 1.5;
constexpr double kColourMargin = 0.04;
/// Look-alikes whose colours all misfit by more than this are another edition, of no model.
constexpr double kNoColourFit = 0.2;

/// The chromaticity distance of two BGR pixels, or a negative number when either is too dark.
double chroma_distance(const cv::Vec3b& a, const cv::Vec3b& b) {
  const int sa = a[0] + a[1] + a[2], sb = b[0] + b[1] + b[2];
  if (sa < kMinColourSum || sb < kMinColourSum)
    return -1.0;
  double d = 0.0;
  for (int c = 0; c < 3; ++c)
    d += std::abs(a[c] / static_cast<double>(sa) - b[c] / static_cast<double>(sb));
  return d;
}

bool same_place(const Instance& a, const Instance& b) {
  const double shared = overlap_area(a.outline, b.outline);
  const double joint = outline_area(a) + outline_area(b) - shared;
  return joint > 0.0 && shared >= kSamePlaceIoU * joint;
}

} // namespace

double colour_misfit(const Instance& instance, const Model& model, const cv::Mat& frame_bgr) {
  if (model.colour.empty() || frame_bgr.empty() || frame_bgr.type() != CV_8UC3 ||
      model.colour.size() != model.mask.size())
    return std::numeric_limits<double>::quiet_NaN();
  // The model's colour at about the frame's resolution: a frame pixel averages 1 / scale model
  // pixels.
  cv::Mat picture = model.colour;
  const double sigma = instance.scale > 0.0 ? 0.5 / instance.scale : 0.0;
  if (sigma > 0.5)
    cv::GaussianBlur(model.colour, picture, cv::Size(), sigma);
  const double area = std::max(1, cv::countNonZero(model.mask));
  const int step = std::max(1, static_cast<int>(std::sqrt(area / kColourSamples)));
  const cv::Matx33d& h = instance.homography;
  double sum = 0.0;
  int seen = 0;
  for (int y = step / 2; y < model.mask.rows; y += step)
    for (int x = step / 2; x < model.mask.cols; x += step) {
      if (!model.mask.at<uchar>(y, x))
        continue;
      const cv::Vec3d q = h * cv::Vec3d(x + 0.5, y + 0.5, 1.0);
      if (!(q[2] > 0.0))
        continue;
      const int u = static_cast<int>(std::floor(q[0] / q[2])),
                v = static_cast<int>(std::floor(q[1] / q[2]));
      if (u < 0 || v < 0 || u >= frame_bgr.cols || v >= frame_bgr.rows)
        continue;
      const cv::Vec3b f = frame_bgr.at<cv::Vec3b>(v, u);
      if (f[0] >= kSaturated || f[1] >= kSaturated || f[2] >= kSaturated)
        continue;
      const double d = chroma_distance(picture.at<cv::Vec3b>(y, x), f);
      if (d < 0.0)
        continue;
      sum += d;
      ++seen;
    }
  return seen >= kMinColourPoints ? sum / seen : std::numeric_limits<double>::quiet_NaN();
}

void decide_by_colour(std::vector<Instance>& instances, const std::vector<Model>& models,
                      const cv::Mat& frame_bgr) {
  const size_t n = instances.size();
  if (frame_bgr.empty() || n < 2)
    return;
  std::vector<double> misfit(n, -1.0); // -1: not measured yet.
  auto misfit_of = [&](size_t i) {
    if (misfit[i] == -1.0)
      misfit[i] =
          colour_misfit(instances[i], models[static_cast<size_t>(instances[i].model)], frame_bgr);
    return misfit[i];
  };
  std::vector<cv::Rect2f> box(n);
  for (size_t i = 0; i < n; ++i)
    box[i] = bounds(instances[i].outline);
  std::vector<char> lost(n, 0), won(n, 0);
  for (size_t a = 0; a < n; ++a)
    for (size_t b = a + 1; b < n; ++b) {
      const Instance& x = instances[a];
      const Instance& y = instances[b];
      if (x.model_name == y.model_name || models[x.model].colour.empty() ||
          models[y.model].colour.empty() || !touch(box[a], box[b]) || !same_place(x, y))
        continue;
      const double fa = misfit_of(a), fb = misfit_of(b);
      if (!std::isfinite(fa) || !std::isfinite(fb))
        continue;
      const bool a_better = fa < fb;
      const double lo = a_better ? fa : fb, hi = a_better ? fb : fa;
      if (lo > kNoColourFit) { // Another edition, of no model: neither is named.
        lost[a] = lost[b] = 1;
        continue;
      }
      if (lo > kMaxColourMisfit || hi < kColourRatio * lo || hi < lo + kColourMargin)
        continue;
      lost[a_better ? b : a] = 1;
      won[a_better ? a : b] = 1;
    }
  std::vector<Instance> kept;
  for (size_t i = 0; i < n; ++i) {
    if (lost[i])
      continue;
    if (won[i])
      instances[i].distinct_matches = instances[i].matches;
    kept.push_back(std::move(instances[i]));
  }
  instances = std::move(kept);
}

} // namespace pickdetect::detail
