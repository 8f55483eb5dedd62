// SPDX-License-Identifier: LGPL-2.1-or-later
#include "runner.hpp"

#include "common/video-buffer.hpp"

#include <pickdetect/error.hpp>
#include <pickdetect/model.hpp>

#include <gst/app/gstappsink.h>
#include <gst/app/gstappsrc.h>
#include <gst/gst.h>
#include <gst/video/video.h>
#ifdef HAVE_PICKDETECT_META
#include <gst/pickdetect/pickdetect-meta.h>
#endif
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstring>

namespace pickdetect::eval {
namespace {

/// How long one frame may take before the element is declared stuck.
constexpr gint64 kFrameTimeoutUs = 300 * G_USEC_PER_SEC;

std::vector<double> doubles(const GValue* v) {
  std::vector<double> out;
  if (!v)
    return out;
  auto add = [&out](const GValue* item) {
    GValue d = G_VALUE_INIT;
    g_value_init(&d, G_TYPE_DOUBLE);
    if (g_value_transform(item, &d))
      out.push_back(g_value_get_double(&d));
    g_value_unset(&d);
  };
  if (GST_VALUE_HOLDS_ARRAY(v)) {
    for (guint i = 0; i < gst_value_array_get_size(v); ++i)
      add(gst_value_array_get_value(v, i));
  } else if (GST_VALUE_HOLDS_LIST(v)) {
    for (guint i = 0; i < gst_value_list_get_size(v); ++i)
      add(gst_value_list_get_value(v, i));
  }
  return out;
}

std::vector<Point> pairs_of(const std::vector<double>& xy) {
  std::vector<Point> out;
  for (size_t i = 0; i + 1 < xy.size(); i += 2)
    out.push_back({xy[i], xy[i + 1]});
  return out;
}

/// The instances in the ROI metas' "pick-instance" structures.
std::vector<DetectedInstance> from_roi_metas(GstBuffer* buffer) {
  std::vector<DetectedInstance> out;
  gpointer state = nullptr;
  while (GstMeta* meta = gst_buffer_iterate_meta_filtered(
             buffer, &state, GST_VIDEO_REGION_OF_INTEREST_META_API_TYPE)) {
    auto* roi = reinterpret_cast<GstVideoRegionOfInterestMeta*>(meta);
    GstStructure* s = gst_video_region_of_interest_meta_get_param(roi, "pick-instance");
    if (!s)
      continue;
    DetectedInstance d;
    if (const gchar* model = gst_structure_get_string(s, "model"))
      d.model = model;
    d.points = pairs_of(doubles(gst_structure_get_value(s, "points")));
    d.polygon = pairs_of(doubles(gst_structure_get_value(s, "outline")));
    if (d.points.empty()) {
      double cx = 0, cy = 0;
      if (gst_structure_get_double(s, "center-x", &cx) &&
          gst_structure_get_double(s, "center-y", &cy))
        d.points.push_back({cx, cy});
    }
    gst_structure_get_double(s, "score", &d.score);
    gint matches = 0;
    if (gst_structure_get_int(s, "matches", &matches))
      d.matches = matches;
    gboolean pickable = FALSE;
    if (gst_structure_get_boolean(s, "pickable", &pickable))
      d.pickable = pickable;
    out.push_back(std::move(d));
  }
  return out;
}

#ifdef HAVE_PICKDETECT_META
std::vector<DetectedInstance> from_pickdetect_meta(const GstPickDetectMeta* meta) {
  std::vector<DetectedInstance> out;
  const guint n = gst_pickdetect_meta_get_n_instances(meta);
  for (guint i = 0; i < n; ++i) {
    const GstPickDetectInstance* in = gst_pickdetect_meta_get_instance(meta, i);
    DetectedInstance d;
    d.model = in->model_name ? in->model_name : "";
    for (guint k = 0; k < in->n_points; ++k)
      d.points.push_back({in->points[k].x, in->points[k].y});
    if (d.points.empty())
      d.points.push_back({in->center_x, in->center_y});
    for (guint k = 0; k < in->n_outline; ++k)
      d.polygon.push_back({in->outline[k].x, in->outline[k].y});
    d.score = in->score;
    d.matches = in->matches;
    d.pickable = in->pickable;
    if (in->track_id > 0)
      d.track = static_cast<long long>(in->track_id);
    out.push_back(std::move(d));
  }
  return out;
}
#endif

} // namespace

std::vector<Frame> load_frames(const Dataset& dataset, bool bgr) {
  std::vector<Frame> frames;
  for (size_t i = 0; i < dataset.scenes.size(); ++i) {
    const Scene& scene = dataset.scenes[i];
    const std::string field = "scenes[" + std::to_string(i) + "].image";
    const std::string path = dataset.path_of(scene.image);
    if (!g_file_test(path.c_str(), G_FILE_TEST_IS_REGULAR))
      throw FormatError(dataset.file + ": " + field + ": '" + path + "' does not exist");
    cv::Mat picture = cv::imread(path, bgr ? cv::IMREAD_COLOR : cv::IMREAD_GRAYSCALE);
    if (picture.empty())
      throw FormatError(dataset.file + ": " + field + ": '" + path +
                        "' cannot be decoded as a picture");
    if (picture.cols != scene.width || picture.rows != scene.height)
      throw FormatError(dataset.file + ": scenes[" + std::to_string(i) +
                        "].width/height: " + std::to_string(scene.width) + "x" +
                        std::to_string(scene.height) + " but '" + path + "' is " +
                        std::to_string(picture.cols) + "x" + std::to_string(picture.rows));
    Frame f;
    f.image = scene.image;
    f.width = picture.cols;
    f.height = picture.rows;
    f.bgr = bgr;
    const size_t row = static_cast<size_t>(picture.cols) * picture.elemSize();
    f.pixels.resize(row * static_cast<size_t>(picture.rows));
    for (int y = 0; y < picture.rows; ++y)
      std::memcpy(f.pixels.data() + row * static_cast<size_t>(y), picture.ptr(y), row);
    frames.push_back(std::move(f));
  }
  return frames;
}

std::string write_model_file(const Dataset& dataset, const ModelInfo& model,
                             const std::string& folder) {
  const std::string picture = dataset.path_of(model.image);
  if (!g_file_test(picture.c_str(), G_FILE_TEST_IS_REGULAR))
    throw FormatError(dataset.file + ": models." + model.name + ".image: '" + picture +
                      "' does not exist");
  gchar* absolute = g_canonicalize_filename(picture.c_str(), nullptr);
  const std::string image(absolute);
  g_free(absolute);
  gchar* file = g_build_filename(folder.c_str(), (model.name + ".yml").c_str(), nullptr);
  const std::string path(file);
  g_free(file);
  pickdetect::Model written;
  written.name = model.name;
  written.image_path = image;
  for (const Point& p : model.principal_points)
    written.principal_points.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y));
  for (const Point& p : model.polygon)
    written.outline.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y));
  try {
    pickdetect::save_model(written, path, false);
  } catch (const pickdetect::Error& e) {
    throw RunError(e.what());
  }
  return path;
}

struct ElementRunner::Impl {
  GstElement* pipeline = nullptr;
  GstElement* src = nullptr;
  GstElement* sink = nullptr;
  GstCaps* caps = nullptr;
  guint64 frames = 0;
  double fps = 0.0; ///< A video sequence's; 0: one frame a second, no frame rate in the caps.
};

ElementRunner::ElementRunner(const std::vector<std::pair<std::string, std::string>>& properties)
    : impl_(new Impl) {
  GError* error = nullptr;
  impl_->pipeline = gst_parse_launch(
      "appsrc name=src format=time ! pickdetect name=detect ! appsink name=sink sync=false",
      &error);
  if (!impl_->pipeline || error) {
    const std::string message = error ? error->message : "unknown error";
    g_clear_error(&error);
    if (impl_->pipeline)
      gst_object_unref(impl_->pipeline);
    delete impl_;
    throw RunError("cannot build 'appsrc ! pickdetect ! appsink': " + message +
                   " (is the pickdetect plugin on GST_PLUGIN_PATH?)");
  }
  GstBin* bin = GST_BIN(impl_->pipeline);
  impl_->src = gst_bin_get_by_name(bin, "src");
  impl_->sink = gst_bin_get_by_name(bin, "sink");
  GstElement* detect = gst_bin_get_by_name(bin, "detect");
  std::string problem;
  for (const auto& [name, value] : properties) {
    GParamSpec* spec = g_object_class_find_property(G_OBJECT_GET_CLASS(detect), name.c_str());
    if (!spec) {
      problem = "the pickdetect element has no property '" + name + "'";
      break;
    }
    GValue v = G_VALUE_INIT;
    g_value_init(&v, spec->value_type);
    const bool parsed = gst_value_deserialize(&v, value.c_str());
    if (!parsed || g_param_value_validate(spec, &v)) {
      g_value_unset(&v);
      problem = "the pickdetect element's property '" + name + "' cannot take '" + value + "'" +
                (parsed ? " (out of range)" : "");
      break;
    }
    g_object_set_property(G_OBJECT(detect), name.c_str(), &v);
    g_value_unset(&v);
  }
  gst_object_unref(detect);
  if (problem.empty() &&
      gst_element_set_state(impl_->pipeline, GST_STATE_PLAYING) == GST_STATE_CHANGE_FAILURE) {
    problem = "the pipeline refused to start";
    GstBus* bus = gst_element_get_bus(impl_->pipeline);
    if (GstMessage* m = gst_bus_pop_filtered(bus, GST_MESSAGE_ERROR)) {
      GError* err = nullptr;
      gchar* debug = nullptr;
      gst_message_parse_error(m, &err, &debug);
      problem += std::string(": ") + (err ? err->message : "") +
                 (debug ? std::string(" (") + debug + ")" : std::string());
      g_clear_error(&err);
      g_free(debug);
      gst_message_unref(m);
    }
    gst_object_unref(bus);
  }
  if (!problem.empty()) {
    gst_element_set_state(impl_->pipeline, GST_STATE_NULL);
    gst_object_unref(impl_->src);
    gst_object_unref(impl_->sink);
    gst_object_unref(impl_->pipeline);
    delete impl_;
    throw RunError(problem);
  }
}

ElementRunner::~ElementRunner() {
  gst_app_src_end_of_stream(GST_APP_SRC(impl_->src));
  gst_element_set_state(impl_->pipeline, GST_STATE_NULL);
  if (impl_->caps)
    gst_caps_unref(impl_->caps);
  gst_object_unref(impl_->src);
  gst_object_unref(impl_->sink);
  gst_object_unref(impl_->pipeline);
  delete impl_;
}

void ElementRunner::fail_from_bus(const std::string& context) {
  check_bus(context);
  throw RunError(context + ": the element gave no frame back");
}

void ElementRunner::check_bus(const std::string& context) {
  GstBus* bus = gst_element_get_bus(impl_->pipeline);
  GstMessage* m = gst_bus_pop_filtered(bus, GST_MESSAGE_ERROR);
  gst_object_unref(bus);
  if (!m)
    return;
  GError* err = nullptr;
  gchar* debug = nullptr;
  gst_message_parse_error(m, &err, &debug);
  const std::string message = std::string(err ? err->message : "error") +
                              (debug ? std::string(" (") + debug + ")" : std::string());
  g_clear_error(&err);
  g_free(debug);
  gst_message_unref(m);
  throw RunError(context + ": " + message);
}

void ElementRunner::set_fps(double fps) {
  impl_->fps = fps;
}

FrameResult ElementRunner::process(const Frame& frame) {
  const char* format = frame.bgr ? "BGR" : "GRAY8";
  const cv::Size size(frame.width, frame.height);
  if (!impl_->caps || [&] {
        const GstStructure* s = gst_caps_get_structure(impl_->caps, 0);
        int w = 0, h = 0;
        gst_structure_get_int(s, "width", &w);
        gst_structure_get_int(s, "height", &h);
        return w != frame.width || h != frame.height ||
               g_strcmp0(gst_structure_get_string(s, "format"), format) != 0;
      }()) {
    if (impl_->caps)
      gst_caps_unref(impl_->caps);
    impl_->caps = gst_caps_new_simple(
        "video/x-raw", "format", G_TYPE_STRING, format, "width", G_TYPE_INT, frame.width, "height",
        G_TYPE_INT, frame.height, "framerate", GST_TYPE_FRACTION,
        impl_->fps > 0 ? static_cast<int>(std::lround(impl_->fps * 1000)) : 0,
        impl_->fps > 0 ? 1000 : 1, nullptr);
  }
  const cv::Mat picture(size, frame.bgr ? CV_8UC3 : CV_8UC1,
                        const_cast<unsigned char*>(frame.pixels.data()));
  GstBuffer* buffer = pickdetect::tools::video_buffer(picture, format);
  const GstClockTime frame_time =
      impl_->fps > 0 ? static_cast<GstClockTime>(GST_SECOND / impl_->fps) : GST_SECOND;
  GST_BUFFER_PTS(buffer) = impl_->frames * frame_time;
  GST_BUFFER_DURATION(buffer) = frame_time;
  ++impl_->frames;
  GstSample* in = gst_sample_new(buffer, impl_->caps, nullptr, nullptr);
  gst_buffer_unref(buffer);

  const std::string context = "scene '" + frame.image + "'";
  const gint64 start = g_get_monotonic_time();
  const GstFlowReturn pushed = gst_app_src_push_sample(GST_APP_SRC(impl_->src), in);
  gst_sample_unref(in);
  if (pushed != GST_FLOW_OK)
    fail_from_bus(context);
  GstSample* out = nullptr;
  while (!out) {
    out = gst_app_sink_try_pull_sample(GST_APP_SINK(impl_->sink), 50 * GST_MSECOND);
    const gint64 now = g_get_monotonic_time();
    if (!out) {
      check_bus(context);
      if (gst_app_sink_is_eos(GST_APP_SINK(impl_->sink)) || now - start > kFrameTimeoutUs)
        fail_from_bus(context);
    }
  }
  FrameResult result;
  result.ms = static_cast<double>(g_get_monotonic_time() - start) / 1000.0;
  GstBuffer* got = gst_sample_get_buffer(out);
  bool found = false;
#ifdef HAVE_PICKDETECT_META
  if (const GstPickDetectMeta* meta = gst_buffer_get_pickdetect_meta(got)) {
    result.instances = from_pickdetect_meta(meta);
    found = true;
  }
#endif
  if (!found)
    result.instances = from_roi_metas(got);
  gst_sample_unref(out);
  return result;
}

} // namespace pickdetect::eval
