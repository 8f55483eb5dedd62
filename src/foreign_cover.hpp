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
/// of its grey levels at least this), and the frame too: a flat frame cell (a highlight that
/// washed the print out, or a plain surface) tells nothing either way.
constexpr double kMinCellTexture = 8.0;
constexpr double kMinFrameTexture = 5.0;
/// A textured frame cell correlating this little with the model's picture carried there shows
/// something else.
constexpr double kMaxForeignCorrelation = 0.3;

/// An instance counts as covered when at least this many connected cells show something else
/// (scattered cells of noise and glare measured at most 3 on the development sets' uncovered
/// instances, 0 for most).
constexpr int kMinForeignCells = 4;

/// The largest 4-connected group of cells where the frame shows something else than the
/// instance: the model's picture, carried into the frame by the instance's homography, and the
/// frame are compared cell by cell (normalised cross-correlation after a light blur). Cells
/// outside the frame, outside the model's mask or under one of `above` (instances lying on
/// this one) are not compared. Scattered single cells come from noise and glare; an object
/// lying on the instance leaves a connected group. `grey`: the frame, CV_8UC1.
int foreign_cover_cells(const Instance& inst, const Model& model, const cv::Mat& grey,
                        const std::vector<const Instance*>& above);

} // namespace pickdetect::detail
