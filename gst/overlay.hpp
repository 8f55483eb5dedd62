// SPDX-License-Identifier: LGPL-2.1-or-later
// The pickdetect element's drawing of instances (the paper's Fig. 5) in the frame's own format.
#pragma once

#include <pickdetect/detector.hpp>

#include <gst/video/video.h>

#include <opencv2/core.hpp>

#include <vector>

namespace gstpickdetect {

/// An 8-bit RGB colour.
struct Rgb {
  int r, g, b;
};

/// Draws instances straight into mapped video frames (the paper's Fig. 5, plus what a picker
/// needs): the outline in green with the pick order ("#1", "#2"...) in large green figures left
/// of the centre when the instance is pickable, in red when it is covered, in orange otherwise;
/// a large green circle on the centre with the number of matches beside it; the model's name in
/// white under it; small blue / magenta / yellow / cyan circles on the other principal points.
/// Packed RGB is drawn with the channel order of the format, grey in grey levels over a black halo,
/// YUV on the luma plane and on the subsampled chroma planes with the colours converted with the
/// stream's colour matrix (BT.601 when the caps do not say).
class Overlay {
public:
  /// Chooses, once per caps, which planes to draw on and how colours map onto them. Returns false
  /// for a format it cannot draw in (anything but 8-bit grey, packed RGB and 8-bit 4:2:0 YUV).
  bool configure(const GstVideoInfo& info);

  /// Draws into `frame`, mapped writable, of the format given to configure().
  void draw(GstVideoFrame& frame, const std::vector<pickdetect::Instance>& instances) const;

private:
  enum class Kind { Packed, Luma, ChromaU, ChromaV, ChromaUV };
  struct Layer {
    Kind kind = Kind::Luma;
    int plane = 0;
    int component = 0;               ///< A component stored in the plane (gives the plane's size).
    int channels = 1;                ///< Bytes per pixel in the plane.
    double sx = 1.0;                 ///< Plane pixels per frame pixel, horizontally.
    double sy = 1.0;                 ///< ... and vertically.
    int index[4] = {-1, -1, -1, -1}; ///< Packed: byte of R, G, B, A. ChromaUV: byte of U, V.
  };

  cv::Scalar colour(const Layer& layer, Rgb rgb) const;

  std::vector<Layer> layers_;
  double kr_ = 0.299;
  double kb_ = 0.114;
  bool full_range_ = false;
  bool halo_ = false; ///< Grey frames: strokes go over a black halo.
};

} // namespace gstpickdetect
