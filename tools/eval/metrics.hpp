// SPDX-License-Identifier: LGPL-2.1-or-later
// The benchmark's metrics (FORMAT.md, "Metrics"), per model and pooled over models.
//
// Choices FORMAT.md leaves open, made the same way in score.py:
//  - Polygons are clipped to the frame exactly (geometry.hpp); outlines may be convex or not.
//  - Greedy matching takes candidate pairs (IoU >= 0.5) by descending IoU; ties go to the
//    earlier detection, then the earlier true instance (file order).
//  - Don't-care instances (visible < 0.3) take part in the matching like any other; a detection
//    paired with one is neither TP nor FP, and its area counts in no pixel figure.
//  - The 95th percentile interpolates linearly between order statistics (rank 0.95 * (n - 1)).
//  - Principal points: mean over every (TP, point) pair of the distance between the detected
//    and the true point of the same index (points beyond the shorter list are ignored).
//  - Pick safety counts only scenes in which every instance has `covered`. Pick precision:
//    detections flagged pickable there, safe when paired (required or don't care) with an
//    instance whose covered < 0.02; unpaired ones are unsafe.
//  - A ratio whose denominator is 0 is undefined (JSON null, "-" in tables).
//  - ms_per_frame: per model, the median over frames of that model's time (one element per
//    model); overall, the median over frames of the frame's time: the time of the element that
//    had every model loaded at once plus any per-model times (the cost of finding every model in
//    a frame). With all models in one element there is no per-model time (null).
#pragma once

#include "dataset.hpp"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace pickdetect::eval {

constexpr double kDontCareVisible = 0.3;
constexpr double kMatchIoU = 0.5;
constexpr double kPickCovered = 0.02;

/// The figures of one model (or of all models pooled).
struct Summary {
  long tp = 0, fp = 0, fn = 0;
  std::optional<double> object_precision, object_recall;
  std::optional<double> pixel_precision, pixel_recall;
  std::optional<double> center_mean_px, center_p95_px, points_mean_px;
  std::optional<double> pick_precision, pick_recall;
  std::optional<double> ms_per_frame;
};

/// Sums from which a Summary is computed; adding two of them pools their counts.
struct Tally {
  long tp = 0, fp = 0, required = 0;
  double tp_intersection = 0.0;      ///< Sum over TP of |D ∩ G|.
  double counted_detected = 0.0;     ///< Sum over TP and FP of |D|.
  double required_true = 0.0;        ///< Sum over required instances of |G|.
  std::vector<double> center_errors; ///< One per TP.
  double point_error_sum = 0.0;
  long point_count = 0;
  long pickable_flagged = 0, pickable_safe = 0; ///< Pick precision.
  long pick_required = 0, pick_found = 0;       ///< Pick recall.
  std::vector<double> ms;                       ///< One per frame.

  void add(const Tally& other);
  Summary summary() const;
};

/// How one detection of a scene was judged.
struct Pairing {
  int instance = -1; ///< Index of the paired true instance in the scene, -1 when none.
  double iou = 0.0;
};

/// Pairs the detections and true instances of one model in one scene (indices into the
/// scene's lists; entries of other models are ignored). Returns one Pairing per detection.
std::vector<Pairing> match_scene(const Scene& scene, const std::vector<DetectedInstance>& detected,
                                 const std::string& model);

/// Accumulates scenes and reports per model and overall.
class Scorer {
public:
  explicit Scorer(const Dataset& dataset);

  /// Scores the detections of `model` in scene `scene_index` (the detections of other models
  /// are ignored). Throws FormatError for a model the dataset does not have.
  void add_scene(size_t scene_index, const std::vector<DetectedInstance>& detected,
                 const std::string& model);
  /// Scores every model's detections in the scene.
  void add_scene(size_t scene_index, const std::vector<DetectedInstance>& detected);
  /// Records how long the model's element took on the scene's frame.
  void add_time(size_t scene_index, const std::string& model, double ms);
  /// Records how long the element with all the models loaded at once took on the frame.
  void add_frame_time(size_t scene_index, double ms);

  Summary model_summary(const std::string& model) const;
  Summary overall() const;
  const Dataset& dataset() const { return dataset_; }
  /// Centre error of every true positive, keyed by (scene index, true instance index).
  const std::map<std::pair<size_t, size_t>, double>& center_errors() const {
    return center_by_truth_;
  }
  /// Every detection scored, per scene (for the tracking figures of a sequence).
  const std::map<size_t, std::vector<DetectedInstance>>& detections() const { return detections_; }

private:
  const Dataset& dataset_;
  std::map<std::string, Tally> tallies_;
  std::map<std::pair<size_t, size_t>, double> center_by_truth_;
  std::map<size_t, double> frame_ms_; ///< Scene -> time summed over models.
  std::map<size_t, std::vector<DetectedInstance>> detections_;
};

/// Centre errors compared on the same instances: the mean per method over the true instances
/// that every method found (each method's own mean is over its own true positives, so a method
/// that finds only the easy instances can show a lower one).
struct PairedCenters {
  long instances = 0;
  std::map<std::string, double> mean_px; ///< Per method; empty when `instances` is 0.
};
PairedCenters paired_centers(const std::map<std::string, Scorer>& scorers);

/// Scores a whole detections file against a dataset: one Scorer per method ("" when the lines
/// carry no method). Throws FormatError on images the dataset lacks or listed twice.
std::map<std::string, Scorer> score_detections(const Dataset& dataset,
                                               const std::vector<SceneDetections>& lines);

/// The summary as a JSON object with FORMAT.md's keys (undefined ratios are null).
std::string summary_json(const Summary& s, int indent = 0);

/// A JSON document with per model and overall figures for each method:
/// {"dataset": NAME, "methods": {METHOD: {"overall": {...}, "models": {MODEL: {...}}}}};
/// a video sequence (fps) adds "tracking" to each method (tracking.hpp's figures).
std::string report_json(const Dataset& dataset, const std::map<std::string, Scorer>& scorers);

/// A table shaped like the paper's Table 1, one row per model and method, then overall rows.
std::string report_table(const Dataset& dataset, const std::map<std::string, Scorer>& scorers);

} // namespace pickdetect::eval
