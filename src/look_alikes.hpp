// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: instances of different models found in the same place.
#pragma once

#include <pickdetect/detector.hpp>

#include <vector>

namespace pickdetect::detail {

/// Look-alike products (a family sharing a brand's design) let a few of one product's features
/// match another product's picture, so one object can come out as a strong instance of its own
/// model and a weak one of a look-alike, in the same place. Two different objects cannot lie
/// there both: an instance is dropped when an instance of another model with more matches
/// covers at least kSamePlaceIoU of the pair's joint outline (intersection over union) and
/// holds at least half of its supporting keypoints. A box lying on another keeps its own
/// evidence outside the box below, so it stays.
void drop_look_alikes(std::vector<Instance>& instances);

} // namespace pickdetect::detail
