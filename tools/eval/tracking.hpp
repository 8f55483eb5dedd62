// SPDX-License-Identifier: LGPL-2.1-or-later
// The tracking figures of a video sequence (FORMAT.md, "Video sequences"): MOTA, IDF1, identity
// switches, fragmented tracks, ghost ids, objects counted against objects present.
//
// Choices FORMAT.md leaves open, made the same way in score.py:
//  - The per-frame pairing is the one of the per-frame figures (match_scene, per model);
//    detections are the TP and FP of that pairing (those paired with a don't-care instance
//    count nowhere).
//  - A detection without a track id pairs its true object with "no id": that is an identity
//    switch when the last pairing had an id (and the other way round), and it adds nothing to
//    IDTP nor to the ids an object was paired with.
//  - IDTP's one-to-one assignment is greedy: (true object, id) pairs by descending frames
//    shared, ties by the smaller true track, then the smaller id.
//  - A ghost is an id carried by detections in 5 frames or more (paired or not, any model)
//    that the assignment gave to no true object.
#pragma once

#include "dataset.hpp"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace pickdetect::eval {

constexpr int kTrackMinFrames = 5;

struct TrackingSummary {
  long required = 0, detections = 0, fn = 0, fp = 0, id_switches = 0, idtp = 0;
  std::optional<double> mota, idf1;
  long objects_present = 0, objects_counted = 0, fragmented = 0, ghosts = 0;
};

/// `detected[i]` are every model's detections in scene i of the sequence.
TrackingSummary score_tracking(const Dataset& dataset,
                               const std::map<size_t, std::vector<DetectedInstance>>& detected);

} // namespace pickdetect::eval
