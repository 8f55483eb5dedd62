// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: look-alike products told apart by the frame's colour.
#pragma once

#include <pickdetect/detector.hpp>
#include <pickdetect/model.hpp>

#include <opencv2/core.hpp>

#include <vector>

namespace pickdetect::detail {

/// How far the frame's colour under an instance's pose is from its model's colour: the mean,
/// over points of the model's mask, of the L1 distance between the chromaticities (each
/// channel over the sum of the three, so that the light's gain cancels) of the model's colour
/// picture and of the frame's pixel the pose puts the point on. Dark points and the frame's
/// saturated ones are left out. NaN when the model or the frame has no colour, or too few
/// points are seen.
double colour_misfit(const Instance& instance, const Model& model, const cv::Mat& frame_bgr);

/// Look-alike products that differ in colour (one design printed in a blue and an orange
/// edition) share all their features, so that their distinct matches cannot tell them apart.
/// Of two instances of different products in one place (outlines overlapping by kSamePlaceIoU,
/// as drop_look_alikes asks), the frame's colour (`frame_bgr`, CV_8UC3) decides when both
/// models have colour, the better fit is a fit (misfit at most kMaxColourMisfit) and the other
/// is clearly worse (kColourMargin): the worse goes, and all of the better's matches become
/// its own (distinct_matches), as the colour told its rival out. When neither fits (both
/// misfits above kNoColourFit) the object is an edition of no model, and both go: a colour
/// that fits no model is not forced on one. An instance that loses to any rival goes.
/// Undecided pairs are left to drop_look_alikes.
void decide_by_colour(std::vector<Instance>& instances, const std::vector<Model>& models,
                      const cv::Mat& frame_bgr);

} // namespace pickdetect::detail
