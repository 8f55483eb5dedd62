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

/// Whether `strong` explains `weak`: same place, and most of weak's support lies on it.
bool explains(const Instance& strong, const Instance& weak) {
  if (!same_place(strong, weak))
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

bool same_place(const Instance& a, const Instance& b) {
  // overlap_area intersects the outlines' convex hulls: the union is of the hulls too, so the
  // ratio stays within 0-1 for an outline that is not convex.
  const double shared = overlap_area(a.outline, b.outline);
  const double joint = hull_area(a.outline) + hull_area(b.outline) - shared;
  return joint > 0.0 && shared >= kSamePlaceIoU * joint;
}

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
