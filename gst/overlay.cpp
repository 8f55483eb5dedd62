// SPDX-License-Identifier: LGPL-2.1-or-later
#include "overlay.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace gstpickdetect {

namespace {

constexpr Rgb kWhite{255, 255, 255};
constexpr Rgb kGreen{0, 255, 0};
constexpr Rgb kRed{255, 0, 0};
constexpr Rgb kOrange{255, 160, 0};
// No green or red among the points: those tell pickable from covered.
constexpr Rgb kPointColours[] = {{0, 0, 255}, {255, 0, 255}, {255, 255, 0}, {0, 255, 255}};

constexpr int kShift = 4; // Sub-pixel bits for OpenCV's drawing functions.
constexpr double kOne = 1 << kShift;

constexpr int kOutlineThickness = 2;
constexpr int kPickableOutlineThickness = 3;
constexpr int kCentreRadius = 12;
constexpr int kCentreThickness = 3;
constexpr int kPointRadius = 5;
constexpr int kPointThickness = 2;
constexpr double kFontScale = 0.7;
constexpr int kFontThickness = 2;
constexpr double kOrderFontScale = 1.3; // The pick order, "#1".
constexpr int kOrderFontThickness = 3;
constexpr double kLabelFontScale = 0.55; // The model's name.
constexpr int kLabelFontThickness = 2;

int clamp8(double v) {
  return static_cast<int>(std::lround(std::clamp(v, 0.0, 255.0)));
}

} // namespace

bool Overlay::configure(const GstVideoInfo& info) {
  layers_.clear();
  halo_ = false;
  const GstVideoFormatInfo* finfo = info.finfo;
  if (!finfo || GST_VIDEO_FORMAT_INFO_BITS(finfo) != 8 || GST_VIDEO_FORMAT_INFO_IS_TILED(finfo))
    return false;

  full_range_ = info.colorimetry.range == GST_VIDEO_COLOR_RANGE_0_255;
  if (!gst_video_color_matrix_get_Kr_Kb(info.colorimetry.matrix, &kr_, &kb_)) {
    kr_ = 0.299; // BT.601
    kb_ = 0.114;
  }

  if (GST_VIDEO_FORMAT_INFO_IS_RGB(finfo)) {
    if (GST_VIDEO_FORMAT_INFO_N_PLANES(finfo) != 1)
      return false;
    Layer layer;
    layer.kind = Kind::Packed;
    layer.channels = GST_VIDEO_FORMAT_INFO_PSTRIDE(finfo, 0);
    if (layer.channels != 3 && layer.channels != 4)
      return false;
    for (guint c = 0; c < GST_VIDEO_FORMAT_INFO_N_COMPONENTS(finfo); c++)
      layer.index[c] = GST_VIDEO_FORMAT_INFO_POFFSET(finfo, c);
    layers_.push_back(layer);
    return true;
  }

  if (GST_VIDEO_FORMAT_INFO_IS_GRAY(finfo)) {
    full_range_ = true; // Grey frames are drawn in plain grey levels...
    halo_ = true;       // ...over a black halo.
    Layer layer;
    layer.kind = Kind::Luma;
    layer.channels = GST_VIDEO_FORMAT_INFO_PSTRIDE(finfo, 0);
    if (layer.channels != 1)
      return false;
    layers_.push_back(layer);
    return true;
  }

  if (!GST_VIDEO_FORMAT_INFO_IS_YUV(finfo) || GST_VIDEO_FORMAT_INFO_N_COMPONENTS(finfo) != 3)
    return false;

  Layer luma;
  luma.kind = Kind::Luma;
  luma.plane = GST_VIDEO_FORMAT_INFO_PLANE(finfo, GST_VIDEO_COMP_Y);
  luma.component = GST_VIDEO_COMP_Y;
  luma.channels = GST_VIDEO_FORMAT_INFO_PSTRIDE(finfo, GST_VIDEO_COMP_Y);
  if (luma.channels != 1)
    return false; // Packed YUV (YUY2...) is not among the element's formats.
  layers_.push_back(luma);

  const int u_plane = GST_VIDEO_FORMAT_INFO_PLANE(finfo, GST_VIDEO_COMP_U);
  const int v_plane = GST_VIDEO_FORMAT_INFO_PLANE(finfo, GST_VIDEO_COMP_V);
  auto chroma = [&](Kind kind, int component) {
    Layer layer;
    layer.kind = kind;
    layer.plane = GST_VIDEO_FORMAT_INFO_PLANE(finfo, component);
    layer.component = component;
    layer.channels = GST_VIDEO_FORMAT_INFO_PSTRIDE(finfo, component);
    layer.sx = 1.0 / (1 << GST_VIDEO_FORMAT_INFO_W_SUB(finfo, component));
    layer.sy = 1.0 / (1 << GST_VIDEO_FORMAT_INFO_H_SUB(finfo, component));
    return layer;
  };
  if (u_plane == v_plane) {
    Layer uv = chroma(Kind::ChromaUV, GST_VIDEO_COMP_U);
    if (uv.channels != 2)
      return false;
    uv.index[0] = GST_VIDEO_FORMAT_INFO_POFFSET(finfo, GST_VIDEO_COMP_U);
    uv.index[1] = GST_VIDEO_FORMAT_INFO_POFFSET(finfo, GST_VIDEO_COMP_V);
    layers_.push_back(uv);
  } else {
    Layer u = chroma(Kind::ChromaU, GST_VIDEO_COMP_U);
    Layer v = chroma(Kind::ChromaV, GST_VIDEO_COMP_V);
    if (u.channels != 1 || v.channels != 1)
      return false;
    layers_.push_back(u);
    layers_.push_back(v);
  }
  return true;
}

cv::Scalar Overlay::colour(const Layer& layer, Rgb rgb) const {
  if (layer.kind == Kind::Packed) {
    cv::Scalar s(255, 255, 255, 255); // Padding (x) and alpha bytes are opaque.
    const int values[3] = {rgb.r, rgb.g, rgb.b};
    for (int c = 0; c < 3; c++)
      if (layer.index[c] >= 0)
        s[layer.index[c]] = values[c];
    return s;
  }
  const double r = rgb.r / 255.0, g = rgb.g / 255.0, b = rgb.b / 255.0;
  const double y = kr_ * r + (1.0 - kr_ - kb_) * g + kb_ * b; // [0, 1]
  const double pb = (b - y) / (2.0 * (1.0 - kb_));            // [-0.5, 0.5]
  const double pr = (r - y) / (2.0 * (1.0 - kr_));
  const double luma = full_range_ ? 255.0 * y : 16.0 + 219.0 * y;
  const double cb = 128.0 + (full_range_ ? 255.0 : 224.0) * pb;
  const double cr = 128.0 + (full_range_ ? 255.0 : 224.0) * pr;
  switch (layer.kind) {
  case Kind::Luma:
    return cv::Scalar(clamp8(luma));
  case Kind::ChromaU:
    return cv::Scalar(clamp8(cb));
  case Kind::ChromaV:
    return cv::Scalar(clamp8(cr));
  case Kind::ChromaUV: {
    cv::Scalar s;
    s[layer.index[0]] = clamp8(cb);
    s[layer.index[1]] = clamp8(cr);
    return s;
  }
  case Kind::Packed:
    break;
  }
  return cv::Scalar();
}

void Overlay::draw(GstVideoFrame& frame, const std::vector<pickdetect::Instance>& instances) const {
  if (instances.empty())
    return;
  for (const Layer& layer : layers_) {
    const int width = layer.kind == Kind::Packed
                          ? GST_VIDEO_FRAME_WIDTH(&frame)
                          : GST_VIDEO_FRAME_COMP_WIDTH(&frame, layer.component);
    const int height = layer.kind == Kind::Packed
                           ? GST_VIDEO_FRAME_HEIGHT(&frame)
                           : GST_VIDEO_FRAME_COMP_HEIGHT(&frame, layer.component);
    cv::Mat plane(height, width, CV_8UC(layer.channels),
                  GST_VIDEO_FRAME_PLANE_DATA(&frame, layer.plane),
                  static_cast<size_t>(GST_VIDEO_FRAME_PLANE_STRIDE(&frame, layer.plane)));

    const double s = std::min(layer.sx, layer.sy);
    auto at = [&](cv::Point2f p) {
      return cv::Point(static_cast<int>(std::lround(p.x * layer.sx * kOne)),
                       static_cast<int>(std::lround(p.y * layer.sy * kOne)));
    };
    auto radius = [&](int r) { return static_cast<int>(std::lround(r * s * kOne)); };
    auto thickness = [&](int t) { return std::max(1, static_cast<int>(std::lround(t * s))); };

    // Grey frames get a black halo under every stroke, or mid-grey marks would vanish.
    const int passes = halo_ ? 2 : 1;
    for (int pass = 0; pass < passes; pass++) {
      const bool halo = halo_ && pass == 0;
      const int extra = halo ? 2 : 0;
      auto paint = [&](Rgb rgb) { return halo ? cv::Scalar::all(0) : colour(layer, rgb); };
      const cv::Scalar green = paint(kGreen);

      for (const pickdetect::Instance& instance : instances) {
        // Pickable: green, thick, with its pick order. Covered: red. Neither (e.g. mostly out of
        // the frame): orange.
        const Rgb state = instance.pickable ? kGreen : instance.covered ? kRed : kOrange;
        std::vector<cv::Point> outline;
        outline.reserve(instance.outline.size());
        for (const cv::Point2f& p : instance.outline)
          outline.push_back(at(p));
        if (outline.size() >= 2)
          cv::polylines(
              plane, outline, true, paint(state),
              thickness(instance.pickable ? kPickableOutlineThickness : kOutlineThickness) + extra,
              cv::LINE_AA, kShift);

        for (size_t i = 1; i < instance.points.size(); i++) {
          const Rgb& c =
              kPointColours[(i - 1) % (sizeof(kPointColours) / sizeof(kPointColours[0]))];
          cv::circle(plane, at(instance.points[i]), radius(kPointRadius), paint(c),
                     thickness(kPointThickness) + extra, cv::LINE_AA, kShift);
        }

        // Text is placed in frame pixels, then carried into the plane like the points.
        auto text = [&](const std::string& str, cv::Point2d frame_at, double font_scale,
                        int font_thickness, const cv::Scalar& colour) {
          const cv::Point plane_at(static_cast<int>(std::lround(frame_at.x * layer.sx)),
                                   static_cast<int>(std::lround(frame_at.y * layer.sy)));
          cv::putText(plane, str, plane_at, cv::FONT_HERSHEY_SIMPLEX, font_scale * s, colour,
                      thickness(font_thickness) + extra, cv::LINE_AA);
        };
        auto text_size = [](const std::string& str, double font_scale, int font_thickness) {
          int baseline = 0;
          return cv::getTextSize(str, cv::FONT_HERSHEY_SIMPLEX, font_scale, font_thickness,
                                 &baseline);
        };

        const cv::Point2f centre = instance.points.empty() ? instance.center : instance.points[0];
        cv::circle(plane, at(centre), radius(kCentreRadius), green,
                   thickness(kCentreThickness) + extra, cv::LINE_AA, kShift);
        text(std::to_string(instance.matches),
             {centre.x + kCentreRadius + 4.0, centre.y - kCentreRadius - 4.0}, kFontScale,
             kFontThickness, green);

        // The model's name (and the view it matched), centred under the centre circle.
        const std::string name = instance.view.empty()
                                     ? instance.model_name
                                     : instance.model_name + " (" + instance.view + ")";
        const cv::Size label = text_size(name, kLabelFontScale, kLabelFontThickness);
        const cv::Point2d label_at(centre.x - label.width / 2.0,
                                   centre.y + kCentreRadius + 6.0 + label.height);
        if (!halo) // White letters on a dark rim, readable on light objects too.
          text(name, label_at, kLabelFontScale, kLabelFontThickness + 2,
               colour(layer, Rgb{0, 0, 0}));
        text(name, label_at, kLabelFontScale, kLabelFontThickness, paint(kWhite));

        // The pick order, large, above left of the centre circle (the matches are above right).
        if (instance.pickable && instance.pick_order > 0) {
          const std::string order = "#" + std::to_string(instance.pick_order);
          const cv::Size size = text_size(order, kOrderFontScale, kOrderFontThickness);
          text(order, {centre.x - kCentreRadius - 4.0 - size.width, centre.y - kCentreRadius - 4.0},
               kOrderFontScale, kOrderFontThickness, green);
        }
      }
    }
  }
}

} // namespace gstpickdetect
