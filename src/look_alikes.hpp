// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: instances of different models found in the same place.
#pragma once

#include <pickdetect/detector.hpp>
#include <pickdetect/model.hpp>

#include <opencv2/core.hpp>

#include <vector>

namespace pickdetect::detail {

/// Look-alike products (a family sharing a brand's design) let one object come out as an
/// instance of its own model and as instances of its look-alikes, in the same place: with
/// Ambiguity::Share every model gets the matches of the shared design, and only the product's
/// own design gives distinct matches (Instance::distinct_matches). Two different objects cannot
/// lie there both. Instances are rivals when they are of different models and one explains the
/// other: it covers at least kSamePlaceIoU of the pair's joint outline (intersection over
/// union) and holds at least half of the other's supporting keypoints. A box lying on another
/// keeps its own evidence outside the box below, so both stay.
/// Of rivals, all but the one with the most distinct matches (then the most matches) go; that
/// one stays only with at least kMinDistinct distinct matches and kDistinctMargin more than
/// any rival had. Otherwise which product lies there is not known, and none is reported.
/// Views of one product (models of one name) in one place are no rivals: the one with more
/// matches stays, whatever their distinct matches.
/// Any instance, rivals or not, needs at least `min_distinct_alone` distinct matches (the
/// detector asks for half of min-matches).
void drop_look_alikes(std::vector<Instance>& instances, int min_distinct_alone);

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
