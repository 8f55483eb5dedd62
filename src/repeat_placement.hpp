// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: an instance of a repeated design placed where all its parts agree.
#pragma once

#include <pickdetect/detector.hpp>
#include <pickdetect/matching.hpp>
#include <pickdetect/model.hpp>

#include <opencv2/core.hpp>

#include <vector>

namespace pickdetect::detail {

/// A candidate place must explain the frame better than the instance's own place by at least
/// this many cells, each place judged where the other does not predict the print (cells that
/// show the print, less cells that show something else): a copy predicted where the belt, the
/// tote or another object lies denies a whole part's cells; noise and glare deny a few in any
/// place.
constexpr int kMinShiftGainCells = 6;
/// A place shifted by a copy whose grasp point lies this many frame pixels or more from the
/// instance's and that explains the frame within kMinShiftGainCells as well leaves the instance
/// Instance::place_unsure; nearer copies (a small pattern repeated within a picture) move the
/// grasp by little.
constexpr double kMinUnsureShiftPx = 24.0;
/// A candidate place must keep this share of the instance's supporting keypoints on its outline.
constexpr double kMinShiftSupportShare = 0.9;

/// `inst` moved by `shift` (model pixels) along its model's picture: its homography, outline,
/// centre and grasp point carried with it, all else (its support) as it was.
Instance shifted(const Instance& inst, const Model& model, const cv::Point2f& shift);

/// A match to a repeated part votes for every place it could mean; where a part of the design is
/// hidden (out of the frame, under something) or the votes of neighbouring copies tie, the
/// instance can come out shifted by a copy or more along the design, its outline running past
/// the object's end. For each instance of a model with repeat shifts (`matcher`'s
/// repeat_shifts, model pixels), the instance is moved by each shift that keeps its
/// supporting keypoints on it, and the place that best explains the frame's pixels where the
/// two places differ is kept: the true place predicts print only where the object is, and the
/// frame shows it there; a shifted one predicts a copy where the belt, the tote or another
/// object shows, or outside the frame. Where both predict the print, a repeated design predicts
/// the same: no evidence either way. An instance whose place, once chosen, has a rival far
/// enough off (kMinUnsureShiftPx) that explains the frame nearly as well is
/// Instance::place_unsure. `grey`: the frame, CV_8UC1; empty: nothing is moved; `motion_blur`: the
/// frame's (compare_cells).
void place_repeated_designs(std::vector<Instance>& instances, const std::vector<Model>& models,
                            const Matcher& matcher, const cv::Mat& grey,
                            const cv::Point2f& motion_blur = cv::Point2f());

} // namespace pickdetect::detail
