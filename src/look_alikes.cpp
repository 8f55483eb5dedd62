// SPDX-License-Identifier: LGPL-2.1-or-later
// Instances of different models in the same place: the weaker one is a look-alike.
#include "look_alikes.hpp"

#include <pickdetect/occlusion.hpp>

#include <opencv2/imgproc.hpp>

#include <cmath>

namespace pickdetect::detail {
namespace {

/// Outlines of two instances of different models overlapping this much (intersection over
/// union) show the same object. Different products lying on each other measured at most 0.62
/// on the development sets, look-alike ghosts at least 0.96.
constexpr double kSamePlaceIoU = 0.8;

double outline_area(const Instance& inst) {
  return inst.outline.size() >= 3 ? std::abs(cv::contourArea(inst.outline)) : 0.0;
}

/// Whether `strong` explains `weak`: same place, and most of weak's support lies on it.
bool explains(const Instance& strong, const Instance& weak) {
  const double shared = overlap_area(strong.outline, weak.outline);
  const double joint = outline_area(strong) + outline_area(weak) - shared;
  if (!(joint > 0.0) || shared < kSamePlaceIoU * joint)
    return false;
  size_t inside = 0;
  for (const cv::Point2f& p : weak.support)
    inside += cv::pointPolygonTest(strong.outline, p, false) >= 0;
  return 2 * inside >= weak.support.size();
}

} // namespace

void drop_look_alikes(std::vector<Instance>& instances) {
  std::vector<char> drop(instances.size(), 0);
  for (size_t w = 0; w < instances.size(); ++w)
    for (size_t s = 0; s < instances.size() && !drop[w]; ++s) {
      const Instance& strong = instances[s];
      const Instance& weak = instances[w];
      // Strictly stronger (ties: the earlier one), of another model, itself kept.
      const bool stronger =
          strong.matches > weak.matches || (strong.matches == weak.matches && s < w);
      if (s != w && !drop[s] && strong.model != weak.model && stronger && explains(strong, weak))
        drop[w] = 1;
    }
  std::vector<Instance> kept;
  for (size_t i = 0; i < instances.size(); ++i)
    if (!drop[i])
      kept.push_back(std::move(instances[i]));
  instances = std::move(kept);
}

} // namespace pickdetect::detail
