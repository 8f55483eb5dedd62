// SPDX-License-Identifier: LGPL-2.1-or-later
#include "repeat_placement.hpp"

#include "foreign_cover.hpp"
#include "model_scene.hpp"
#include "polygon.hpp"

#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace pickdetect::detail {
namespace {

/// How the frame shows an instance's print, `others` (the other instances, which may lie on it)
/// left out: cells where it shows the print, and where it shows something else (denies_print).
struct PrintCells {
  int shown = 0, denied = 0;
};

PrintCells print_cells(const Instance& inst, const Model& model, const cv::Mat& grey,
                       const std::vector<const Instance*>& others, const cv::Point2f& motion_blur) {
  const CellComparison cmp = compare_cells(inst, model, grey, others, {}, {}, motion_blur);
  PrintCells out;
  for (const CellLook& look : cmp.looks) {
    out.shown += shows_print(look) ? 1 : 0;
    out.denied += denies_print(look, cmp) ? 1 : 0;
  }
  return out;
}

Instance shifted(const Instance& inst, const Model& model, const cv::Point2f& shift) {
  Instance out = inst;
  const cv::Matx33d by(1, 0, shift.x, 0, 1, shift.y, 0, 0, 1);
  place(out, model, inst.homography * by);
  set_grasp(out, model);
  return out;
}

} // namespace

void place_repeated_designs(std::vector<Instance>& instances, const std::vector<Model>& models,
                            const Matcher& matcher, const cv::Mat& grey,
                            const cv::Point2f& motion_blur) {
  if (grey.empty())
    return;
  // Decided for all first, then moved: each decision reads the others' outlines.
  std::vector<Instance> moved(instances.size());
  std::vector<char> is_moved(instances.size(), 0);
  cv::parallel_for_(cv::Range(0, static_cast<int>(instances.size())), [&](const cv::Range& r) {
    for (int i = r.start; i < r.end; ++i) {
      const Instance& inst = instances[static_cast<size_t>(i)];
      const std::vector<cv::Point2f>& shifts = matcher.repeat_shifts(inst.model);
      if (shifts.empty() || inst.outline.size() < 3)
        continue;
      const Model& model = models[static_cast<size_t>(inst.model)];
      // What lies on it is no evidence against a place: the other instances are left out.
      std::vector<const Instance*> others;
      for (size_t j = 0; j < instances.size(); ++j)
        if (j != static_cast<size_t>(i))
          others.push_back(&instances[j]);
      const PrintCells own = print_cells(inst, model, grey, others, motion_blur);
      const int need = static_cast<int>(
          std::ceil(std::max<double>(kMinShiftGainCells, kMinShiftGainShare * own.shown)));
      const double support = static_cast<double>(inst.support.size());
      int best = own.denied - need + 1;
      for (const cv::Point2f& shift : shifts) {
        Instance candidate = shifted(inst, model, shift);
        if (count_inside(inst.support, candidate.outline) < kMinShiftSupportShare * support)
          continue;
        const int denied = print_cells(candidate, model, grey, others, motion_blur).denied;
        if (denied < best) {
          best = denied;
          moved[static_cast<size_t>(i)] = std::move(candidate);
          is_moved[static_cast<size_t>(i)] = 1;
        }
      }
    }
  });
  for (size_t i = 0; i < instances.size(); ++i)
    if (is_moved[i])
      instances[i] = std::move(moved[i]);
}

} // namespace pickdetect::detail
