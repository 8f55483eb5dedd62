// SPDX-License-Identifier: LGPL-2.1-or-later
// The benchmark formats (see the benchmark's FORMAT.md): dataset.json and detections JSON Lines.
#pragma once

#include "geometry.hpp"

#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace pickdetect::eval {

/// A file that does not follow the format. The message names the file and the field
/// (e.g. "data/dataset.json: scenes[2].instances[0].visible: expected a number, got a string").
class FormatError : public std::runtime_error {
public:
  explicit FormatError(const std::string& what) : std::runtime_error(what) {}
};

struct ModelInfo {
  std::string name;
  std::string image;                   ///< As written in the file (relative to the dataset folder).
  std::vector<Point> principal_points; ///< [0] is the object centre.
  Polygon polygon;
};

struct TrueInstance {
  std::string model;
  std::vector<Point> points;
  Polygon polygon;
  double visible = 1.0;
  std::optional<double> covered; ///< Absent where unknown.
  std::optional<double> in_frame;
  std::optional<int> z;
  std::optional<double> angle, scale, tilt;
  /// Video sequences: the identity of the physical object, the same in every frame.
  std::optional<long long> track;
};

struct Scene {
  std::string image; ///< As written in the file (relative to the dataset folder).
  int width = 0;
  int height = 0;
  std::vector<TrueInstance> instances;
};

struct Dataset {
  std::string name;
  std::string dir;               ///< Folder holding dataset.json; images are relative to it.
  std::string file;              ///< Path of dataset.json.
  std::vector<ModelInfo> models; ///< In the file's order.
  std::vector<Scene> scenes;
  /// Video sequences (FORMAT.md): frames per second; the scenes are the frames, in order, and
  /// every instance has its `track`.
  std::optional<double> fps;

  const ModelInfo* find_model(const std::string& name) const;
  /// dir joined with a path from the file (kept as is when absolute).
  std::string path_of(const std::string& relative) const;
};

/// Reads DIR/dataset.json (or the given .json file). Throws FormatError naming the file and
/// the field that is wrong. Does not open the pictures.
Dataset load_dataset(const std::string& dir_or_file);

/// Parses a dataset from text; `origin` names the file in error messages.
Dataset parse_dataset(const std::string& text, const std::string& origin, const std::string& dir);

struct DetectedInstance {
  std::string model;
  std::vector<Point> points; ///< In the model's order; [0] is the centre.
  Polygon polygon;
  double score = 0.0;
  int matches = 0;
  bool pickable = false;
  std::optional<long long> track; ///< The element's track id, when it tracks.
};

/// One line of a detections file: the detections in one scene (by one method).
struct SceneDetections {
  std::string image;
  std::string method; ///< Optional "method" key (empty when absent).
  /// Optional "ms" key: milliseconds the element took on this frame, per model (one element
  /// per model, pickdetect-eval --per-model).
  std::map<std::string, double> ms;
  /// Optional "frame_ms" key: milliseconds the element took on this frame with all its models
  /// loaded at once (pickdetect-eval's default).
  std::optional<double> frame_ms;
  std::vector<DetectedInstance> instances;
};

/// Reads a detections JSON Lines file (blank lines are skipped). Throws FormatError naming the
/// file, the line and the field.
std::vector<SceneDetections> load_detections(const std::string& path);
std::vector<SceneDetections> parse_detections(const std::string& text, const std::string& origin);

/// One JSON line (no trailing newline) for a detections file.
std::string detections_line(const SceneDetections& scene);

} // namespace pickdetect::eval
