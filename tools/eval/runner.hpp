// SPDX-License-Identifier: LGPL-2.1-or-later
// Runs scenes through the real `pickdetect` GStreamer element and reads its metadata back.
#pragma once

#include "dataset.hpp"

#include <functional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace pickdetect::eval {

/// The element could not be built, configured or run.
class RunError : public std::runtime_error {
public:
  explicit RunError(const std::string& what) : std::runtime_error(what) {}
};

/// One frame as pushed into appsrc: 8-bit grey or BGR, packed rows.
struct Frame {
  std::string image; ///< The scene's image as written in the dataset.
  int width = 0;
  int height = 0;
  bool bgr = false;
  std::vector<unsigned char> pixels;
};

/// Reads every scene picture of the dataset (GRAY8 or BGR). Throws FormatError naming the
/// dataset file and the scene's field when a picture is missing, unreadable, or not of the
/// size the dataset gives.
std::vector<Frame> load_frames(const Dataset& dataset, bool bgr);

/// Writes a model file for the element (the dataset's picture, principal points and polygon as
/// outline, named as in the dataset) into `folder`; returns its path.
std::string write_model_file(const Dataset& dataset, const ModelInfo& model,
                             const std::string& folder);

struct FrameResult {
  std::vector<DetectedInstance> instances;
  double ms = 0.0; ///< Wall time from pushing the frame to getting it back.
};

/// appsrc ! pickdetect ! appsink. Properties are (name, value-as-text) pairs, parsed as
/// gst-launch would; an unknown property or a value that does not parse or fit is refused.
class ElementRunner {
public:
  explicit ElementRunner(const std::vector<std::pair<std::string, std::string>>& properties);
  ~ElementRunner();
  ElementRunner(const ElementRunner&) = delete;
  ElementRunner& operator=(const ElementRunner&) = delete;

  /// The frames are those of one video at `fps` (timestamps and caps follow it), before the
  /// first frame.
  void set_fps(double fps);
  /// Pushes one frame and waits for it to come out of the element.
  FrameResult process(const Frame& frame);

private:
  [[noreturn]] void fail_from_bus(const std::string& context);
  void check_bus(const std::string& context);

  struct Impl;
  Impl* impl_;
};

} // namespace pickdetect::eval
