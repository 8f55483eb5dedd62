// SPDX-License-Identifier: LGPL-2.1-or-later
// Raw video frames for the pickdetect element, made from OpenCV pictures: caps and GstBuffers of
// every format the element takes, with GStreamer's default strides or padded planes. Used by the
// tests, the fuzzers and the tools that drive the element.
#pragma once

#include <gst/gst.h>
#include <gst/video/video.h>

#include <opencv2/core.hpp>

#include <string>

namespace pickdetect::tools {

/// "video/x-raw,format=FORMAT,width=W,height=H,framerate=FPS/1".
std::string caps_string(const char* format, cv::Size size, int fps = 30);

/// The byte written around the planes of a padded frame, to check nothing reads or writes there.
constexpr guint8 kCanary = 0xA5;

/// How the planes of a frame lie in its buffer.
enum class Layout {
  Default, ///< GStreamer's default strides (rows rounded up to 4 bytes), no GstVideoMeta.
  Padded,  ///< Padding on all sides of every plane and strides of 64 bytes, filled with kCanary
           ///< and described by a GstVideoMeta.
};

/// A buffer for one frame of `info`, not filled in; its bytes are kCanary. With `align`, `info`
/// is aligned by it first and a GstVideoMeta describes the planes. Null when `align` does not
/// fit the format.
GstBuffer* allocate_video_buffer(GstVideoInfo& info, const GstVideoAlignment* align = nullptr);

/// A frame of `format` showing `picture`: a grey picture (CV_8UC1) in any format, as R = G = B =
/// grey with opaque alpha or as Y = grey with neutral chroma; a BGR picture (CV_8UC3) in BGR, or
/// in any other format through converted_video_buffer. PTS 0 and a duration of 1/30 s.
/// `info_out` receives the frame's layout. Null when the format is unknown or does not take
/// the picture.
GstBuffer* video_buffer(const cv::Mat& picture, const char* format, Layout layout = Layout::Default,
                        GstVideoInfo* info_out = nullptr);

/// A frame of `format` showing the BGR picture `bgr` (CV_8UC3), converted by GStreamer's video
/// converter (the default colorimetry of the format and size, as caps without one get). PTS 0
/// and a duration of 1/30 s. Null when the format is unknown or the conversion fails.
GstBuffer* converted_video_buffer(const cv::Mat& bgr, const char* format,
                                  Layout layout = Layout::Default,
                                  GstVideoInfo* info_out = nullptr);

/// A frame of `format` and `size` whose every plane holds random bytes (seeded by the size).
GstBuffer* noise_video_buffer(const char* format, cv::Size size, Layout layout = Layout::Default,
                              GstVideoInfo* info_out = nullptr);

} // namespace pickdetect::tools
