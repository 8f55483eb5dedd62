// SPDX-License-Identifier: LGPL-2.1-or-later
#include "repeat_placement.hpp"

#include "foreign_cover.hpp"
#include "model_scene.hpp"
#include "polygon.hpp"

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstddef>
#include <limits>

namespace pickdetect::detail {
namespace {

/// How well a place explains the frame where another place of the same design does not
/// predict it (cells whose centres lie outside `other`, an outline): the cells that show the
/// print, less those that show something else (denies_print). Where both places predict the
/// print, a repeated design predicts the same there, and which cells are compared depends
/// only on how near each outline's edge they lie: no evidence either way.
int explained_beyond(const CellComparison& cmp, const std::vector<cv::Point2f>& other) {
  int score = 0;
  for (int r = 0; r < cmp.rows; ++r)
    for (int c = 0; c < cmp.columns; ++c) {
      const CellLook& look = cmp.looks[static_cast<size_t>(r) * cmp.columns + c];
      if (!look.compared)
        continue;
      const cv::Point2f centre(
          static_cast<float>(cmp.origin.x + kCoverCell * c) + 0.5f * kCoverCell,
          static_cast<float>(cmp.origin.y + kCoverCell * r) + 0.5f * kCoverCell);
      if (cv::pointPolygonTest(other, centre, false) >= 0)
        continue;
      score += shows_print(look) ? 1 : denies_print(look, cmp) ? -1 : 0;
    }
  return score;
}

/// The best of an instance's places shifted by a copy, if one explains the frame better by
/// kMinShiftGainCells, and how nearly the best of those far enough off to matter
/// (kMinUnsureShiftPx) comes to it (gain over the instance's own place).
struct ShiftChoice {
  bool move = false;
  Instance moved;
  int rival_gain = std::numeric_limits<int>::min();
};

ShiftChoice choose_shift(const Instance& inst, const Model& model,
                         const std::vector<cv::Point2f>& shifts, const cv::Mat& grey,
                         const std::vector<const Instance*>& others,
                         const cv::Point2f& motion_blur) {
  ShiftChoice out;
  // What lies on it is no evidence against a place: `others` are left out of each comparison.
  const CellComparison own = compare_cells(inst, model, grey, others, {}, {}, motion_blur);
  const double support = static_cast<double>(inst.support.size());
  int best_gain = kMinShiftGainCells - 1;
  for (const cv::Point2f& shift : shifts) {
    Instance candidate = shifted(inst, model, shift);
    if (count_inside(inst.support, candidate.outline) < kMinShiftSupportShare * support)
      continue;
    const CellComparison there = compare_cells(candidate, model, grey, others, {}, {}, motion_blur);
    // Each place judged where only it predicts the print: the true place shows it there,
    // a shifted one predicts a copy where the belt, the tote or another object shows.
    const int gain =
        explained_beyond(there, inst.outline) - explained_beyond(own, candidate.outline);
    if (cv::norm(candidate.grasp - inst.grasp) >= kMinUnsureShiftPx)
      out.rival_gain = std::max(out.rival_gain, gain);
    if (gain > best_gain) {
      best_gain = gain;
      out.moved = std::move(candidate);
      out.move = true;
    }
  }
  return out;
}

} // namespace

Instance shifted(const Instance& inst, const Model& model, const cv::Point2f& shift) {
  Instance out = inst;
  const cv::Matx33d by(1, 0, shift.x, 0, 1, shift.y, 0, 0, 1);
  place(out, model, inst.homography * by);
  set_grasp(out, model);
  return out;
}

void place_repeated_designs(std::vector<Instance>& instances, const std::vector<Model>& models,
                            const Matcher& matcher, const cv::Mat& grey,
                            const cv::Point2f& motion_blur) {
  if (grey.empty())
    return;
  // Decided for all first, then moved: each decision reads the others' outlines.
  std::vector<Instance> placed(instances.size());
  std::vector<char> is_placed(instances.size(), 0);
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
      ShiftChoice choice = choose_shift(inst, model, shifts, grey, others, motion_blur);
      Instance& out = placed[static_cast<size_t>(i)];
      out = choice.move ? std::move(choice.moved) : inst;
      // How sure the chosen place is, against its own rivals.
      if (choice.move)
        choice = choose_shift(out, model, shifts, grey, others, motion_blur);
      out.place_unsure = choice.rival_gain > -kMinShiftGainCells;
      is_placed[static_cast<size_t>(i)] = 1;
    }
  });
  for (size_t i = 0; i < instances.size(); ++i)
    if (is_placed[i])
      instances[i] = std::move(placed[i]);
}

} // namespace pickdetect::detail
