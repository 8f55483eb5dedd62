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

/// Whether two instances' outlines overlap by at least kSamePlaceIoU (intersection over union):
/// they show one object.
bool same_place(const Instance& a, const Instance& b);

} // namespace pickdetect::detail
