// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: something that is no instance lying on one (a package of another kind,
// a bag, a hand), seen in the frame's pixels.
#pragma once

#include <pickdetect/detector.hpp>
#include <pickdetect/model.hpp>

#include <opencv2/core.hpp>

#include <vector>

namespace pickdetect::detail {

/// Side of the square cells the instance is compared in, in frame pixels.
constexpr int kCoverCell = 12;
/// A cell is compared only where the model's picture has texture there (standard deviation
/// of its band-passed grey levels at least this); the frame is textured there (at least the
/// second figure) or flat (a highlight that washed the print out, or a plain surface).
constexpr double kMinCellTexture = 8.0;
constexpr double kMinFrameTexture = 5.0;
/// A textured frame cell correlating this little with the model's picture carried there shows
/// something else.
constexpr double kMaxForeignCorrelation = 0.3;
/// A flat frame cell shows a plain surface lying on the print when the print, with as much of
/// its detail as the frame keeps where the print is seen (the median over the matching cells:
/// blur, exposure), would show at least kFlatCoverDetail times the flatness threshold there,
/// the frame shows at most kFlatCoverShare of that, and the cell is no more than kGlareLevels
/// of the model's grey levels brighter than the print in the frame's light (brighter: a
/// highlight washing the print out, or a white surface; they cannot be told apart).
constexpr double kFlatCoverDetail = 2.0;
constexpr double kFlatCoverShare = 0.25;
constexpr double kGlareLevels = 30.0;

/// An instance counts as covered when at least this many connected cells show something else
/// (groups of noise, glare and blur on uncovered instances stayed smaller on the development
/// sets and the README's synthetic ones).
constexpr int kMinForeignCells = 4;

/// The largest 4-connected group of cells where the frame shows something else than the
/// instance: the model's picture, carried into the frame by the instance's homography, and the
/// frame are compared cell by cell (normalised cross-correlation at half size, through a
/// band-pass that leaves out light and blur); a flat frame cell counts when the print would
/// show clear detail there and it is no highlight (kFlatCoverDetail). Cells outside the frame,
/// outside the model's mask, near the edge of what is seen of it, or under one of `above`
/// (instances lying on this one) are not compared. Scattered single cells come from noise and
/// glare; an object lying on the instance leaves a connected group. `grey`: the frame, CV_8UC1.
int foreign_cover_cells(const Instance& inst, const Model& model, const cv::Mat& grey,
                        const std::vector<const Instance*>& above);

} // namespace pickdetect::detail
