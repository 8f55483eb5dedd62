// SPDX-License-Identifier: LGPL-2.1-or-later
// The pickdetect element's work on one frame: the grey view detection reads, detection, the
// overlay, the metas and the bus message's structure. Holds no element state, so frames can be
// worked on in any thread.
#pragma once

#include "overlay.hpp"

#include <pickdetect/calibration.hpp>
#include <pickdetect/detector.hpp>
#include <pickdetect/feature_reuse.hpp>
#include <pickdetect/tracker.hpp>

#include <gst/gst.h>
#include <gst/video/video.h>

#include <opencv2/core.hpp>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace gstpickdetect {

/// Everything set through the element's properties that a frame is processed with.
struct FrameConfig {
  pickdetect::Settings settings;
  bool draw = false;
  bool post_messages = true;
  /// From the `calibration` property: instances are also placed on the work plane; null: not.
  std::shared_ptr<const pickdetect::Calibration> calibration;
  bool tracking = true;                            ///< The `tracking` property.
  double track_timeout_ms = 500.0;                 ///< The `track-timeout` property.
  std::optional<pickdetect::CountLine> count_line; ///< The `count-line` property, parsed.
  int full_detection_interval = 15;                ///< The `full-detection-interval` property.
};

/// The stream's tracker, for attach_frame (streaming thread only).
struct FrameTracking {
  pickdetect::Tracker* tracker = nullptr; ///< Null: frame by frame, no track fields.
  /// Tracker time of the last frame (running time, ns); frames without a timestamp follow it
  /// by one frame duration.
  std::optional<gint64> last_time;
  /// What the last frames found, reused by the next one's detection (threads = 1 only).
  pickdetect::FeatureReuse reuse;
  /// The frame's "pickdetect-track" and "pickdetect-count" structures, for the caller to post
  /// after the frame's own message.
  std::vector<GstStructure*> messages;
};

/// The "pickdetect-track" structure of a track starting or ending.
GstStructure* track_structure(const pickdetect::TrackEvent& event);

/// What detect_frame found, for attach_frame.
struct FrameDetection {
  pickdetect::Detection detection;
  double overlay_ms = 0.0;
  /// What the detection reused from the frames before (absent: detected whole, no reuse).
  std::optional<pickdetect::ReuseStats> reuse;
};

/// What the negotiated caps decide about working on a frame; set once per caps.
class FrameFormat {
public:
  /// Chooses how to read grey from `info`'s format and how to draw in it. False, with `error`
  /// set, for a format the element cannot draw in.
  bool configure(const GstVideoInfo& info, std::string& error);

  const GstVideoInfo& info() const { return info_; }
  /// How grey is read, for the debug log.
  const char* grey_source_name() const;

  /// A grey view of the mapped frame: the luma plane itself, or a conversion into `scratch`.
  cv::Mat grey(const GstVideoFrame& frame, cv::Mat& scratch) const;

  /// The mapped frame in colour, BGR: a view of a BGR frame itself, the channels of another
  /// packed RGB format reordered into `scratch`, or a YUV frame's planes converted into
  /// `scratch` (its chroma scaled up to the frame's size, the caps' colour matrix and range).
  /// Empty for GRAY8.
  cv::Mat colour(const GstVideoFrame& frame, cv::Mat& scratch) const;

  const Overlay& overlay() const { return overlay_; }

private:
  enum class GreySource {
    Plane,    ///< GRAY8 and YUV: the luma plane itself.
    CvtColor, ///< RGB, BGR, RGBx / RGBA, BGRx / BGRA: cv::cvtColor.
    Weighted, ///< xRGB, xBGR, ARGB, ABGR: channel-weighted sum (cv::transform).
  };

  GstVideoInfo info_{};
  GreySource grey_source_ = GreySource::Plane;
  int cvt_code_ = -1;
  cv::Mat weights_; ///< 1 x channels, CV_32F, for GreySource::Weighted.
  /// YUV formats: Y, U, V (8-bit, as the caps' colorimetry codes them) to B, G, R.
  cv::Matx34f yuv_to_bgr_;
  Overlay overlay_;
};

/// What a frame is processed with, taken as a whole under the element's lock: the same
/// settings, models and format from its detection to its metas, whatever is set meanwhile.
struct FrameInputs {
  std::shared_ptr<const pickdetect::Detector> detector;
  std::shared_ptr<const FrameFormat> format;
  FrameConfig config;
};

/// Posts the "pickdetect" element message of a frame on `element` (nothing when null); takes
/// `structure`.
void post_frame_message(GstElement* element, GstStructure* structure);

/// Detects on `buffer` (writable, of `format`), draws when `config.draw`, and attaches the
/// metas (see the element's documentation). When `config.post_messages`, `*message` receives the
/// "pickdetect" element message's structure (the caller posts it), timestamps taken from
/// `segment`. Errors are posted on `element` and returned as GST_FLOW_ERROR. Never throws.
/// With `tracking` and its tracker, the instances are tracked before they are attached.
GstFlowReturn process_frame(GstElement* element, GstBuffer* buffer, const FrameFormat& format,
                            const FrameConfig& config, const pickdetect::Detector& detector,
                            const GstSegment& segment, GstStructure** message,
                            FrameTracking* tracking = nullptr);

/// process_frame in two halves: detection and drawing (any thread), then tracking and the metas
/// (in frame order, where the tracker lives).
/// With `reuse`, the detection reuses what the frames before found (streaming thread only).
GstFlowReturn detect_frame(GstElement* element, GstBuffer* buffer, const FrameFormat& format,
                           const FrameConfig& config, const pickdetect::Detector& detector,
                           FrameDetection& found, pickdetect::FeatureReuse* reuse = nullptr);
GstFlowReturn attach_frame(GstElement* element, GstBuffer* buffer, const FrameFormat& format,
                           const FrameConfig& config, const pickdetect::Detector& detector,
                           const GstSegment& segment, FrameDetection& found, GstStructure** message,
                           FrameTracking* tracking);

} // namespace gstpickdetect
