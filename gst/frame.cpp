// SPDX-License-Identifier: LGPL-2.1-or-later
#include "frame.hpp"

#include <gst/pickdetect/pickdetect-meta.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <optional>
#include <vector>

GST_DEBUG_CATEGORY_EXTERN(gst_pick_detect_debug);
#define GST_CAT_DEFAULT gst_pick_detect_debug

namespace gstpickdetect {
namespace {

/// Milliseconds on the steady clock since `start`.
double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

/// Where each instance lies on the work plane (empty when there is no calibration; an
/// instance whose pixels do not look onto the plane has none).
using PlaneInstances = std::vector<std::optional<pickdetect::PlaneInstance>>;

template <typename Point> GValue double_array(const std::vector<Point>& points) {
  GValue array = G_VALUE_INIT;
  g_value_init(&array, GST_TYPE_ARRAY);
  for (const Point& p : points) {
    for (const double v : {static_cast<double>(p.x), static_cast<double>(p.y)}) {
      GValue item = G_VALUE_INIT;
      g_value_init(&item, G_TYPE_DOUBLE);
      g_value_set_double(&item, v);
      gst_value_array_append_and_take_value(&array, &item);
    }
  }
  return array;
}

/// Per instance, what tracking adds (null pointers and empty lists: no tracking).
using TrackFields = std::vector<pickdetect::TrackedInstance>;

void add_track_fields(GstStructure* s, const pickdetect::TrackedInstance& t) {
  gst_structure_set(s, "track-id", G_TYPE_UINT64, static_cast<guint64>(t.track_id), "first-seen",
                    G_TYPE_UINT64, static_cast<guint64>(std::max<std::int64_t>(0, t.first_seen_ns)),
                    "frames-seen", G_TYPE_INT, t.frames_seen, "velocity-x", G_TYPE_DOUBLE,
                    t.velocity.x, "velocity-y", G_TYPE_DOUBLE, t.velocity.y, "tracked",
                    G_TYPE_BOOLEAN, static_cast<gboolean>(t.tracked), nullptr);
}

/// The "pick-instance" structure of ROI params and bus messages; `plane` adds the world fields.
GstStructure* instance_structure(const pickdetect::Instance& instance,
                                 const std::optional<pickdetect::PlaneInstance>& plane,
                                 double height_mm, const pickdetect::TrackedInstance* track) {
  GstStructure* s = gst_structure_new(
      "pick-instance", "model", G_TYPE_STRING, instance.model_name.c_str(), "center-x",
      G_TYPE_DOUBLE, static_cast<double>(instance.center.x), "center-y", G_TYPE_DOUBLE,
      static_cast<double>(instance.center.y), "angle", G_TYPE_DOUBLE, instance.angle, "scale",
      G_TYPE_DOUBLE, instance.scale, "score", G_TYPE_DOUBLE, instance.score, "matches", G_TYPE_INT,
      instance.matches, "visibility", G_TYPE_DOUBLE, instance.visibility, "covered", G_TYPE_BOOLEAN,
      static_cast<gboolean>(instance.covered), "pickable", G_TYPE_BOOLEAN,
      static_cast<gboolean>(instance.pickable), "pick-order", G_TYPE_INT, instance.pick_order,
      "grasp-x", G_TYPE_DOUBLE, static_cast<double>(instance.grasp.x), "grasp-y", G_TYPE_DOUBLE,
      static_cast<double>(instance.grasp.y), "grasp-angle", G_TYPE_DOUBLE, instance.grasp_angle,
      nullptr);
  gst_structure_set(s, "view", G_TYPE_STRING, instance.view.c_str(), nullptr);
  GValue points = double_array(instance.points);
  gst_structure_take_value(s, "points", &points);
  GValue outline = double_array(instance.outline);
  gst_structure_take_value(s, "outline", &outline);
  if (plane) {
    gst_structure_set(s, "world-x", G_TYPE_DOUBLE, plane->center.x, "world-y", G_TYPE_DOUBLE,
                      plane->center.y, "world-angle", G_TYPE_DOUBLE, plane->angle, "grasp-world-x",
                      G_TYPE_DOUBLE, plane->grasp.x, "grasp-world-y", G_TYPE_DOUBLE, plane->grasp.y,
                      "height", G_TYPE_DOUBLE, height_mm, nullptr);
    GValue world_outline = double_array(plane->outline);
    gst_structure_take_value(s, "world-outline", &world_outline);
  }
  if (track)
    add_track_fields(s, *track);
  if (track && plane)
    gst_structure_set(s, "world-velocity-x", G_TYPE_DOUBLE, plane->velocity.x, "world-velocity-y",
                      G_TYPE_DOUBLE, plane->velocity.y, nullptr);
  return s;
}

/// The height of the instance's model above the plane, in millimetres.
double model_height(const pickdetect::Detector& detector, const pickdetect::Instance& instance) {
  const std::vector<pickdetect::Model>& models = detector.models();
  return instance.model >= 0 && static_cast<size_t>(instance.model) < models.size()
             ? models[static_cast<size_t>(instance.model)].height_mm
             : 0.0;
}

PlaneInstances locate_all(GstElement* element, const pickdetect::Detection& detection,
                          const pickdetect::Detector& detector,
                          const pickdetect::Calibration* calibration) {
  PlaneInstances out;
  if (!calibration)
    return out;
  out.reserve(detection.instances.size());
  for (const pickdetect::Instance& in : detection.instances) {
    try {
      out.emplace_back(pickdetect::locate_on_plane(in, *calibration, model_height(detector, in)));
    } catch (const std::exception& e) {
      GST_WARNING_OBJECT(element, "instance of %s at (%.1f, %.1f) not placed on the plane: %s",
                         in.model_name.c_str(), in.center.x, in.center.y, e.what());
      out.emplace_back(std::nullopt);
    }
  }
  return out;
}

std::vector<GstPickDetectPoint> to_meta_points(const std::vector<cv::Point2f>& points) {
  std::vector<GstPickDetectPoint> out;
  out.reserve(points.size());
  for (const cv::Point2f& p : points)
    out.push_back(GstPickDetectPoint{p.x, p.y});
  return out;
}

void attach_metas(GstBuffer* buffer, const std::vector<pickdetect::Instance>& instances,
                  const PlaneInstances& planes, const pickdetect::Detector& detector, int width,
                  int height, const TrackFields& tracks, const pickdetect::CommonMotion& motion) {
  GstPickDetectMeta* meta = gst_buffer_add_pickdetect_meta(buffer);
  meta->has_motion = motion.found;
  meta->motion_x = motion.velocity.x;
  meta->motion_y = motion.velocity.y;
  for (size_t i = 0; i < instances.size(); i++) {
    const pickdetect::Instance& in = instances[i];
    std::vector<GstPickDetectPoint> points = to_meta_points(in.points);
    std::vector<GstPickDetectPoint> outline = to_meta_points(in.outline);
    GstPickDetectInstance out{};
    out.model_name = const_cast<gchar*>(in.model_name.c_str());
    out.view_name = const_cast<gchar*>(in.view.c_str());
    out.center_x = in.center.x;
    out.center_y = in.center.y;
    out.angle = in.angle;
    out.scale = in.scale;
    out.score = in.score;
    out.matches = in.matches;
    out.n_points = static_cast<guint>(points.size());
    out.points = points.data();
    out.n_outline = static_cast<guint>(outline.size());
    out.outline = outline.data();
    out.visibility = in.visibility;
    out.covered = in.covered;
    out.pickable = in.pickable; // The core's decision, reported as it is.
    out.pick_order = in.pick_order;
    out.grasp_x = in.grasp.x;
    out.grasp_y = in.grasp.y;
    out.grasp_angle = in.grasp_angle;
    out.height = model_height(detector, in);
    if (i < tracks.size()) {
      const pickdetect::TrackedInstance& t = tracks[i];
      out.track_id = t.track_id;
      out.first_seen = static_cast<guint64>(std::max<std::int64_t>(0, t.first_seen_ns));
      out.frames_seen = static_cast<guint>(t.frames_seen);
      out.velocity_x = t.velocity.x;
      out.velocity_y = t.velocity.y;
      out.tracked = t.tracked;
    }
    std::vector<GstPickDetectPoint> world_outline;
    if (i < planes.size() && planes[i]) {
      const pickdetect::PlaneInstance& plane = *planes[i];
      out.calibrated = TRUE;
      out.world_velocity_x = plane.velocity.x;
      out.world_velocity_y = plane.velocity.y;
      out.world_x = plane.center.x;
      out.world_y = plane.center.y;
      out.world_angle = plane.angle;
      out.grasp_world_x = plane.grasp.x;
      out.grasp_world_y = plane.grasp.y;
      for (const cv::Point2d& p : plane.outline)
        world_outline.push_back(GstPickDetectPoint{p.x, p.y});
      out.n_world_outline = static_cast<guint>(world_outline.size());
      out.world_outline = world_outline.empty() ? nullptr : world_outline.data();
    }
    gst_pickdetect_meta_add_instance(meta, &out);
  }

  // ROI ids continue after those already on the buffer, so they stay unique within it.
  gint next_id = 0;
  gpointer state = nullptr;
  while (GstMeta* m = gst_buffer_iterate_meta_filtered(
             buffer, &state, GST_VIDEO_REGION_OF_INTEREST_META_API_TYPE)) {
    next_id = std::max(next_id, reinterpret_cast<GstVideoRegionOfInterestMeta*>(m)->id + 1);
  }

  for (size_t i = 0; i < instances.size(); i++) {
    const pickdetect::Instance& in = instances[i];
    const std::vector<cv::Point2f>& shape = in.outline.empty() ? in.points : in.outline;
    double x0 = in.center.x, y0 = in.center.y, x1 = in.center.x, y1 = in.center.y;
    for (const cv::Point2f& p : shape) {
      x0 = std::min<double>(x0, p.x);
      y0 = std::min<double>(y0, p.y);
      x1 = std::max<double>(x1, p.x);
      y1 = std::max<double>(y1, p.y);
    }
    const int left = std::clamp(static_cast<int>(std::floor(x0)), 0, width);
    const int top = std::clamp(static_cast<int>(std::floor(y0)), 0, height);
    const int right = std::clamp(static_cast<int>(std::ceil(x1)), 0, width);
    const int bottom = std::clamp(static_cast<int>(std::ceil(y1)), 0, height);
    GstVideoRegionOfInterestMeta* roi = gst_buffer_add_video_region_of_interest_meta(
        buffer, in.model_name.c_str(), static_cast<guint>(left), static_cast<guint>(top),
        static_cast<guint>(right - left), static_cast<guint>(bottom - top));
    // With tracking the ROI's id is the track's (DL Streamer's convention, with an object_id
    // param), the same in every frame the object is in.
    const pickdetect::TrackedInstance* track = i < tracks.size() ? &tracks[i] : nullptr;
    roi->id = track ? static_cast<gint>(track->track_id) : next_id++;
    roi->parent_id = -1;
    gst_video_region_of_interest_meta_add_param(
        roi, instance_structure(in, i < planes.size() ? planes[i] : std::nullopt,
                                model_height(detector, in), track));
    if (track)
      gst_video_region_of_interest_meta_add_param(
          roi, gst_structure_new("object_id", "id", G_TYPE_INT, static_cast<gint>(track->track_id),
                                 nullptr));
  }
}

GstStructure* message_structure(GstBuffer* buffer, const GstSegment& segment,
                                const pickdetect::Detection& detection,
                                const PlaneInstances& planes, const pickdetect::Detector& detector,
                                double metadata_ms, double overlay_ms, const TrackFields& tracks,
                                const pickdetect::CommonMotion* motion,
                                const std::optional<pickdetect::ReuseStats>& reuse) {
  const GstClockTime ts = GST_BUFFER_PTS(buffer);
  GstClockTime running_time = GST_CLOCK_TIME_NONE, stream_time = GST_CLOCK_TIME_NONE;
  if (segment.format == GST_FORMAT_TIME) {
    running_time = gst_segment_to_running_time(&segment, GST_FORMAT_TIME, ts);
    stream_time = gst_segment_to_stream_time(&segment, GST_FORMAT_TIME, ts);
  }

  GValue list = G_VALUE_INIT;
  g_value_init(&list, GST_TYPE_LIST);
  for (size_t i = 0; i < detection.instances.size(); i++) {
    const pickdetect::Instance& in = detection.instances[i];
    GValue item = G_VALUE_INIT;
    g_value_init(&item, GST_TYPE_STRUCTURE);
    g_value_take_boxed(&item, instance_structure(in, i < planes.size() ? planes[i] : std::nullopt,
                                                 model_height(detector, in),
                                                 i < tracks.size() ? &tracks[i] : nullptr));
    gst_value_list_append_and_take_value(&list, &item);
  }
  GstStructure* s =
      gst_structure_new("pickdetect", "timestamp", G_TYPE_UINT64, ts, "stream-time", G_TYPE_UINT64,
                        stream_time, "running-time", G_TYPE_UINT64, running_time, "duration",
                        G_TYPE_UINT64, GST_BUFFER_DURATION(buffer), nullptr);
  gst_structure_take_value(s, "instances", &list);
  const pickdetect::Timings& t = detection.timings;
  gst_structure_set(s, "features-ms", G_TYPE_DOUBLE, t.features_ms, "matching-ms", G_TYPE_DOUBLE,
                    t.matching_ms, "clustering-ms", G_TYPE_DOUBLE, t.clustering_ms, "metadata-ms",
                    G_TYPE_DOUBLE, metadata_ms, "overlay-ms", G_TYPE_DOUBLE, overlay_ms, nullptr);
  if (motion)
    gst_structure_set(s, "motion", G_TYPE_BOOLEAN, static_cast<gboolean>(motion->found), "motion-x",
                      G_TYPE_DOUBLE, motion->velocity.x, "motion-y", G_TYPE_DOUBLE,
                      motion->velocity.y, nullptr);
  if (reuse)
    gst_structure_set(s, "features-extracted", G_TYPE_INT, reuse->extracted, "features-reused",
                      G_TYPE_INT, reuse->reused, "extracted-share", G_TYPE_DOUBLE,
                      reuse->extracted_share, nullptr);
  return s;
}

/// Detection and drawing on the mapped frame. Errors are posted and returned.
GstFlowReturn detect_and_draw(GstElement* element, GstVideoFrame& frame, const FrameFormat& format,
                              const FrameConfig& config, const pickdetect::Detector& detector,
                              FrameDetection& found, pickdetect::FeatureReuse* reuse) {
  pickdetect::Detection& detection = found.detection;
  double& overlay_ms = found.overlay_ms;
  try {
    cv::Mat scratch, colour_scratch;
    const cv::Mat grey = format.grey(frame, scratch);
    // The frame's colour, whenever its format has colour: it tells look-alikes apart whose
    // models have colour, and covers from highlights on any model (a highlight is near white).
    const cv::Mat colour = format.colour(frame, colour_scratch);
    if (reuse) {
      detection = reuse->detect(detector, grey, config.settings, colour);
      found.reuse = reuse->last();
    } else {
      detection = detector.detect(grey, colour, config.settings);
    }
  } catch (const std::exception& e) {
    GST_ELEMENT_ERROR(element, STREAM, FAILED, ("Detection failed: %s", e.what()), (nullptr));
    return GST_FLOW_ERROR;
  } catch (...) {
    GST_ELEMENT_ERROR(element, STREAM, FAILED, ("Detection failed"), ("unknown exception"));
    return GST_FLOW_ERROR;
  }
  GST_LOG_OBJECT(element, "%zu instances; features %.1f ms, matching %.1f ms, clustering %.1f ms",
                 detection.instances.size(), detection.timings.features_ms,
                 detection.timings.matching_ms, detection.timings.clustering_ms);

  overlay_ms = 0.0;
  if (config.draw) {
    const auto drawing = std::chrono::steady_clock::now();
    try {
      format.overlay().draw(frame, detection.instances);
      overlay_ms = ms_since(drawing);
    } catch (const std::exception& e) {
      GST_ELEMENT_WARNING(element, STREAM, FAILED, ("Drawing failed: %s", e.what()), (nullptr));
    }
  }
  return GST_FLOW_OK;
}

/// Component `c` of a mapped frame as an 8-bit picture of its own size: a view of its plane, or
/// a copy when its samples are interleaved with another component's (NV12, NV21).
cv::Mat component(const GstVideoFrame& frame, int c) {
  const int width = GST_VIDEO_FRAME_COMP_WIDTH(&frame, c);
  const int height = GST_VIDEO_FRAME_COMP_HEIGHT(&frame, c);
  const int stride = GST_VIDEO_FRAME_COMP_STRIDE(&frame, c);
  const int step = GST_VIDEO_FRAME_COMP_PSTRIDE(&frame, c);
  guint8* data = static_cast<guint8*>(GST_VIDEO_FRAME_COMP_DATA(&frame, c));
  if (step == 1)
    return cv::Mat(height, width, CV_8UC1, data, static_cast<size_t>(stride));
  cv::Mat out(height, width, CV_8UC1);
  for (int y = 0; y < height; y++) {
    const guint8* row = data + static_cast<ptrdiff_t>(y) * stride;
    guint8* to = out.ptr<guint8>(y);
    for (int x = 0; x < width; x++)
      to[x] = row[x * step];
  }
  return out;
}

/// Y, U, V to B, G, R for the caps' colorimetry: its matrix (BT.601 when it names none) and its
/// range (the offsets and scales of 8-bit video or full range).
cv::Matx34f yuv_to_bgr(const GstVideoInfo& info) {
  gdouble kr = 0.299, kb = 0.114;
  if (!gst_video_color_matrix_get_Kr_Kb(info.colorimetry.matrix, &kr, &kb)) {
    kr = 0.299;
    kb = 0.114;
  }
  gint offset[GST_VIDEO_MAX_COMPONENTS], scale[GST_VIDEO_MAX_COMPONENTS];
  gst_video_color_range_offsets(info.colorimetry.range, info.finfo, offset, scale);
  const double sy = 255.0 / scale[0], sc = 255.0 / scale[1];
  const double kg = 1.0 - kr - kb;
  // Per output channel: weights of Y, U (Cb), V (Cr); offsets folded into the last column.
  const double b_u = 2.0 * (1.0 - kb) * sc, r_v = 2.0 * (1.0 - kr) * sc;
  const double g_u = -2.0 * kb * (1.0 - kb) / kg * sc, g_v = -2.0 * kr * (1.0 - kr) / kg * sc;
  const double oy = offset[0], oc = offset[1];
  auto row = [&](double wu, double wv) { return cv::Vec4d(sy, wu, wv, -sy * oy - (wu + wv) * oc); };
  const cv::Vec4d b = row(b_u, 0.0), g = row(g_u, g_v), r = row(0.0, r_v);
  cv::Matx34f m;
  for (int k = 0; k < 4; k++) {
    m(0, k) = static_cast<float>(b[k]);
    m(1, k) = static_cast<float>(g[k]);
    m(2, k) = static_cast<float>(r[k]);
  }
  return m;
}

} // namespace

bool FrameFormat::configure(const GstVideoInfo& info, std::string& error) {
  info_ = info;
  const GstVideoFormatInfo* finfo = info.finfo;
  cvt_code_ = -1;
  weights_.release();
  if (GST_VIDEO_FORMAT_INFO_IS_GRAY(finfo) || GST_VIDEO_FORMAT_INFO_IS_YUV(finfo)) {
    grey_source_ = GreySource::Plane;
    if (GST_VIDEO_FORMAT_INFO_IS_YUV(finfo))
      yuv_to_bgr_ = yuv_to_bgr(info);
  } else {
    switch (GST_VIDEO_INFO_FORMAT(&info)) {
    case GST_VIDEO_FORMAT_RGB:
      cvt_code_ = cv::COLOR_RGB2GRAY;
      break;
    case GST_VIDEO_FORMAT_BGR:
      cvt_code_ = cv::COLOR_BGR2GRAY;
      break;
    case GST_VIDEO_FORMAT_RGBx:
    case GST_VIDEO_FORMAT_RGBA:
      cvt_code_ = cv::COLOR_RGBA2GRAY;
      break;
    case GST_VIDEO_FORMAT_BGRx:
    case GST_VIDEO_FORMAT_BGRA:
      cvt_code_ = cv::COLOR_BGRA2GRAY;
      break;
    default:
      break;
    }
    if (cvt_code_ >= 0) {
      grey_source_ = GreySource::CvtColor;
    } else {
      // Same weights as cv::cvtColor's, placed on the bytes that hold R, G and B.
      const int channels = GST_VIDEO_FORMAT_INFO_PSTRIDE(finfo, 0);
      weights_ = cv::Mat::zeros(1, channels, CV_32F);
      const float luma[3] = {0.299f, 0.587f, 0.114f};
      for (int c = 0; c < 3; c++)
        weights_.at<float>(0, GST_VIDEO_FORMAT_INFO_POFFSET(finfo, c)) = luma[c];
      grey_source_ = GreySource::Weighted;
    }
  }
  if (!overlay_.configure(info)) {
    error = std::string("cannot draw in format ") + GST_VIDEO_INFO_NAME(&info);
    return false;
  }
  return true;
}

const char* FrameFormat::grey_source_name() const {
  switch (grey_source_) {
  case GreySource::Plane:
    return "the luma plane";
  case GreySource::CvtColor:
    return "cv::cvtColor";
  case GreySource::Weighted:
    break;
  }
  return "a weighted channel sum";
}

cv::Mat FrameFormat::grey(const GstVideoFrame& frame, cv::Mat& scratch) const {
  const int width = GST_VIDEO_FRAME_WIDTH(&frame);
  const int height = GST_VIDEO_FRAME_HEIGHT(&frame);
  const size_t stride = static_cast<size_t>(GST_VIDEO_FRAME_PLANE_STRIDE(&frame, 0));
  void* data = GST_VIDEO_FRAME_PLANE_DATA(&frame, 0);
  if (grey_source_ == GreySource::Plane)
    return cv::Mat(height, width, CV_8UC1, data, stride);
  const int channels = GST_VIDEO_FRAME_COMP_PSTRIDE(&frame, 0);
  const cv::Mat packed(height, width, CV_8UC(channels), data, stride);
  if (grey_source_ == GreySource::CvtColor)
    cv::cvtColor(packed, scratch, cvt_code_);
  else
    cv::transform(packed, scratch, weights_);
  return scratch;
}

cv::Mat FrameFormat::colour(const GstVideoFrame& frame, cv::Mat& scratch) const {
  const int width = GST_VIDEO_FRAME_WIDTH(&frame);
  const int height = GST_VIDEO_FRAME_HEIGHT(&frame);
  if (grey_source_ == GreySource::Plane) {
    if (!GST_VIDEO_FORMAT_INFO_IS_YUV(info_.finfo))
      return cv::Mat();
    // Y as it is, U and V scaled up to it, then the colour matrix.
    std::vector<cv::Mat> yuv(3);
    for (int c = 0; c < 3; c++) {
      cv::Mat plane = component(frame, c);
      if (plane.size() != cv::Size(width, height))
        cv::resize(plane, plane, cv::Size(width, height), 0, 0, cv::INTER_LINEAR);
      yuv[static_cast<size_t>(c)] = plane;
    }
    cv::Mat merged;
    cv::merge(yuv, merged);
    cv::transform(merged, scratch, yuv_to_bgr_);
    return scratch;
  }
  const size_t stride = static_cast<size_t>(GST_VIDEO_FRAME_PLANE_STRIDE(&frame, 0));
  void* data = GST_VIDEO_FRAME_PLANE_DATA(&frame, 0);
  const int channels = GST_VIDEO_FRAME_COMP_PSTRIDE(&frame, 0);
  const cv::Mat packed(height, width, CV_8UC(channels), data, stride);
  if (GST_VIDEO_INFO_FORMAT(&info_) == GST_VIDEO_FORMAT_BGR)
    return packed;
  // Components 0, 1, 2 of packed RGB formats are R, G and B, at these byte offsets.
  const GstVideoFormatInfo* finfo = info_.finfo;
  auto offset = [&](int c) { return static_cast<int>(GST_VIDEO_FORMAT_INFO_POFFSET(finfo, c)); };
  const int from_to[] = {offset(2), 0, offset(1), 1, offset(0), 2};
  scratch.create(height, width, CV_8UC3);
  cv::mixChannels(&packed, 1, &scratch, 1, from_to, 3);
  return scratch;
}

GstStructure* track_structure(const pickdetect::TrackEvent& e) {
  GstStructure* s = gst_structure_new(
      "pickdetect-track", "event", G_TYPE_STRING, e.started ? "start" : "end", "track-id",
      G_TYPE_UINT64, static_cast<guint64>(e.track_id), "model", G_TYPE_STRING, e.model.c_str(),
      "first-seen", G_TYPE_UINT64, static_cast<guint64>(std::max<std::int64_t>(0, e.first_seen_ns)),
      "last-seen", G_TYPE_UINT64, static_cast<guint64>(std::max<std::int64_t>(0, e.last_seen_ns)),
      "frames-seen", G_TYPE_INT, e.frames_seen, "center-x", G_TYPE_DOUBLE,
      static_cast<double>(e.last.center.x), "center-y", G_TYPE_DOUBLE,
      static_cast<double>(e.last.center.y), "angle", G_TYPE_DOUBLE, e.last.angle, "scale",
      G_TYPE_DOUBLE, e.last.scale, nullptr);
  GValue outline = double_array(e.last.outline);
  gst_structure_take_value(s, "outline", &outline);
  if (!e.started)
    gst_structure_set(s, "reason", G_TYPE_STRING, pickdetect::track_end_name(e.reason), nullptr);
  return s;
}

GstFlowReturn detect_frame(GstElement* element, GstBuffer* buffer, const FrameFormat& format,
                           const FrameConfig& config, const pickdetect::Detector& detector,
                           FrameDetection& found, pickdetect::FeatureReuse* reuse) {
  GstVideoFrame frame;
  const auto flags = static_cast<GstMapFlags>(config.draw ? GST_MAP_READWRITE : GST_MAP_READ);
  if (!gst_video_frame_map(&frame, const_cast<GstVideoInfo*>(&format.info()), buffer, flags)) {
    GST_ELEMENT_ERROR(element, STREAM, FAILED, ("Could not map the frame"),
                      ("buffer of %" G_GSIZE_FORMAT " bytes, caps %s %dx%d",
                       gst_buffer_get_size(buffer), GST_VIDEO_INFO_NAME(&format.info()),
                       GST_VIDEO_INFO_WIDTH(&format.info()),
                       GST_VIDEO_INFO_HEIGHT(&format.info())));
    return GST_FLOW_ERROR;
  }
  const GstFlowReturn ret = detect_and_draw(element, frame, format, config, detector, found, reuse);
  gst_video_frame_unmap(&frame);
  return ret;
}

GstFlowReturn attach_frame(GstElement* element, GstBuffer* buffer, const FrameFormat& format,
                           const FrameConfig& config, const pickdetect::Detector& detector,
                           const GstSegment& segment, FrameDetection& found, GstStructure** message,
                           FrameTracking* tracking) {
  pickdetect::Detection& detection = found.detection;
  // The frame is unmapped, so the buffer is writable again for the metas.
  if (!gst_buffer_is_writable(buffer)) {
    GST_ELEMENT_ERROR(element, CORE, FAILED, (nullptr), ("buffer not writable, cannot add metas"));
    return GST_FLOW_ERROR;
  }
  try {
    const auto attaching = std::chrono::steady_clock::now();
    TrackFields tracks;
    pickdetect::CommonMotion motion;
    if (tracking && tracking->tracker) {
      // Running time; a frame without a timestamp follows the last one by a frame.
      const GstVideoInfo& info = format.info();
      const gint64 frame_ns =
          GST_VIDEO_INFO_FPS_N(&info) > 0
              ? static_cast<gint64>(gst_util_uint64_scale_int(
                    GST_SECOND, GST_VIDEO_INFO_FPS_D(&info), GST_VIDEO_INFO_FPS_N(&info)))
              : static_cast<gint64>(GST_SECOND / 30);
      GstClockTime running = GST_CLOCK_TIME_NONE;
      if (segment.format == GST_FORMAT_TIME && GST_BUFFER_PTS_IS_VALID(buffer))
        running = gst_segment_to_running_time(&segment, GST_FORMAT_TIME, GST_BUFFER_PTS(buffer));
      const gint64 now = GST_CLOCK_TIME_IS_VALID(running)
                             ? static_cast<gint64>(running)
                             : tracking->last_time.value_or(-frame_ns) + frame_ns;
      tracking->last_time = now;
      pickdetect::TrackedFrame tracked = tracking->tracker->update(
          detection.instances, now,
          cv::Size(GST_VIDEO_INFO_WIDTH(&info), GST_VIDEO_INFO_HEIGHT(&info)));
      // Those carried forward come last, within max-instances.
      const size_t limit = config.settings.max_instances > 0
                               ? std::max(detection.instances.size(),
                                          static_cast<size_t>(config.settings.max_instances))
                               : tracked.instances.size();
      if (tracked.instances.size() > limit)
        tracked.instances.resize(limit);
      detection.instances.clear();
      for (const pickdetect::TrackedInstance& t : tracked.instances)
        detection.instances.push_back(t.instance);
      tracks = std::move(tracked.instances);
      motion = tracked.motion;
      for (const pickdetect::TrackEvent& e : tracked.events)
        tracking->messages.push_back(track_structure(e));
      for (const pickdetect::CountEvent& c : tracked.counts)
        tracking->messages.push_back(gst_structure_new(
            "pickdetect-count", "track-id", G_TYPE_UINT64, static_cast<guint64>(c.track_id),
            "model", G_TYPE_STRING, c.model.c_str(), "count", G_TYPE_INT, c.count, "total",
            G_TYPE_INT, c.total, "running-time", G_TYPE_UINT64, static_cast<guint64>(now),
            nullptr));
    }
    PlaneInstances planes = locate_all(element, detection, detector, config.calibration.get());
    for (size_t i = 0; i < planes.size() && i < tracks.size(); ++i)
      if (planes[i]) {
        const pickdetect::Instance& in = detection.instances[i];
        try {
          planes[i]->velocity =
              pickdetect::velocity_on_plane(cv::Point2d(in.center), tracks[i].velocity,
                                            *config.calibration, model_height(detector, in));
        } catch (const std::exception& e) {
          GST_WARNING_OBJECT(element, "no velocity on the plane for %s at (%.1f, %.1f): %s",
                             in.model_name.c_str(), in.center.x, in.center.y, e.what());
        }
      }
    attach_metas(buffer, detection.instances, planes, detector,
                 GST_VIDEO_INFO_WIDTH(&format.info()), GST_VIDEO_INFO_HEIGHT(&format.info()),
                 tracks, motion);
    const double metadata_ms = ms_since(attaching);
    const bool tracked = tracking && tracking->tracker;
    if (config.post_messages && message)
      *message =
          message_structure(buffer, segment, detection, planes, detector, metadata_ms,
                            found.overlay_ms, tracks, tracked ? &motion : nullptr, found.reuse);
  } catch (const std::exception& e) {
    GST_ELEMENT_ERROR(element, CORE, FAILED, ("Could not attach the instances: %s", e.what()),
                      (nullptr));
    return GST_FLOW_ERROR;
  }
  return GST_FLOW_OK;
}

GstFlowReturn process_frame(GstElement* element, GstBuffer* buffer, const FrameFormat& format,
                            const FrameConfig& config, const pickdetect::Detector& detector,
                            const GstSegment& segment, GstStructure** message,
                            FrameTracking* tracking) {
  FrameDetection found;
  pickdetect::FeatureReuse* reuse = tracking && tracking->tracker ? &tracking->reuse : nullptr;
  const GstFlowReturn ret = detect_frame(element, buffer, format, config, detector, found, reuse);
  if (ret != GST_FLOW_OK)
    return ret;
  return attach_frame(element, buffer, format, config, detector, segment, found, message, tracking);
}

void post_frame_message(GstElement* element, GstStructure* structure) {
  if (structure)
    gst_element_post_message(element, gst_message_new_element(GST_OBJECT(element), structure));
}

} // namespace gstpickdetect
