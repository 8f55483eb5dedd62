// SPDX-License-Identifier: LGPL-2.1-or-later
// Tests of the pickdetect element with GstHarness, on synthetic frames: copies of box.png pasted
// at known poses onto a noisy background.
// OpenCV comes before gstcheck.h, whose `fail` macro would clash with OpenCV's identifiers.
#include <pickdetect/detector.hpp>
#include <pickdetect/model.hpp>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <glib/gstdio.h>
#include <gst/check/gstcheck.h>
#include <gst/check/gstharness.h>
#include <gst/pickdetect/pickdetect-meta.h>
#include <gst/video/video.h>

#include "../support/colour_print.hpp"
#include "../support/harness.hpp"
#include "../support/soft_disc.hpp"
#include "common/scene.hpp"
#include "common/video-buffer.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

namespace {

using pickdetect::test_harness::kBoxPath;
using pickdetect::test_harness::roi_metas;
using pickdetect::test_harness::roi_param;

const char* const kFormats[] = {"GRAY8", "RGB",  "BGR",  "RGBx", "BGRx", "xRGB", "xBGR", "RGBA",
                                "BGRA",  "ARGB", "ABGR", "I420", "YV12", "NV12", "NV21"};

struct Pose {
  double x, y, angle, scale;
};

// Two instances that do not touch, turned and scaled differently.
const Pose kPoses[] = {{180.0, 150.0, 30.0, 0.6}, {450.0, 320.0, 250.0, 0.7}};

struct Truth {
  cv::Point2d centre;
  double angle;
  double scale;
};

const pickdetect::Model& box_model() {
  static const pickdetect::Model model = pickdetect::load_model(kBoxPath);
  return model;
}

/// The box's pose in the scene helpers' terms (about the picture's centre, the box's centre).
pickdetect::test_scene::Pose scene_pose(const Pose& pose) {
  return {cv::Point2f(static_cast<float>(pose.x), static_cast<float>(pose.y)), pose.angle,
          pose.scale};
}

/// A grey scene of the given size with the box at kPoses (those that fit), and the truth.
cv::Mat make_scene(cv::Size size, std::vector<Truth>* truth, bool with_boxes = true) {
  cv::Mat scene = pickdetect::test_scene::smooth_noise_background(size);
  if (!with_boxes)
    return scene;
  for (const Pose& pose : kPoses) {
    pickdetect::test_scene::paste(scene, box_model().image, {scene_pose(pose)});
    if (truth)
      truth->push_back(Truth{cv::Point2d(pose.x, pose.y), pose.angle, pose.scale});
  }
  return scene;
}

/// The scene in `format` (a grey picture in any format, a BGR one in BGR or converted to YUV; see
/// pickdetect::tools::video_buffer), GStreamer's strides.
GstBuffer* scene_buffer(const cv::Mat& picture, const char* format) {
  GstBuffer* buffer = pickdetect::tools::video_buffer(picture, format);
  fail_unless(buffer != nullptr, "no %s buffer", format);
  return buffer;
}

std::string caps_string(const char* format, cv::Size size) {
  return pickdetect::tools::caps_string(format, size);
}

/// A harness around a lone pickdetect (h->element is the element) with the box model.
GstHarness* pickdetect_harness(bool draw = false) {
  return pickdetect::test_harness::pickdetect_harness("model", kBoxPath.c_str(), "draw",
                                                      static_cast<gboolean>(draw));
}

/// The instances of the meta, left to right.
std::vector<const GstPickDetectInstance*> sorted_instances(const GstPickDetectMeta* meta) {
  std::vector<const GstPickDetectInstance*> out;
  for (guint i = 0; i < gst_pickdetect_meta_get_n_instances(meta); i++)
    out.push_back(gst_pickdetect_meta_get_instance(meta, i));
  std::sort(out.begin(), out.end(), [](auto* a, auto* b) { return a->center_x < b->center_x; });
  return out;
}

double angle_difference(double a, double b) {
  const double d = std::fmod(std::fabs(a - b), 360.0);
  return std::min(d, 360.0 - d);
}

void check_against_truth(const GstPickDetectMeta* meta, const std::vector<Truth>& truth,
                         const char* format) {
  const auto instances = sorted_instances(meta);
  fail_unless_equals_int(instances.size(), truth.size());
  for (size_t i = 0; i < truth.size(); i++) {
    const GstPickDetectInstance* in = instances[i];
    const double error =
        std::hypot(in->center_x - truth[i].centre.x, in->center_y - truth[i].centre.y);
    fail_unless(error < 1.5, "%s: instance %zu at (%.2f, %.2f), truth (%.2f, %.2f)", format, i,
                in->center_x, in->center_y, truth[i].centre.x, truth[i].centre.y);
    fail_unless(angle_difference(in->angle, truth[i].angle) < 3.0, "%s: angle %.2f, truth %.2f",
                format, in->angle, truth[i].angle);
    fail_unless(std::fabs(in->scale / truth[i].scale - 1.0) < 0.05, "%s: scale %.3f, truth %.3f",
                format, in->scale, truth[i].scale);
  }
}

/// The output buffer in RGB, for looking at colours whatever the format.
cv::Mat to_rgb(GstBuffer* buffer, const char* format, cv::Size size) {
  GstVideoInfo in_info, out_info;
  gst_video_info_set_format(&in_info, gst_video_format_from_string(format), size.width,
                            size.height);
  gst_video_info_set_format(&out_info, GST_VIDEO_FORMAT_RGB, size.width, size.height);
  GstBuffer* out = gst_buffer_new_allocate(nullptr, GST_VIDEO_INFO_SIZE(&out_info), nullptr);
  GstVideoFrame in_frame, out_frame;
  fail_unless(gst_video_frame_map(&in_frame, &in_info, buffer, GST_MAP_READ));
  fail_unless(gst_video_frame_map(&out_frame, &out_info, out, GST_MAP_WRITE));
  GstVideoConverter* converter = gst_video_converter_new(&in_info, &out_info, nullptr);
  gst_video_converter_frame(converter, &in_frame, &out_frame);
  gst_video_converter_free(converter);
  cv::Mat rgb(size, CV_8UC3);
  for (int y = 0; y < size.height; y++)
    std::memcpy(rgb.ptr(y),
                static_cast<guint8*>(GST_VIDEO_FRAME_PLANE_DATA(&out_frame, 0)) +
                    y * GST_VIDEO_FRAME_PLANE_STRIDE(&out_frame, 0),
                size.width * 3);
  gst_video_frame_unmap(&in_frame);
  gst_video_frame_unmap(&out_frame);
  gst_buffer_unref(out);
  return rgb;
}

int count_pixels(const cv::Mat& rgb, cv::Vec3b lo, cv::Vec3b hi) {
  cv::Mat mask;
  cv::inRange(rgb, lo, hi, mask);
  return cv::countNonZero(mask);
}

} // namespace

// Every format finds the same instances, at the truth, and leaves the pixels alone.
GST_START_TEST(test_formats_same_instances) {
  const cv::Size size(638, 478); // Odd strides: rows are padded in GRAY8, RGB and YUV.
  std::vector<Truth> truth;
  const cv::Mat scene = make_scene(size, &truth);
  std::vector<GstPickDetectInstance> reference;

  for (const char* format : kFormats) {
    GstHarness* h = pickdetect_harness(false);
    gst_harness_set_src_caps_str(h, caps_string(format, size).c_str());
    GstBuffer* in = scene_buffer(scene, format);
    GstBuffer* original = gst_buffer_copy_deep(in);
    GstBuffer* out = gst_harness_push_and_pull(h, in);
    fail_unless(out != nullptr, "%s: no output", format);

    // draw=false: bit-identical pixels.
    GstMapInfo map;
    fail_unless(gst_buffer_map(out, &map, GST_MAP_READ));
    fail_unless_equals_int(map.size, gst_buffer_get_size(original));
    fail_unless(gst_buffer_memcmp(original, 0, map.data, map.size) == 0, "%s: pixels changed",
                format);
    gst_buffer_unmap(out, &map);

    const GstPickDetectMeta* meta = gst_buffer_get_pickdetect_meta(out);
    fail_unless(meta != nullptr, "%s: no meta", format);
    check_against_truth(meta, truth, format);

    const auto instances = sorted_instances(meta);
    if (reference.empty()) {
      for (const GstPickDetectInstance* in_ : instances)
        reference.push_back(*in_); // Shallow: only the numbers are compared.
    } else {
      for (size_t i = 0; i < reference.size(); i++) {
        const double d = std::hypot(instances[i]->center_x - reference[i].center_x,
                                    instances[i]->center_y - reference[i].center_y);
        fail_unless(d < 0.5, "%s: instance %zu is %.3f px from GRAY8's", format, i, d);
      }
    }
    gst_buffer_unref(original);
    gst_buffer_unref(out);
    gst_harness_teardown(h);
  }
}
GST_END_TEST;

// draw=true draws the outline, the centre and the points in the right colours in every format.
GST_START_TEST(test_draw_colours) {
  const cv::Size size(640, 480);
  const cv::Mat scene = make_scene(size, nullptr);

  for (const char* format : kFormats) {
    GstHarness* h = pickdetect_harness(true);
    gst_harness_set_src_caps_str(h, caps_string(format, size).c_str());
    GstBuffer* in = scene_buffer(scene, format);
    GstBuffer* original = gst_buffer_copy_deep(in);
    GstBuffer* out = gst_harness_push_and_pull(h, in);
    fail_unless(out != nullptr);

    GstMapInfo map;
    fail_unless(gst_buffer_map(out, &map, GST_MAP_READ));
    fail_unless(gst_buffer_memcmp(original, 0, map.data, map.size) != 0, "%s: nothing drawn",
                format);
    gst_buffer_unmap(out, &map);

    const cv::Mat before = to_rgb(original, format, size);
    const cv::Mat after = to_rgb(out, format, size);
    const bool grey = std::strcmp(format, "GRAY8") == 0;
    // The scene is grey, so any coloured pixel comes from the overlay.
    const int green_before = count_pixels(before, {0, 170, 0}, {90, 255, 90});
    const int green = count_pixels(after, {0, 170, 0}, {90, 255, 90});
    const int blue = count_pixels(after, {0, 0, 170}, {90, 90, 255});
    const int red = count_pixels(after, {170, 0, 0}, {255, 90, 90});
    // The model's name is in thin white letters (anti-aliased).
    const int white = count_pixels(after, {230, 230, 230}, {255, 255, 255});
    const int white_before = count_pixels(before, {230, 230, 230}, {255, 255, 255});
    fail_unless_equals_int(green_before, 0);
    fail_unless(white > white_before + 20, "%s: model name missing (%d white pixels, %d before)",
                format, white, white_before);
    if (grey) {
      // Grey levels: the green centre circle is drawn at green's luma (150).
      const int luma_green = count_pixels(after, {145, 145, 145}, {155, 155, 155});
      const int luma_green_before = count_pixels(before, {145, 145, 145}, {155, 155, 155});
      fail_unless(luma_green > luma_green_before + 50, "GRAY8: centre circle missing");
    } else {
      // Both boxes are pickable: two green outlines (each over 600 px long), no red.
      fail_unless(green > 1500, "%s: only %d green pixels", format, green);
      fail_unless(blue > 10, "%s: only %d blue pixels", format, blue);
      fail_unless(red < 5, "%s: %d red pixels, but nothing is covered", format, red);
    }
    gst_buffer_unref(original);
    gst_buffer_unref(out);
    gst_harness_teardown(h);
  }
}
GST_END_TEST;

static std::vector<double> double_array(const GstStructure* s, const char* field) {
  const GValue* v = gst_structure_get_value(s, field);
  fail_unless(v != nullptr && GST_VALUE_HOLDS_ARRAY(v), "field %s is not an array", field);
  std::vector<double> out;
  for (guint i = 0; i < gst_value_array_get_size(v); i++) {
    const GValue* item = gst_value_array_get_value(v, i);
    fail_unless(G_VALUE_HOLDS_DOUBLE(item));
    out.push_back(g_value_get_double(item));
  }
  return out;
}

static void check_structure_matches(const GstStructure* s, const GstPickDetectInstance* in) {
  fail_unless(gst_structure_has_name(s, "pick-instance"));
  double d;
  gint i;
  gboolean b;
  fail_unless_equals_string(gst_structure_get_string(s, "model"), in->model_name);
  fail_unless_equals_string(gst_structure_get_string(s, "view"), in->view_name);
  fail_unless(gst_structure_get_double(s, "center-x", &d) && d == in->center_x);
  fail_unless(gst_structure_get_double(s, "center-y", &d) && d == in->center_y);
  fail_unless(gst_structure_get_double(s, "angle", &d) && d == in->angle);
  fail_unless(gst_structure_get_double(s, "scale", &d) && d == in->scale);
  fail_unless(gst_structure_get_double(s, "score", &d) && d == in->score);
  fail_unless(gst_structure_get_double(s, "visibility", &d) && d == in->visibility);
  fail_unless(gst_structure_get_double(s, "grasp-x", &d) && d == in->grasp_x);
  fail_unless(gst_structure_get_double(s, "grasp-y", &d) && d == in->grasp_y);
  fail_unless(gst_structure_get_double(s, "grasp-angle", &d) && d == in->grasp_angle);
  fail_unless(gst_structure_get_int(s, "matches", &i) && i == in->matches);
  fail_unless(gst_structure_get_int(s, "pick-order", &i) && i == in->pick_order);
  fail_unless(gst_structure_get_boolean(s, "pickable", &b) && !b == !in->pickable);
  fail_unless(gst_structure_get_boolean(s, "covered", &b) && !b == !in->covered);
  const std::vector<double> points = double_array(s, "points");
  fail_unless_equals_int(points.size(), 2 * in->n_points);
  for (guint k = 0; k < in->n_points; k++)
    fail_unless(points[2 * k] == in->points[k].x && points[2 * k + 1] == in->points[k].y);
  fail_unless(points[0] == in->center_x && points[1] == in->center_y,
              "points[0] is not the centre");
  const std::vector<double> outline = double_array(s, "outline");
  fail_unless_equals_int(outline.size(), 2 * in->n_outline);
  for (guint k = 0; k < in->n_outline; k++)
    fail_unless(outline[2 * k] == in->outline[k].x && outline[2 * k + 1] == in->outline[k].y);
}

// The custom meta, the ROI metas and the bus message all tell the same instances.
/// The next "pickdetect" frame message on the bus, passing over the track and count messages.
static GstMessage* pop_frame_message(GstBus* bus) {
  while (GstMessage* msg = gst_bus_pop_filtered(bus, GST_MESSAGE_ELEMENT)) {
    if (gst_structure_has_name(gst_message_get_structure(msg), "pickdetect"))
      return msg;
    gst_message_unref(msg);
  }
  return nullptr;
}

GST_START_TEST(test_meta_roi_message) {
  const cv::Size size(640, 480);
  std::vector<Truth> truth;
  const cv::Mat scene = make_scene(size, &truth);

  GstHarness* h = pickdetect_harness();
  gboolean post = FALSE;
  g_object_get(h->element, "post-messages", &post, nullptr);
  fail_unless(post, "post-messages is on by default");
  GstBus* bus = gst_bus_new();
  gst_element_set_bus(h->element, bus);
  gst_harness_set_src_caps_str(h, caps_string("GRAY8", size).c_str());
  GstBuffer* in = scene_buffer(scene, "GRAY8");
  GST_BUFFER_PTS(in) = 5 * GST_SECOND;
  GstBuffer* out = gst_harness_push_and_pull(h, in);
  fail_unless(out != nullptr);

  const GstPickDetectMeta* meta = gst_buffer_get_pickdetect_meta(out);
  fail_unless(meta != nullptr);
  check_against_truth(meta, truth, "GRAY8");
  fail_unless(gst_pickdetect_meta_get_instance(meta, meta->n_instances) == nullptr);
  for (guint k = 0; k < meta->n_instances; k++) {
    const GstPickDetectInstance* in_ = gst_pickdetect_meta_get_instance(meta, k);
    fail_unless_equals_string(in_->model_name, "box");
    fail_unless(in_->matches >= 6);
    fail_unless(in_->score > 0.0 && in_->score <= 1.0);
    fail_unless(in_->n_points >= 1 && in_->n_outline >= 3);
    fail_unless(in_->points[0].x == in_->center_x && in_->points[0].y == in_->center_y);
    fail_unless(in_->visibility > 0.9);
    fail_unless(!in_->covered);
    fail_unless(in_->pickable); // The two boxes do not overlap.
    fail_unless(in_->pick_order >= 1 && in_->pick_order <= 2);
  }

  // One ROI per instance, unique ids, the outline's box, the same numbers.
  std::vector<gint> ids;
  guint n_roi = 0;
  for (GstVideoRegionOfInterestMeta* roi : roi_metas(out)) {
    fail_unless_equals_string(g_quark_to_string(roi->roi_type), "box");
    fail_unless(std::find(ids.begin(), ids.end(), roi->id) == ids.end(), "duplicate ROI id");
    ids.push_back(roi->id);
    const GstStructure* s = roi_param(roi);
    fail_unless(s != nullptr);
    double cx, cy;
    fail_unless(gst_structure_get_double(s, "center-x", &cx));
    fail_unless(gst_structure_get_double(s, "center-y", &cy));
    const GstPickDetectInstance* match = nullptr;
    for (guint k = 0; k < meta->n_instances; k++)
      if (meta->instances[k].center_x == cx && meta->instances[k].center_y == cy)
        match = &meta->instances[k];
    fail_unless(match != nullptr, "ROI without its instance");
    check_structure_matches(s, match);
    double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
    for (guint k = 0; k < match->n_outline; k++) {
      x0 = std::min(x0, match->outline[k].x);
      y0 = std::min(y0, match->outline[k].y);
      x1 = std::max(x1, match->outline[k].x);
      y1 = std::max(y1, match->outline[k].y);
    }
    fail_unless(std::fabs(roi->x - std::max(0.0, x0)) <= 1.0 &&
                std::fabs(roi->y - std::max(0.0, y0)) <= 1.0);
    fail_unless(std::fabs(roi->x + roi->w - std::min(640.0, x1)) <= 1.0 &&
                std::fabs(roi->y + roi->h - std::min(480.0, y1)) <= 1.0);
    fail_unless(roi->x + roi->w <= 640 && roi->y + roi->h <= 480);
    n_roi++;
  }
  fail_unless_equals_int(n_roi, meta->n_instances);

  // The bus message.
  GstMessage* msg = pop_frame_message(bus);
  fail_unless(msg != nullptr, "no element message");
  const GstStructure* s = gst_message_get_structure(msg);
  fail_unless(gst_structure_has_name(s, "pickdetect"));
  guint64 ts, running, stream;
  fail_unless(gst_structure_get_uint64(s, "timestamp", &ts) && ts == 5 * GST_SECOND);
  fail_unless(gst_structure_get_uint64(s, "running-time", &running) && running == 5 * GST_SECOND);
  fail_unless(gst_structure_get_uint64(s, "stream-time", &stream) && stream == 5 * GST_SECOND);
  const GValue* list = gst_structure_get_value(s, "instances");
  fail_unless(list != nullptr && GST_VALUE_HOLDS_LIST(list));
  fail_unless_equals_int(gst_value_list_get_size(list), meta->n_instances);
  for (guint k = 0; k < gst_value_list_get_size(list); k++) {
    const GstStructure* item = gst_value_get_structure(gst_value_list_get_value(list, k));
    check_structure_matches(item, gst_pickdetect_meta_get_instance(meta, k));
  }
  gst_message_unref(msg);
  gst_buffer_unref(out);

  // Nothing in the frame: still a meta (empty), no ROI, a message with an empty list.
  out = gst_harness_push_and_pull(h, scene_buffer(make_scene(size, nullptr, false), "GRAY8"));
  meta = gst_buffer_get_pickdetect_meta(out);
  fail_unless(meta != nullptr);
  fail_unless_equals_int(gst_pickdetect_meta_get_n_instances(meta), 0);
  fail_unless(gst_buffer_get_video_region_of_interest_meta(out) == nullptr);
  msg = pop_frame_message(bus);
  fail_unless(msg != nullptr);
  fail_unless_equals_int(
      gst_value_list_get_size(gst_structure_get_value(gst_message_get_structure(msg), "instances")),
      0);
  gst_message_unref(msg);
  gst_buffer_unref(out);

  // post-messages=false: no message.
  g_object_set(h->element, "post-messages", FALSE, nullptr);
  gst_buffer_unref(gst_harness_push_and_pull(h, scene_buffer(scene, "GRAY8")));
  fail_unless(pop_frame_message(bus) == nullptr);

  // Settings changed while playing apply from the next frame on.
  g_object_set(h->element, "max-instances", 1, nullptr);
  out = gst_harness_push_and_pull(h, scene_buffer(scene, "GRAY8"));
  fail_unless_equals_int(gst_pickdetect_meta_get_n_instances(gst_buffer_get_pickdetect_meta(out)),
                         1);
  gst_buffer_unref(out);
  g_object_set(h->element, "max-instances", 0, "min-matches", 100000, nullptr);
  out = gst_harness_push_and_pull(h, scene_buffer(scene, "GRAY8"));
  fail_unless_equals_int(gst_pickdetect_meta_get_n_instances(gst_buffer_get_pickdetect_meta(out)),
                         0);
  gst_buffer_unref(out);

  gst_element_set_bus(h->element, nullptr);
  gst_object_unref(bus);
  gst_harness_teardown(h);
}
GST_END_TEST;

/// Runs `launch` (starting with pickdetect) on one 640x480 GRAY8 scene and returns the output.
static GstBuffer* run_chain(const std::string& launch, const cv::Mat& scene) {
  GstHarness* h = gst_harness_new_parse(launch.c_str());
  gst_harness_set_src_caps_str(h, caps_string("GRAY8", cv::Size(scene.cols, scene.rows)).c_str());
  GstBuffer* out = gst_harness_push_and_pull(h, scene_buffer(scene, "GRAY8"));
  gst_harness_teardown(h);
  return out;
}

// videoscale halves every coordinate of the custom meta; videoconvert keeps it as it is.
GST_START_TEST(test_meta_through_videoscale_videoconvert) {
  const cv::Mat scene = make_scene(cv::Size(640, 480), nullptr);
  const std::string pd = "pickdetect model=\"" + kBoxPath + "\" ";
  GstBuffer* ref = run_chain(pd, scene);
  GstBuffer* scaled = run_chain(
      pd + "! videoscale ! capsfilter caps=video/x-raw,width=320,height=240,format=GRAY8", scene);
  GstBuffer* converted =
      run_chain(pd + "! videoconvert ! capsfilter caps=video/x-raw,format=I420", scene);

  const GstPickDetectMeta* r = gst_buffer_get_pickdetect_meta(ref);
  const GstPickDetectMeta* s = gst_buffer_get_pickdetect_meta(scaled);
  const GstPickDetectMeta* c = gst_buffer_get_pickdetect_meta(converted);
  fail_unless(r && s && c);
  fail_unless_equals_int(gst_buffer_get_size(scaled), 320 * 240);
  fail_unless_equals_int(r->n_instances, 2);
  fail_unless_equals_int(s->n_instances, r->n_instances);
  fail_unless_equals_int(c->n_instances, r->n_instances);
  for (guint k = 0; k < r->n_instances; k++) {
    const GstPickDetectInstance* a = &r->instances[k];
    const GstPickDetectInstance* b = &s->instances[k];
    const GstPickDetectInstance* d = &c->instances[k];
    fail_unless_equals_string(b->model_name, a->model_name);
    fail_unless(std::fabs(b->center_x - a->center_x / 2) < 1e-9);
    fail_unless(std::fabs(b->center_y - a->center_y / 2) < 1e-9);
    fail_unless(std::fabs(b->grasp_x - a->grasp_x / 2) < 1e-9);
    fail_unless(std::fabs(b->scale - a->scale / 2) < 1e-9);
    fail_unless(std::fabs(b->angle - a->angle) < 1e-9);
    fail_unless_equals_int(b->n_points, a->n_points);
    fail_unless_equals_int(b->n_outline, a->n_outline);
    for (guint p = 0; p < a->n_points; p++)
      fail_unless(std::fabs(b->points[p].x - a->points[p].x / 2) < 1e-9 &&
                  std::fabs(b->points[p].y - a->points[p].y / 2) < 1e-9);
    for (guint p = 0; p < a->n_outline; p++)
      fail_unless(std::fabs(b->outline[p].x - a->outline[p].x / 2) < 1e-9 &&
                  std::fabs(b->outline[p].y - a->outline[p].y / 2) < 1e-9);
    fail_unless(b->points != a->points && b->outline != a->outline); // Own copies.

    fail_unless_equals_string(d->model_name, a->model_name);
    fail_unless(d->center_x == a->center_x && d->center_y == a->center_y && d->angle == a->angle &&
                d->scale == a->scale && d->score == a->score && d->matches == a->matches &&
                d->visibility == a->visibility && d->covered == a->covered &&
                d->pickable == a->pickable && d->pick_order == a->pick_order &&
                d->grasp_x == a->grasp_x && d->grasp_y == a->grasp_y &&
                d->grasp_angle == a->grasp_angle);
    fail_unless(d->n_points == a->n_points && d->n_outline == a->n_outline);
    fail_unless(std::memcmp(d->points, a->points, sizeof(GstPickDetectPoint) * a->n_points) == 0);
    fail_unless(std::memcmp(d->outline, a->outline, sizeof(GstPickDetectPoint) * a->n_outline) ==
                0);
  }
  gst_buffer_unref(ref);
  gst_buffer_unref(scaled);
  gst_buffer_unref(converted);
}
GST_END_TEST;

struct SwapState {
  GstHarness* h;
  cv::Mat scene;
  std::atomic<bool> stop{false};
  std::atomic<int> frames{0};
  std::vector<std::string> models; ///< Model of each frame ("" = none found), pusher only.
  bool mixed = false;              ///< A frame had instances of two models.
};

static gpointer push_frames(gpointer data) {
  auto* st = static_cast<SwapState*>(data);
  while (!st->stop.load()) {
    GstBuffer* out = gst_harness_push_and_pull(st->h, scene_buffer(st->scene, "GRAY8"));
    if (!out)
      break;
    const GstPickDetectMeta* meta = gst_buffer_get_pickdetect_meta(out);
    std::string model;
    for (guint k = 0; meta && k < meta->n_instances; k++) {
      if (!model.empty() && model != meta->instances[k].model_name)
        st->mixed = true;
      model = meta->instances[k].model_name;
    }
    st->models.push_back(meta ? model : "<no meta>");
    gst_buffer_unref(out);
    st->frames.fetch_add(1);
  }
  return nullptr;
}

static void wait_frames(const SwapState& st, int n) {
  const gint64 deadline = g_get_monotonic_time() + 120 * G_TIME_SPAN_SECOND;
  while (st.frames.load() < n && g_get_monotonic_time() < deadline)
    g_usleep(2000);
  fail_unless(st.frames.load() >= n, "frames stopped flowing");
}

// Swapping the model from another thread while frames flow: no crash, no frame with two models,
// every frame started after the swap uses the new model; a bad model keeps the old one.
GST_START_TEST(test_model_swap_while_playing) {
  gchar* dir = g_dir_make_tmp("pickdetect-XXXXXX", nullptr);
  fail_unless(dir != nullptr);
  gchar* contents;
  gsize length;
  fail_unless(g_file_get_contents(kBoxPath.c_str(), &contents, &length, nullptr));
  gchar* crate = g_build_filename(dir, "crate.png", nullptr);
  fail_unless(g_file_set_contents(crate, contents, length, nullptr));
  g_free(contents);
  gchar* broken = g_build_filename(dir, "broken.yml", nullptr);
  fail_unless(g_file_set_contents(broken, "this: [is not a model", -1, nullptr));

  SwapState st;
  st.h = pickdetect_harness();
  st.scene = make_scene(cv::Size(640, 480), nullptr);
  GstBus* bus = gst_bus_new();
  gst_element_set_bus(st.h->element, bus);
  gst_harness_set_src_caps_str(st.h, caps_string("GRAY8", cv::Size(640, 480)).c_str());
  GThread* pusher = g_thread_new("pusher", push_frames, &st);

  wait_frames(st, 2);
  g_object_set(st.h->element, "model", crate, nullptr); // Returns once the swap is done.
  const int swapped_at = st.frames.load();
  wait_frames(st, swapped_at + 3);

  // A model that cannot be loaded: a warning, the old model stays.
  g_object_set(st.h->element, "model", broken, nullptr);
  gchar* model = nullptr;
  g_object_get(st.h->element, "model", &model, nullptr);
  fail_unless_equals_string(model, crate);
  g_free(model);
  const int broken_at = st.frames.load();
  wait_frames(st, broken_at + 3);

  st.stop = true;
  g_thread_join(pusher);

  fail_unless(!st.mixed, "a frame mixed two models");
  const int n = static_cast<int>(st.models.size());
  for (int i = 0; i < n; i++) {
    if (i < 2)
      fail_unless_equals_string(st.models[i].c_str(), "box");
    if (i > swapped_at) // Frame swapped_at may have begun before the swap.
      fail_unless_equals_string(st.models[i].c_str(), "crate");
  }
  GstMessage* msg = gst_bus_pop_filtered(bus, GST_MESSAGE_WARNING);
  fail_unless(msg != nullptr, "no warning for the broken model");
  GError* err = nullptr;
  gst_message_parse_warning(msg, &err, nullptr);
  fail_unless(err->domain == GST_RESOURCE_ERROR);
  fail_unless(std::strstr(err->message, "broken.yml") != nullptr, "%s", err->message);
  g_error_free(err);
  gst_message_unref(msg);

  gst_element_set_bus(st.h->element, nullptr);
  gst_object_unref(bus);
  gst_harness_teardown(st.h);
  g_unlink(crate);
  g_unlink(broken);
  g_rmdir(dir);
  g_free(crate);
  g_free(broken);
  g_free(dir);
}
GST_END_TEST;

/// Starts "videotestsrc ! pickdetect <props> ! fakesink"; returns the error of the failed start.
static GError* start_error(const char* props) {
  gchar* launch = g_strdup_printf("videotestsrc num-buffers=1 ! pickdetect %s ! fakesink", props);
  GstElement* pipeline = gst_parse_launch(launch, nullptr);
  g_free(launch);
  fail_unless(pipeline != nullptr);
  fail_unless_equals_int(gst_element_set_state(pipeline, GST_STATE_PAUSED),
                         GST_STATE_CHANGE_FAILURE);
  GstBus* bus = gst_element_get_bus(pipeline);
  GstMessage* msg = gst_bus_pop_filtered(bus, GST_MESSAGE_ERROR);
  fail_unless(msg != nullptr, "no error message");
  GError* err = nullptr;
  gst_message_parse_error(msg, &err, nullptr);
  gst_message_unref(msg);
  gst_object_unref(bus);
  gst_element_set_state(pipeline, GST_STATE_NULL);
  gst_object_unref(pipeline);
  return err;
}

// A missing, invalid or absent model fails the start with an error naming the file and why.
GST_START_TEST(test_model_errors) {
  GError* err = start_error("model=/nonexistent/folder/parts.yml");
  fail_unless(g_error_matches(err, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_NOT_FOUND), "%s",
              err->message);
  fail_unless(std::strstr(err->message, "/nonexistent/folder/parts.yml") != nullptr, "%s",
              err->message);
  g_error_free(err);

  gchar* dir = g_dir_make_tmp("pickdetect-XXXXXX", nullptr);
  gchar* bad = g_build_filename(dir, "bad.yml", nullptr);
  fail_unless(g_file_set_contents(bad, "%YAML:1.0\nnot: [a model\n", -1, nullptr));
  gchar* props = g_strdup_printf("model=\"%s\"", bad);
  err = start_error(props);
  fail_unless(g_error_matches(err, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_SETTINGS), "%s",
              err->message);
  fail_unless(std::strstr(err->message, bad) != nullptr, "%s", err->message);
  g_error_free(err);
  g_free(props);
  g_unlink(bad);
  g_rmdir(dir);
  g_free(bad);
  g_free(dir);

  // A folder is not readable as a model.
  props = g_strdup_printf("model=\"%s\"", TEST_DATA_DIR);
  err = start_error(props);
  fail_unless(g_error_matches(err, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_OPEN_READ), "%s",
              err->message);
  fail_unless(std::strstr(err->message, TEST_DATA_DIR) != nullptr, "%s", err->message);
  g_error_free(err);
  g_free(props);

  err = start_error("");
  fail_unless(g_error_matches(err, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_NOT_FOUND));
  fail_unless(std::strstr(err->message, "\"model\"") != nullptr, "%s", err->message);
  g_error_free(err);
}
GST_END_TEST;

/* ---- Several models in one element; pickable and covered ---------------------------------- */

/// A picture pasted into `scene` (grey) at `pose`, about the picture's centre.
static void paste(cv::Mat& scene, const cv::Mat& picture, const Pose& pose) {
  pickdetect::test_scene::paste(scene, picture, {scene_pose(pose)});
}

/// A look-alike of the box: box.png with its right half replaced by a piece of baboon.jpg, so
/// that the two models share the left half. Written as `dir`/variant.png; returns the path.
static std::string write_variant(const std::string& dir) {
  const cv::Mat box = box_model().image;
  cv::Mat variant = box.clone();
  cv::Mat baboon = cv::imread(std::string(TEST_DATA_DIR) + "/baboon.jpg", cv::IMREAD_GRAYSCALE);
  fail_unless(!baboon.empty(), "baboon.jpg missing from " TEST_DATA_DIR);
  const cv::Rect right(box.cols / 2, 0, box.cols - box.cols / 2, box.rows);
  cv::resize(baboon(cv::Rect(0, 0, baboon.cols / 2, baboon.rows / 2)), variant(right), right.size(),
             0, 0, cv::INTER_AREA);
  const std::string path = dir + "/variant.png";
  fail_unless(cv::imwrite(path, variant));
  return path;
}

/// The box at kPoses[0] and the variant (see write_variant) at kPoses[1], in a 640x480 grey
/// scene.
static cv::Mat box_and_variant_scene(const std::string& variant_path) {
  cv::Mat scene = make_scene(cv::Size(640, 480), nullptr, false);
  paste(scene, box_model().image, kPoses[0]);
  paste(scene, cv::imread(variant_path, cv::IMREAD_GRAYSCALE), kPoses[1]);
  return scene;
}

/// A harness around pickdetect (the box model, then `model` set before the start) taking GRAY8
/// frames of `size`.
static GstHarness* gray_harness(const std::string& model, cv::Size size) {
  GstHarness* h = pickdetect_harness();
  g_object_set(h->element, "model", model.c_str(), nullptr);
  gst_harness_set_src_caps_str(h, caps_string("GRAY8", size).c_str());
  return h;
}

/// A temporary folder, removed with what is in it.
struct TempDir {
  std::string path;
  TempDir() {
    gchar* dir = g_dir_make_tmp("pickdetect-XXXXXX", nullptr);
    fail_unless(dir != nullptr);
    path = dir;
    g_free(dir);
  }
  /// Writes `text` to the file `name` in the folder; returns its path.
  std::string write(const std::string& name, const std::string& text) const {
    const std::string file = path + "/" + name;
    fail_unless(g_file_set_contents(file.c_str(), text.c_str(), -1, nullptr));
    return file;
  }
  ~TempDir() {
    if (GDir* d = g_dir_open(path.c_str(), 0, nullptr)) {
      while (const gchar* name = g_dir_read_name(d))
        g_unlink((path + "/" + name).c_str());
      g_dir_close(d);
    }
    g_rmdir(path.c_str());
  }
};

/// The model names of the meta's instances, sorted.
static std::vector<std::string> model_names(const GstPickDetectMeta* meta) {
  std::vector<std::string> names;
  for (guint k = 0; meta && k < meta->n_instances; k++)
    names.emplace_back(meta->instances[k].model_name);
  std::sort(names.begin(), names.end());
  return names;
}

/// The meta's instance nearest to (x, y).
static const GstPickDetectInstance* nearest(const GstPickDetectMeta* meta, double x, double y) {
  const GstPickDetectInstance* best = nullptr;
  for (guint k = 0; k < meta->n_instances; k++)
    if (!best || std::hypot(meta->instances[k].center_x - x, meta->instances[k].center_y - y) <
                     std::hypot(best->center_x - x, best->center_y - y))
      best = &meta->instances[k];
  return best;
}

// Two look-alike models in one element (the variant shares half of the box): each instance is
// found once, under its own model's name, in the meta, the ROI metas and the bus message.
GST_START_TEST(test_look_alike_models) {
  TempDir dir;
  const std::string variant_path = write_variant(dir.path);
  const cv::Mat variant = cv::imread(variant_path, cv::IMREAD_GRAYSCALE);
  const cv::Size size(640, 480);

  GstHarness* h = pickdetect_harness();
  g_object_set(h->element, "model", (kBoxPath + ", " + variant_path).c_str(), nullptr);
  GstBus* bus = gst_bus_new();
  gst_element_set_bus(h->element, bus);
  gst_harness_set_src_caps_str(h, caps_string("GRAY8", size).c_str());

  // Each model at each place in turn, so that the names follow the pictures, not the places.
  for (int swap = 0; swap < 2; swap++) {
    cv::Mat scene = make_scene(size, nullptr, false);
    const Pose& box_pose = kPoses[swap];
    const Pose& variant_pose = kPoses[1 - swap];
    paste(scene, box_model().image, box_pose);
    paste(scene, variant, variant_pose);
    GstBuffer* out = gst_harness_push_and_pull(h, scene_buffer(scene, "GRAY8"));
    const GstPickDetectMeta* meta = gst_buffer_get_pickdetect_meta(out);
    fail_unless(meta != nullptr);
    fail_unless_equals_int(meta->n_instances, 2); // Neither is reported as both.
    const GstPickDetectInstance* box = nearest(meta, box_pose.x, box_pose.y);
    const GstPickDetectInstance* var = nearest(meta, variant_pose.x, variant_pose.y);
    fail_unless(box != var);
    fail_unless_equals_string(box->model_name, "box");
    fail_unless_equals_string(var->model_name, "variant");
    fail_unless(std::hypot(box->center_x - box_pose.x, box->center_y - box_pose.y) < 2.0,
                "box at (%.1f, %.1f)", box->center_x, box->center_y);
    fail_unless(std::hypot(var->center_x - variant_pose.x, var->center_y - variant_pose.y) < 2.0,
                "variant at (%.1f, %.1f)", var->center_x, var->center_y);

    // The ROI metas name the same model as the instance at their centre.
    guint n_roi = 0;
    for (GstVideoRegionOfInterestMeta* roi : roi_metas(out)) {
      const GstStructure* s = roi_param(roi);
      double cx = 0, cy = 0;
      fail_unless(gst_structure_get_double(s, "center-x", &cx) &&
                  gst_structure_get_double(s, "center-y", &cy));
      const GstPickDetectInstance* in = nearest(meta, cx, cy);
      fail_unless_equals_string(g_quark_to_string(roi->roi_type), in->model_name);
      check_structure_matches(s, in);
      n_roi++;
    }
    fail_unless_equals_int(n_roi, 2);
    GstMessage* msg = pop_frame_message(bus);
    fail_unless(msg != nullptr);
    const GValue* list = gst_structure_get_value(gst_message_get_structure(msg), "instances");
    fail_unless_equals_int(gst_value_list_get_size(list), 2);
    for (guint k = 0; k < 2; k++)
      check_structure_matches(gst_value_get_structure(gst_value_list_get_value(list, k)),
                              &meta->instances[k]);
    gst_message_unref(msg);
    gst_buffer_unref(out);
  }
  gst_element_set_bus(h->element, nullptr);
  gst_object_unref(bus);
  gst_harness_teardown(h);
}
GST_END_TEST;

// Adding a model to the list while playing, then removing it: each takes effect from the next
// frame on, the whole set at once.
GST_START_TEST(test_add_remove_model_while_playing) {
  TempDir dir;
  const std::string variant_path = write_variant(dir.path);
  const cv::Size size(640, 480);
  const cv::Mat scene = box_and_variant_scene(variant_path);

  GstHarness* h = pickdetect_harness();
  gst_harness_set_src_caps_str(h, caps_string("GRAY8", size).c_str());
  auto names_of_next_frame = [&] {
    GstBuffer* out = gst_harness_push_and_pull(h, scene_buffer(scene, "GRAY8"));
    std::vector<std::string> names = model_names(gst_buffer_get_pickdetect_meta(out));
    gst_buffer_unref(out);
    return names;
  };
  auto count = [](const std::vector<std::string>& names, const char* name) {
    return std::count(names.begin(), names.end(), name);
  };

  std::vector<std::string> names = names_of_next_frame();
  fail_unless(!names.empty() && count(names, "box") == static_cast<long>(names.size()),
              "box alone: something else than box found");

  const std::string both = kBoxPath + "," + variant_path;
  g_object_set(h->element, "model", both.c_str(), nullptr);
  gchar* model = nullptr;
  g_object_get(h->element, "model", &model, nullptr);
  fail_unless_equals_string(model, both.c_str());
  g_free(model);
  for (int frame = 0; frame < 2; frame++) {
    names = names_of_next_frame();
    fail_unless(names == std::vector<std::string>({"box", "variant"}),
                "with both models: %zu instances", names.size());
  }

  g_object_set(h->element, "model", kBoxPath.c_str(), nullptr);
  names = names_of_next_frame();
  fail_unless(!names.empty());
  fail_unless_equals_int(count(names, "variant"), 0);
  gst_harness_teardown(h);
}
GST_END_TEST;

// A model file listing two views of one product: each instance is of the product, with the view
// it matched, in the meta, the ROI and its pick-instance param. The back (variant.png) shares
// the front's left half: in one place the view with more matches is the one seen.
GST_START_TEST(test_views_of_one_product) {
  TempDir dir;
  const std::string variant_path = write_variant(dir.path);
  const std::string carton =
      dir.write("carton.yml", "%YAML:1.0\nname: carton\nviews:\n  - name: front\n    image: \"" +
                                  kBoxPath + "\"\n  - image: variant.png\n");
  const cv::Mat scene = box_and_variant_scene(variant_path);
  GstHarness* h = gray_harness(carton, scene.size());
  GstBuffer* out = gst_harness_push_and_pull(h, scene_buffer(scene, "GRAY8"));
  const GstPickDetectMeta* meta = gst_buffer_get_pickdetect_meta(out);
  fail_unless(model_names(meta) == std::vector<std::string>({"carton", "carton"}));
  for (int k = 0; k < 2; k++) {
    const GstPickDetectInstance* in = nearest(meta, kPoses[k].x, kPoses[k].y);
    fail_unless(in != nullptr);
    fail_unless_equals_string(in->view_name, k == 0 ? "front" : "variant");
  }
  int rois = 0;
  for (GstVideoRegionOfInterestMeta* roi : roi_metas(out)) {
    fail_unless_equals_string(g_quark_to_string(roi->roi_type), "carton");
    const GstStructure* s = roi_param(roi);
    double x = 0, y = 0;
    fail_unless(gst_structure_get_double(s, "center-x", &x) &&
                gst_structure_get_double(s, "center-y", &y));
    check_structure_matches(s, nearest(meta, x, y));
    rois++;
  }
  fail_unless_equals_int(rois, 2);
  gst_buffer_unref(out);
  gst_harness_teardown(h);
}
GST_END_TEST;

/// The output of one element with `models` for `scene` pushed in `format`: colour formats made
/// from the BGR `scene` (by GStreamer's video converter where not BGR), GRAY8 from `grey`.
static GstBuffer* push_in_format(const std::string& models, const char* format,
                                 const cv::Mat& scene, const cv::Mat& grey) {
  GstHarness* h = pickdetect_harness();
  g_object_set(h->element, "model", models.c_str(), nullptr);
  gst_harness_set_src_caps_str(h, caps_string(format, scene.size()).c_str());
  const GstVideoFormatInfo* info = gst_video_format_get_info(gst_video_format_from_string(format));
  GstBuffer* in = scene_buffer(GST_VIDEO_FORMAT_INFO_IS_GRAY(info) ? grey : scene, format);
  GstBuffer* out = gst_harness_push_and_pull(h, in);
  gst_harness_teardown(h);
  return out;
}

// Two editions of one design that differ in colour (red and blue swapped): in colour formats
// (packed RGB and YUV) each instance is named by the frame's colour; in GRAY8 the result is the
// core's without colour (which edition a grey frame names is a matter of chance, see
// tests/core/test_colour.cpp).
GST_START_TEST(test_colour_names_look_alike_editions) {
  TempDir dir;
  const cv::Mat warm = pickdetect::test_scene::fruits_print(TEST_DATA_DIR);
  fail_unless(!warm.empty());
  cv::Mat cold;
  cv::cvtColor(warm, cold, cv::COLOR_BGR2RGB);
  fail_unless(cv::imwrite(dir.path + "/warm.png", warm) &&
              cv::imwrite(dir.path + "/cold.png", cold));
  const cv::Size size(800, 480);
  cv::Mat grey = pickdetect::test_scene::smooth_noise_background(size, 3), scene;
  cv::cvtColor(grey, scene, cv::COLOR_GRAY2BGR);
  const Pose at[] = {{220.0, 240.0, 20.0, 0.9}, {580.0, 240.0, 250.0, 0.9}};
  pickdetect::test_scene::paste(scene, warm, {scene_pose(at[0])});
  pickdetect::test_scene::paste(scene, cold, {scene_pose(at[1])});
  cv::cvtColor(scene, grey, cv::COLOR_BGR2GRAY);
  // In grey, what the core finds without colour.
  const std::string models = dir.path + "/warm.png," + dir.path + "/cold.png";
  const std::vector<pickdetect::Instance> found =
      pickdetect::Detector(pickdetect::load_models(models)).detect(grey).instances;
  std::string in_grey[2];
  for (const pickdetect::Instance& in : found)
    for (int k = 0; k < 2; k++)
      if (std::hypot(in.center.x - at[k].x, in.center.y - at[k].y) < 4.0)
        in_grey[k] = in.model_name;

  for (const char* format : {"BGR", "RGB", "xRGB", "BGRA", "I420", "NV12", "NV21", "GRAY8"}) {
    const bool colour = std::strcmp(format, "GRAY8") != 0;
    GstBuffer* out = push_in_format(models, format, scene, grey);
    const GstPickDetectMeta* meta = gst_buffer_get_pickdetect_meta(out);
    fail_unless(meta != nullptr && meta->n_instances == 2, "%s: %u instances", format,
                meta ? meta->n_instances : 0u);
    for (int k = 0; k < 2; k++) {
      const GstPickDetectInstance* in = nearest(meta, at[k].x, at[k].y);
      fail_unless(std::hypot(in->center_x - at[k].x, in->center_y - at[k].y) < 4.0);
      const std::string expected = colour ? (k == 0 ? "warm" : "cold") : in_grey[k];
      fail_unless(in->model_name == expected, "%s: %s at (%.0f, %.0f), not %s", format,
                  in->model_name, in->center_x, in->center_y, expected.c_str());
    }
    gst_buffer_unref(out);
  }
}
GST_END_TEST;

/// `picture` (BGR, the file `models`) pasted at the middle of a grey scene, under a plain disc of
/// `axes` and colour `bgr` at the picture's point `under` (its rim fading as a highlight's does
/// when `soft`), pushed in colour formats and in GRAY8: expects the one instance covered (not
/// pickable) in colour formats and pickable in GRAY8.
static void expect_covered_in_colour_formats(const std::string& models, const cv::Mat& picture,
                                             cv::Point2f under, cv::Size axes, cv::Scalar bgr,
                                             bool soft = false) {
  const cv::Size size(800, 480);
  cv::Mat grey = pickdetect::test_scene::smooth_noise_background(size, 3), scene;
  cv::cvtColor(grey, scene, cv::COLOR_GRAY2BGR);
  const Pose at = {400.0, 240.0, 20.0, 0.9};
  pickdetect::test_scene::paste(scene, picture, {scene_pose(at)});
  const cv::Point2f disc = pickdetect::test_scene::apply(
      pickdetect::test_scene::model_to_scene(picture.size(), scene_pose(at)), under);
  const cv::Point centre(cvRound(disc.x), cvRound(disc.y));
  if (soft)
    pickdetect::test_scene::add_soft_disc(scene, centre, axes, at.angle,
                                          cv::Vec3b(cv::saturate_cast<uchar>(bgr[0]),
                                                    cv::saturate_cast<uchar>(bgr[1]),
                                                    cv::saturate_cast<uchar>(bgr[2])));
  else
    cv::ellipse(scene, centre, axes, at.angle, 0, 360, bgr, cv::FILLED, cv::LINE_AA);
  cv::cvtColor(scene, grey, cv::COLOR_BGR2GRAY);

  for (const char* format : {"BGR", "RGB", "xRGB", "BGRA", "I420", "NV12", "NV21", "GRAY8"}) {
    const bool colour = std::strcmp(format, "GRAY8") != 0;
    GstBuffer* out = push_in_format(models, format, scene, grey);
    const GstPickDetectMeta* meta = gst_buffer_get_pickdetect_meta(out);
    fail_unless(meta != nullptr && meta->n_instances == 1, "%s: %u instances", format,
                meta ? meta->n_instances : 0u);
    const GstPickDetectInstance* in = nearest(meta, at.x, at.y);
    fail_unless(std::hypot(in->center_x - at.x, in->center_y - at.y) < 4.0);
    fail_unless(in->covered == (colour ? TRUE : FALSE), "%s: covered %d", format, in->covered);
    fail_unless(in->pickable == (colour ? FALSE : TRUE), "%s: pickable %d", format, in->pickable);
    gst_buffer_unref(out);
  }
}

// Pick safety from the frame's colour: a plain card of another colour, as light in grey as the
// plain panel of the print it lies on, makes the instance covered in packed RGB and YUV
// formats; in GRAY8 nothing tells it from the panel.
GST_START_TEST(test_colour_cover_in_colour_formats) {
  TempDir dir;
  const cv::Mat fruits = pickdetect::test_scene::fruits_print(TEST_DATA_DIR);
  fail_unless(!fruits.empty());
  // The picture: the print beside a plain orange panel.
  cv::Mat picture(220, 460, CV_8UC3, cv::Scalar(40, 130, 230));
  fruits.copyTo(picture(cv::Rect(0, 0, fruits.cols, fruits.rows)));
  fail_unless(cv::imwrite(dir.path + "/panel.png", picture));
  // The card over the panel's middle (picture point (380, 110)), teal, as light as the orange.
  const double orange_grey = 0.114 * 40 + 0.587 * 130 + 0.299 * 230;
  const double teal_green = (orange_grey - 0.114 * 200 - 0.299 * 40) / 0.587;
  expect_covered_in_colour_formats(dir.path + "/panel.png", picture, {380.f, 110.f}, {34, 26},
                                   cv::Scalar(200, teal_green, 40));
}
GST_END_TEST;

// A model picture without colour (box.png): the frame's colour still goes to the detector in
// colour formats, where a plain disc of clear colour, lighter than the print under it, covers
// the box (a highlight would be near white); in GRAY8, its rim fading into the print as a
// highlight's does, it may be glare and the box stays pickable.
GST_START_TEST(test_colour_cover_on_a_grey_picture) {
  cv::Mat picture;
  cv::cvtColor(box_model().image, picture, cv::COLOR_GRAY2BGR);
  // Light green (grey level about 191) over the print at picture point (200, 150), grey 113.
  expect_covered_in_colour_formats(kBoxPath, picture, {200.f, 150.f}, {30, 22},
                                   cv::Scalar(120, 240, 120), true);
}
GST_END_TEST;

// A model-set file lists models relative to itself; a broken set, a missing model, two models of
// one name or an empty list entry refuse the start, naming what is wrong.
GST_START_TEST(test_model_set_file) {
  TempDir dir;
  const std::string variant_path = write_variant(dir.path);
  const std::string set_path =
      dir.write("products.yml", "%YAML:1.0\nmodels:\n  - \"" + kBoxPath + "\"\n  - variant.png\n");

  const cv::Mat scene = box_and_variant_scene(variant_path);
  GstHarness* h = gray_harness(set_path, scene.size());
  GstBuffer* out = gst_harness_push_and_pull(h, scene_buffer(scene, "GRAY8"));
  fail_unless(model_names(gst_buffer_get_pickdetect_meta(out)) ==
              std::vector<std::string>({"box", "variant"}));
  gst_buffer_unref(out);
  gst_harness_teardown(h);

  auto expect_error = [](const std::string& model, GstResourceError code, const std::string& what) {
    GError* err = start_error(("model=\"" + model + "\"").c_str());
    fail_unless(g_error_matches(err, GST_RESOURCE_ERROR, code), "%s: %s", model.c_str(),
                err->message);
    fail_unless(std::strstr(err->message, what.c_str()) != nullptr, "%s", err->message);
    g_error_free(err);
  };
  const std::string missing_set = dir.write("missing.yml", "%YAML:1.0\nmodels: [gone.png]\n");
  expect_error(missing_set, GST_RESOURCE_ERROR_NOT_FOUND, dir.path + "/gone.png");
  const std::string empty_set = dir.write("empty.yml", "%YAML:1.0\nmodels: 3\n");
  expect_error(empty_set, GST_RESOURCE_ERROR_SETTINGS, "'models' must be");
  const std::string nested_set = dir.write("nested.yml", "%YAML:1.0\nmodels: [products.yml]\n");
  expect_error(nested_set, GST_RESOURCE_ERROR_SETTINGS, "lists another model set");
  // box.png is in the set too: two models named "box".
  expect_error(set_path + "," + kBoxPath, GST_RESOURCE_ERROR_SETTINGS,
               "two models are named \"box\"");
  expect_error(kBoxPath + ",," + variant_path, GST_RESOURCE_ERROR_SETTINGS, "empty entry");
}
GST_END_TEST;

/// Whether any pixel within `r` of (x, y) is in [lo, hi].
static bool colour_near(const cv::Mat& rgb, cv::Point2f p, int r, cv::Vec3b lo, cv::Vec3b hi) {
  for (int dy = -r; dy <= r; dy++)
    for (int dx = -r; dx <= r; dx++) {
      const int x = static_cast<int>(std::lround(p.x)) + dx;
      const int y = static_cast<int>(std::lround(p.y)) + dy;
      if (x < 0 || y < 0 || x >= rgb.cols || y >= rgb.rows)
        continue;
      const cv::Vec3b c = rgb.at<cv::Vec3b>(y, x);
      if (c[0] >= lo[0] && c[0] <= hi[0] && c[1] >= lo[1] && c[1] <= hi[1] && c[2] >= lo[2] &&
          c[2] <= hi[2])
        return true;
    }
  return false;
}

/// Points every 8 pixels along the instance's outline, leaving out those within `keep_off` of
/// the other outline (where the two outlines cross).
static std::vector<cv::Point2f> along_outline(const GstPickDetectInstance* in,
                                              const GstPickDetectInstance* other, double keep_off) {
  std::vector<cv::Point2f> other_outline;
  for (guint k = 0; k < other->n_outline; k++)
    other_outline.emplace_back(other->outline[k].x, other->outline[k].y);
  std::vector<cv::Point2f> out;
  for (guint k = 0; k < in->n_outline; k++) {
    const GstPickDetectPoint a = in->outline[k], b = in->outline[(k + 1) % in->n_outline];
    const double length = std::hypot(b.x - a.x, b.y - a.y);
    for (double t = 12.0; t < length - 12.0; t += 8.0) {
      const cv::Point2f p(a.x + (b.x - a.x) * t / length, a.y + (b.y - a.y) * t / length);
      if (std::fabs(cv::pointPolygonTest(other_outline, p, true)) > keep_off)
        out.push_back(p);
    }
  }
  return out;
}

// A box a fifth of which lies beyond the frame's left edge: pickable by default, not with
// pick-whole-in-view (set as gst-launch-1.0 sets it, from a string), which a box wholly in view
// keeps.
GST_START_TEST(test_pick_whole_in_view) {
  const cv::Size size(640, 480);
  for (const char* value : {"false", "true"}) {
    for (double x : {70.0, 200.0}) { // Box 227 px wide: a fifth outside, then wholly inside.
      cv::Mat scene = make_scene(size, nullptr, false);
      paste(scene, box_model().image, Pose{x, 240.0, 0.0, 0.7});
      GstHarness* h = pickdetect_harness();
      gst_util_set_object_arg(G_OBJECT(h->element), "pick-whole-in-view", value);
      gboolean whole = FALSE;
      g_object_get(h->element, "pick-whole-in-view", &whole, nullptr);
      fail_unless(!whole == (std::strcmp(value, "false") == 0));
      gst_harness_set_src_caps_str(h, caps_string("GRAY8", size).c_str());
      GstBuffer* out = gst_harness_push_and_pull(h, scene_buffer(scene, "GRAY8"));
      const GstPickDetectMeta* meta = gst_buffer_get_pickdetect_meta(out);
      fail_unless(meta != nullptr);
      fail_unless_equals_int(meta->n_instances, 1);
      const GstPickDetectInstance* in = &meta->instances[0];
      const bool expected = !whole || x > 150.0;
      fail_unless(!in->covered, "pick-whole-in-view=%s, x %.0f: covered", value, x);
      fail_unless(!in->pickable == !expected && (in->pick_order == 1) == expected,
                  "pick-whole-in-view=%s, x %.0f: pickable %d, order %d", value, x, in->pickable,
                  in->pick_order);
      gst_buffer_unref(out);
      gst_harness_teardown(h);
    }
  }
}
GST_END_TEST;

// One box lying across another: the element reports the core's covered / pickable / pick order
// as they are, and draws the pickable one in green, the covered one in red, in every format.
GST_START_TEST(test_pickable_and_covered) {
  const cv::Size size(640, 480);
  cv::Mat scene = make_scene(size, nullptr, false);
  const Pose below{270.0, 220.0, 15.0, 0.7}, above{380.0, 290.0, 60.0, 0.7};
  paste(scene, box_model().image, below);
  paste(scene, box_model().image, above);

  // The core on the same grey frame decides; the element must not decide otherwise.
  const pickdetect::Detector detector({box_model()});
  const pickdetect::Detection core = detector.detect(scene);

  for (const char* format : kFormats) {
    GstHarness* h = pickdetect_harness(true);
    gst_harness_set_src_caps_str(h, caps_string(format, size).c_str());
    GstBuffer* in = scene_buffer(scene, format);
    GstBuffer* original = gst_buffer_copy_deep(in);
    GstBuffer* out = gst_harness_push_and_pull(h, in);
    const GstPickDetectMeta* meta = gst_buffer_get_pickdetect_meta(out);
    fail_unless(meta != nullptr);
    fail_unless_equals_int(meta->n_instances, 2);
    const GstPickDetectInstance* top = nearest(meta, above.x, above.y);
    const GstPickDetectInstance* bottom = nearest(meta, below.x, below.y);
    fail_unless(top != bottom);
    fail_unless(top->pickable && !top->covered && top->pick_order == 1, "%s: top not pickable",
                format);
    fail_unless(!bottom->pickable && bottom->covered && bottom->pick_order == 0,
                "%s: bottom not covered", format);
    fail_unless(bottom->visibility < 0.95, "%s: bottom visibility %.3f", format,
                bottom->visibility);
    fail_unless_equals_int(core.instances.size(), 2);
    for (const pickdetect::Instance& c : core.instances) {
      const GstPickDetectInstance* e = nearest(meta, c.center.x, c.center.y);
      fail_unless(std::hypot(e->center_x - c.center.x, e->center_y - c.center.y) < 0.5);
      fail_unless(!e->pickable == !c.pickable && !e->covered == !c.covered &&
                      e->pick_order == c.pick_order,
                  "%s: the element's pickable / covered / order differ from the core's", format);
      fail_unless(std::fabs(e->visibility - c.visibility) < 1e-9);
    }

    const cv::Mat before = to_rgb(original, format, size);
    const cv::Mat after = to_rgb(out, format, size);
    const std::vector<cv::Point2f> top_edge = along_outline(top, bottom, 8.0);
    const std::vector<cv::Point2f> bottom_edge = along_outline(bottom, top, 8.0);
    fail_unless(top_edge.size() > 40 && bottom_edge.size() > 40);
    const bool grey = std::strcmp(format, "GRAY8") == 0;
    // Grey levels: green is drawn at luma 150, red at 76.
    const cv::Vec3b green_lo = grey ? cv::Vec3b(145, 145, 145) : cv::Vec3b(0, 170, 0);
    const cv::Vec3b green_hi = grey ? cv::Vec3b(155, 155, 155) : cv::Vec3b(90, 255, 90);
    const cv::Vec3b red_lo = grey ? cv::Vec3b(71, 71, 71) : cv::Vec3b(170, 0, 0);
    const cv::Vec3b red_hi = grey ? cv::Vec3b(81, 81, 81) : cv::Vec3b(255, 90, 90);
    auto share = [&](const cv::Mat& rgb, const std::vector<cv::Point2f>& pts, cv::Vec3b lo,
                     cv::Vec3b hi) {
      int n = 0;
      for (const cv::Point2f& p : pts)
        n += colour_near(rgb, p, 1, lo, hi);
      return static_cast<double>(n) / pts.size();
    };
    const double top_green = share(after, top_edge, green_lo, green_hi);
    const double bottom_red = share(after, bottom_edge, red_lo, red_hi);
    fail_unless(top_green > 0.9, "%s: pickable outline green at %.2f of its length", format,
                top_green);
    fail_unless(bottom_red > 0.9, "%s: covered outline red at %.2f of its length", format,
                bottom_red);
    if (!grey) {
      fail_unless(share(before, top_edge, green_lo, green_hi) == 0.0);
      fail_unless(share(before, bottom_edge, red_lo, red_hi) == 0.0);
      fail_unless(share(after, top_edge, red_lo, red_hi) < 0.05, "%s: red on the pickable", format);
      fail_unless(share(after, bottom_edge, green_lo, green_hi) < 0.05, "%s: green on the covered",
                  format);
      // The big "#1" left above the top box's centre: a green blob the covered box lacks.
      const cv::Rect order_box(static_cast<int>(top->center_x) - 60,
                               static_cast<int>(top->center_y) - 45, 48, 35);
      const cv::Rect no_order_box(static_cast<int>(bottom->center_x) - 60,
                                  static_cast<int>(bottom->center_y) - 45, 48, 35);
      fail_unless(count_pixels(after(order_box), green_lo, green_hi) > 80, "%s: no #1", format);
      fail_unless(count_pixels(after(no_order_box), green_lo, green_hi) < 10,
                  "%s: a pick order on the covered box", format);
    }
    gst_buffer_unref(original);
    gst_buffer_unref(out);
    gst_harness_teardown(h);
  }
}
GST_END_TEST;

static Suite* pickdetect_suite(void) {
  Suite* s = suite_create("pickdetect");
  TCase* tc = pickdetect::test_harness::add_tcase(s, "element", 600);
  tcase_add_test(tc, test_model_errors);
  tcase_add_test(tc, test_meta_roi_message);
  tcase_add_test(tc, test_formats_same_instances);
  tcase_add_test(tc, test_draw_colours);
  tcase_add_test(tc, test_meta_through_videoscale_videoconvert);
  tcase_add_test(tc, test_model_swap_while_playing);
  tcase_add_test(tc, test_look_alike_models);
  tcase_add_test(tc, test_add_remove_model_while_playing);
  tcase_add_test(tc, test_model_set_file);
  tcase_add_test(tc, test_views_of_one_product);
  tcase_add_test(tc, test_colour_names_look_alike_editions);
  tcase_add_test(tc, test_colour_cover_in_colour_formats);
  tcase_add_test(tc, test_colour_cover_on_a_grey_picture);
  tcase_add_test(tc, test_pickable_and_covered);
  tcase_add_test(tc, test_pick_whole_in_view);
  return s;
}

GST_CHECK_MAIN(pickdetect);
