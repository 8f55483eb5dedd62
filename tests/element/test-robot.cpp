// SPDX-License-Identifier: LGPL-2.1-or-later
// Robot-ready output (issue 19): positions in millimetres on a tilted work plane, seen through a
// camera with lens distortion, of boxes whose top face lies a known height above the plane; the
// pickdetectjson element's lines against the metas, field by field; bad calibration files.
// OpenCV comes before gstcheck.h, whose `fail` macro would clash with OpenCV's identifiers.
#include "../support/camera_scene.hpp"
#include "common/video-buffer.hpp"

#include <pickdetect/calibration.hpp>

#include <opencv2/imgcodecs.hpp>

#include <glib/gstdio.h>
#include <gst/check/gstcheck.h>
#include <gst/check/gstharness.h>
#include <gst/pickdetect/pickdetect-meta.h>
#include <gst/video/video.h>
#include <json-glib/json-glib.h>

#include "../support/harness.hpp"

#include <cmath>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace {

namespace cs = pickdetect::camera_scene;
using pickdetect::test_harness::kBoxPath;

constexpr double kBoxHeight = 40.0; ///< mm, the model file's `height`.

/// The cell of these tests: a temporary folder with the calibration file (the true camera,
/// looking 28 degrees off the plane's normal) and a model file of box.png with its height.
struct Cell {
  std::string dir, calibration, model;
  pickdetect::Calibration camera;
  cv::Mat rays;

  Cell() {
    gchar* d = g_dir_make_tmp("pickdetect-robot-XXXXXX", nullptr);
    dir = d;
    g_free(d);
    camera = cs::test_camera();
    cs::look_at(camera, {0, 0}, 900.0, 28.0, 15.0);
    calibration = dir + "/cell.yml";
    pickdetect::save_calibration(camera, calibration);
    model = dir + "/box.yml";
    std::ofstream(model) << "%YAML:1.0\nname: box\nimage: \"" << TEST_DATA_DIR
                         << "/box.png\"\nheight: " << kBoxHeight << "\n";
    rays = cs::normalised_rays(camera);
  }
  ~Cell() {
    for (const std::string& f : {calibration, model})
      g_remove(f.c_str());
    g_rmdir(dir.c_str());
  }
};

const std::vector<cs::Box> kBoxes = {
    {{-170, -90}, 20, kBoxHeight, 0.5},
    {{150, -70}, 130, kBoxHeight, 0.5},
    {{-20, 90}, 275, kBoxHeight, 0.5},
};

cv::Mat box_picture() {
  return cv::imread(kBoxPath, cv::IMREAD_GRAYSCALE);
}

GstBuffer* gray_buffer(const cv::Mat& grey, GstClockTime pts) {
  GstBuffer* buffer = pickdetect::tools::video_buffer(grey, "GRAY8");
  GST_BUFFER_PTS(buffer) = pts;
  GST_BUFFER_DURATION(buffer) = GST_SECOND / 10;
  return buffer;
}

std::string gray_caps(const cv::Size& size) {
  return pickdetect::tools::caps_string("GRAY8", size, 10);
}

/// The frame through pickdetect with the cell's calibration and model: the annotated buffer.
GstBuffer* detect(const Cell& cell, const cv::Mat& frame) {
  const std::string launch =
      "pickdetect model=\"" + cell.model + "\" calibration=\"" + cell.calibration + "\"";
  GstHarness* h = gst_harness_new_parse(launch.c_str());
  gst_harness_set_src_caps_str(h, gray_caps(frame.size()).c_str());
  GstBuffer* out = gst_harness_push_and_pull(h, gray_buffer(frame, 0));
  gst_harness_teardown(h);
  return out;
}

double angle_gap(double a, double b) {
  const double d = std::fmod(std::abs(a - b), 360.0);
  return std::min(d, 360.0 - d);
}

GST_START_TEST(test_world_positions_within_half_a_millimetre) {
  const Cell cell;
  const cv::Mat frame = cs::render_boxes(cell.camera, cell.rays, box_picture(), kBoxes);
  GstBuffer* out = detect(cell, frame);
  fail_unless(out != nullptr);
  const GstPickDetectMeta* meta = gst_buffer_get_pickdetect_meta(out);
  fail_unless(meta != nullptr);
  fail_unless_equals_int(gst_pickdetect_meta_get_n_instances(meta), kBoxes.size());

  const cv::Mat box = box_picture();
  for (const cs::Box& truth : kBoxes) {
    const GstPickDetectInstance* best = nullptr;
    double gap = 1e9;
    for (guint i = 0; i < meta->n_instances; i++) {
      const GstPickDetectInstance& in = meta->instances[i];
      fail_unless(in.calibrated, "instance %u not calibrated", i);
      const double d = std::hypot(in.world_x - truth.center.x, in.world_y - truth.center.y);
      if (d < gap) {
        gap = d;
        best = &in;
      }
    }
    fail_unless(gap < 0.5, "box at (%.1f, %.1f) mm: nearest instance at (%.3f, %.3f), %.3f mm off",
                truth.center.x, truth.center.y, best->world_x, best->world_y, gap);
    fail_unless(angle_gap(best->world_angle, truth.angle_deg) < 1.0,
                "box at (%.1f, %.1f): angle %.2f on the plane, expected %.2f", truth.center.x,
                truth.center.y, best->world_angle, truth.angle_deg);
    fail_unless(std::hypot(best->grasp_world_x - truth.center.x,
                           best->grasp_world_y - truth.center.y) < 0.5,
                "grasp point (the centre) off");
    fail_unless(best->height == kBoxHeight, "height %g", best->height);
    // The outline's corners, extrapolated from the pose, within 2 mm.
    fail_unless_equals_int(best->n_world_outline, 4);
    const double a = truth.angle_deg * CV_PI / 180.0;
    const double hw = box.cols / 2.0 * truth.mm_per_model_px;
    const double hh = box.rows / 2.0 * truth.mm_per_model_px;
    const cv::Point2d corners[4] = {{-hw, -hh}, {hw, -hh}, {hw, hh}, {-hw, hh}};
    for (int k = 0; k < 4; k++) {
      const cv::Point2d want(
          truth.center.x + std::cos(a) * corners[k].x - std::sin(a) * corners[k].y,
          truth.center.y + std::sin(a) * corners[k].x + std::cos(a) * corners[k].y);
      const GstPickDetectPoint& got = best->world_outline[k];
      fail_unless(std::hypot(got.x - want.x, got.y - want.y) < 2.0,
                  "outline corner %d: (%.2f, %.2f) mm, expected (%.2f, %.2f)", k, got.x, got.y,
                  want.x, want.y);
    }
    // Without the height the same pixel would be far off: the test sees the height's effect.
    const cv::Point2d flat = cell.camera.to_plane({best->center_x, best->center_y}, 0.0);
    fail_unless(std::hypot(flat.x - truth.center.x, flat.y - truth.center.y) > 5.0,
                "the height should matter here");
  }

  // The pick-instance structures carry the same world fields.
  int rois = 0;
  for (GstVideoRegionOfInterestMeta* roi : pickdetect::test_harness::roi_metas(out)) {
    const GstStructure* s = pickdetect::test_harness::roi_param(roi);
    fail_unless(s != nullptr);
    double wx = 0, wy = 0, angle = 0, gx = 0, gy = 0, height = 0;
    fail_unless(gst_structure_get(s, "world-x", G_TYPE_DOUBLE, &wx, "world-y", G_TYPE_DOUBLE, &wy,
                                  "world-angle", G_TYPE_DOUBLE, &angle, "grasp-world-x",
                                  G_TYPE_DOUBLE, &gx, "grasp-world-y", G_TYPE_DOUBLE, &gy, "height",
                                  G_TYPE_DOUBLE, &height, nullptr));
    const GstPickDetectInstance& in = meta->instances[rois];
    fail_unless(wx == in.world_x && wy == in.world_y && angle == in.world_angle &&
                gx == in.grasp_world_x && gy == in.grasp_world_y && height == in.height);
    const GValue* outline = gst_structure_get_value(s, "world-outline");
    fail_unless(outline && gst_value_array_get_size(outline) == 2 * in.n_world_outline);
    rois++;
  }
  fail_unless_equals_int(rois, meta->n_instances);
  gst_buffer_unref(out);
}
GST_END_TEST;

/// The JSON lines of `buffers` (annotated frames) through pickdetectjson.
std::vector<std::string> json_lines(const std::vector<GstBuffer*>& buffers, const cv::Size& size,
                                    bool add_empty) {
  GstHarness* h =
      gst_harness_new_parse(add_empty ? "pickdetectjson add-empty-results=true" : "pickdetectjson");
  gst_harness_set_src_caps_str(h, gray_caps(size).c_str());
  std::vector<std::string> lines;
  for (GstBuffer* b : buffers) {
    fail_unless_equals_int(gst_harness_push(h, gst_buffer_ref(b)), GST_FLOW_OK);
    while (GstBuffer* out = gst_harness_try_pull(h)) {
      GstMapInfo map;
      fail_unless(gst_buffer_map(out, &map, GST_MAP_READ));
      lines.emplace_back(reinterpret_cast<const char*>(map.data), map.size);
      gst_buffer_unmap(out, &map);
      fail_unless(GST_BUFFER_PTS(out) == GST_BUFFER_PTS(b), "the line keeps the frame's pts");
      gst_buffer_unref(out);
    }
  }
  GstCaps* caps = gst_pad_get_current_caps(h->sinkpad);
  if (caps) {
    fail_unless(gst_structure_has_name(gst_caps_get_structure(caps, 0), "application/x-json"));
    gst_caps_unref(caps);
  }
  gst_harness_teardown(h);
  return lines;
}

void check_number(JsonObject* o, const char* name, double want) {
  fail_unless(json_object_has_member(o, name), "no member %s", name);
  const double got = json_object_get_double_member(o, name);
  fail_unless(got == want, "%s: %.17g in the JSON, %.17g in the meta", name, got, want);
}

void check_points(JsonObject* o, const char* name, const GstPickDetectPoint* points, guint n) {
  JsonArray* a = json_object_get_array_member(o, name);
  fail_unless(a != nullptr, "no array %s", name);
  fail_unless_equals_int(json_array_get_length(a), n);
  for (guint i = 0; i < n; i++) {
    JsonArray* p = json_array_get_array_element(a, i);
    fail_unless(json_array_get_length(p) == 2);
    fail_unless(json_array_get_double_element(p, 0) == points[i].x &&
                    json_array_get_double_element(p, 1) == points[i].y,
                "%s[%u] differs", name, i);
  }
}

GST_START_TEST(test_velocity_on_the_plane_in_millimetres_per_second) {
  // The three boxes ride 6 mm along the plane's x axis per frame, at 10 frames a second: 60 mm/s
  // on the plane, whatever the perspective makes of it in pixels.
  const Cell cell;
  const cv::Mat box = box_picture();
  const std::string launch =
      "pickdetect model=\"" + cell.model + "\" calibration=\"" + cell.calibration + "\"";
  GstHarness* h = gst_harness_new_parse(launch.c_str());
  GstBuffer* last = nullptr;
  for (int k = 0; k < 3; ++k) {
    std::vector<cs::Box> moved = kBoxes;
    for (cs::Box& b : moved)
      b.center.x += 6.0 * k;
    const cv::Mat frame = cs::render_boxes(cell.camera, cell.rays, box, moved);
    if (k == 0)
      gst_harness_set_src_caps_str(h, gray_caps(frame.size()).c_str());
    if (last)
      gst_buffer_unref(last);
    last = gst_harness_push_and_pull(h, gray_buffer(frame, k * GST_SECOND / 10));
  }
  const GstPickDetectMeta* meta = gst_buffer_get_pickdetect_meta(last);
  fail_unless(meta && meta->n_instances == kBoxes.size());
  for (guint i = 0; i < meta->n_instances; i++) {
    const GstPickDetectInstance& in = meta->instances[i];
    fail_unless(in.calibrated && in.track_id != 0 && in.frames_seen == 3);
    fail_unless(std::abs(in.world_velocity_x - 60.0) < 3.0 && std::abs(in.world_velocity_y) < 3.0,
                "box at (%.1f, %.1f) mm: expected (60, 0) mm/s on the plane, got (%.2f, %.2f) "
                "(%.1f, %.1f px/s in the frame)",
                in.world_x, in.world_y, in.world_velocity_x, in.world_velocity_y, in.velocity_x,
                in.velocity_y);
  }
  gst_buffer_unref(last);
  gst_harness_teardown(h);
}
GST_END_TEST;

GST_START_TEST(test_json_lines_match_the_metas) {
  const Cell cell;
  const cv::Mat box = box_picture();
  const cv::Mat frame = cs::render_boxes(cell.camera, cell.rays, box, kBoxes);
  const cv::Mat empty = cs::render_boxes(cell.camera, cell.rays, box, {});
  GstBuffer* annotated = detect(cell, frame);
  GstBuffer* nothing = detect(cell, empty);
  GST_BUFFER_PTS(nothing) = GST_SECOND;
  const GstPickDetectMeta* meta = gst_buffer_get_pickdetect_meta(annotated);
  fail_unless(meta && meta->n_instances == kBoxes.size());
  fail_unless_equals_int(gst_buffer_get_pickdetect_meta(nothing)->n_instances, 0);

  // Without add-empty-results the empty frame gives no line; with it, an empty list.
  const std::vector<std::string> lines = json_lines({annotated, nothing}, frame.size(), false);
  fail_unless_equals_int(lines.size(), 1);
  const std::vector<std::string> all = json_lines({annotated, nothing}, frame.size(), true);
  fail_unless_equals_int(all.size(), 2);
  fail_unless(all[0] == lines[0]);

  for (const std::string& line : all)
    fail_unless(line.back() == '\n' && line.find('\n') == line.size() - 1, "one line per frame");
  JsonParser* parser = json_parser_new();
  GError* error = nullptr;
  fail_unless(json_parser_load_from_data(parser, lines[0].c_str(), -1, &error), "%s",
              error ? error->message : "");
  JsonObject* root = json_node_get_object(json_parser_get_root(parser));
  fail_unless_equals_int(json_object_get_int_member(root, "frame"), 0);
  fail_unless_equals_int(json_object_get_int_member(root, "pts"), 0);
  fail_unless_equals_int(json_object_get_int_member(root, "duration"), GST_SECOND / 10);
  fail_unless(json_object_get_null_member(root, "dts"));
  fail_unless_equals_int(json_object_get_int_member(root, "width"), frame.cols);
  fail_unless_equals_int(json_object_get_int_member(root, "height"), frame.rows);
  JsonArray* instances = json_object_get_array_member(root, "instances");
  fail_unless_equals_int(json_array_get_length(instances), meta->n_instances);
  for (guint i = 0; i < meta->n_instances; i++) {
    const GstPickDetectInstance& in = meta->instances[i];
    JsonObject* o = json_array_get_object_element(instances, i);
    fail_unless_equals_string(json_object_get_string_member(o, "model"), in.model_name);
    fail_unless_equals_string(json_object_get_string_member(o, "view"), in.view_name);
    check_number(o, "center_x", in.center_x);
    check_number(o, "center_y", in.center_y);
    check_number(o, "angle", in.angle);
    check_number(o, "scale", in.scale);
    check_number(o, "score", in.score);
    fail_unless_equals_int(json_object_get_int_member(o, "matches"), in.matches);
    check_number(o, "visibility", in.visibility);
    fail_unless(json_object_get_boolean_member(o, "covered") == static_cast<bool>(in.covered));
    fail_unless(json_object_get_boolean_member(o, "pickable") == static_cast<bool>(in.pickable));
    fail_unless_equals_int(json_object_get_int_member(o, "pick_order"), in.pick_order);
    check_number(o, "grasp_x", in.grasp_x);
    check_number(o, "grasp_y", in.grasp_y);
    check_number(o, "grasp_angle", in.grasp_angle);
    check_points(o, "points", in.points, in.n_points);
    check_points(o, "outline", in.outline, in.n_outline);
    check_number(o, "height", in.height);
    fail_unless(json_object_get_boolean_member(o, "calibrated") && in.calibrated);
    check_number(o, "world_x", in.world_x);
    check_number(o, "world_y", in.world_y);
    check_number(o, "world_angle", in.world_angle);
    check_number(o, "grasp_world_x", in.grasp_world_x);
    check_number(o, "grasp_world_y", in.grasp_world_y);
    check_points(o, "world_outline", in.world_outline, in.n_world_outline);
    // Tracking is on by default: the track fields, and the velocity on the plane.
    fail_unless(in.track_id != 0, "tracking is on by default: every instance has a track id");
    fail_unless_equals_int(json_object_get_int_member(o, "track_id"), in.track_id);
    fail_unless_equals_int(json_object_get_int_member(o, "first_seen"), in.first_seen);
    fail_unless_equals_int(json_object_get_int_member(o, "frames_seen"), in.frames_seen);
    check_number(o, "velocity_x", in.velocity_x);
    check_number(o, "velocity_y", in.velocity_y);
    fail_unless(json_object_get_boolean_member(o, "tracked") == static_cast<bool>(in.tracked));
    check_number(o, "world_velocity_x", in.world_velocity_x);
    check_number(o, "world_velocity_y", in.world_velocity_y);
  }
  g_object_unref(parser);

  parser = json_parser_new();
  fail_unless(json_parser_load_from_data(parser, all[1].c_str(), -1, nullptr));
  root = json_node_get_object(json_parser_get_root(parser));
  fail_unless_equals_int(json_object_get_int_member(root, "frame"), 1);
  fail_unless_equals_int(json_object_get_int_member(root, "pts"), GST_SECOND);
  fail_unless_equals_int(json_array_get_length(json_object_get_array_member(root, "instances")), 0);
  g_object_unref(parser);
  gst_buffer_unref(annotated);
  gst_buffer_unref(nothing);
}
GST_END_TEST;

/// Starts `launch` to PAUSED; the error message posted (empty when it started), and the text
/// of any warning posted meanwhile in `warning`.
std::string start_error(const std::string& launch, std::string* warning = nullptr) {
  GstElement* pipeline = gst_parse_launch(launch.c_str(), nullptr);
  fail_unless(pipeline != nullptr);
  gst_element_set_state(pipeline, GST_STATE_PAUSED);
  std::string text;
  GstBus* bus = gst_element_get_bus(pipeline);
  for (;;) {
    GstMessage* m = gst_bus_timed_pop_filtered(bus, 5 * GST_SECOND,
                                               static_cast<GstMessageType>(GST_MESSAGE_ERROR |
                                                                           GST_MESSAGE_WARNING |
                                                                           GST_MESSAGE_ASYNC_DONE));
    if (!m)
      break;
    const GstMessageType type = GST_MESSAGE_TYPE(m);
    if (type == GST_MESSAGE_ERROR || type == GST_MESSAGE_WARNING) {
      GError* error = nullptr;
      if (type == GST_MESSAGE_ERROR)
        gst_message_parse_error(m, &error, nullptr);
      else
        gst_message_parse_warning(m, &error, nullptr);
      if (type == GST_MESSAGE_ERROR)
        text = error->message;
      else if (warning)
        *warning += error->message;
      g_error_free(error);
    }
    gst_message_unref(m);
    if (type != GST_MESSAGE_WARNING)
      break;
  }
  gst_object_unref(bus);
  gst_element_set_state(pipeline, GST_STATE_NULL);
  gst_object_unref(pipeline);
  return text;
}

GST_START_TEST(test_bad_calibration_fails_the_start_naming_the_file) {
  const Cell cell;
  const std::string src =
      "videotestsrc num-buffers=1 ! video/x-raw,format=GRAY8,width=800,height=600 ! ";
  const std::string tail = " ! fakesink";
  const std::string model = "pickdetect model=\"" + cell.model + "\" calibration=";

  std::string e = start_error(src + model + "\"" + cell.dir + "/none.yml\"" + tail);
  fail_unless(e.find(cell.dir + "/none.yml") != std::string::npos &&
                  e.find("does not exist") != std::string::npos,
              "got: %s", e.c_str());

  const std::string bad = cell.dir + "/bad.yml";
  std::ofstream(bad) << "%YAML:1.0\nkind: camera-plane\nimage_width: 800\nimage_height: 600\n";
  e = start_error(src + model + "\"" + bad + "\"" + tail);
  fail_unless(e.find(bad) != std::string::npos && e.find("camera_matrix") != std::string::npos,
              "got: %s", e.c_str());
  g_remove(bad.c_str());

  // Made for 800x600, given 640x480.
  e = start_error("videotestsrc num-buffers=1 ! video/x-raw,format=GRAY8,width=640,height=480 ! " +
                  model + "\"" + cell.calibration + "\"" + tail);
  fail_unless(e.find("800x600") != std::string::npos && e.find("640x480") != std::string::npos,
              "got: %s", e.c_str());

  // And a good one starts, with no warning.
  std::string warning;
  e = start_error(src + model + "\"" + cell.calibration + "\"" + tail, &warning);
  fail_unless(e.empty() && warning.empty(), "got: %s / %s", e.c_str(), warning.c_str());

  // A bare homography cannot raise the plane to the model's height: it starts, and says so.
  const std::string flat = cell.dir + "/flat.yml";
  pickdetect::Calibration homography;
  homography.kind = pickdetect::CalibrationKind::Homography;
  homography.image_size = {800, 600};
  pickdetect::save_calibration(homography, flat);
  e = start_error(src + model + "\"" + flat + "\"" + tail, &warning);
  g_remove(flat.c_str());
  fail_unless(e.empty(), "got: %s", e.c_str());
  fail_unless(warning.find("height of 40 mm is not accounted for") != std::string::npos,
              "warning: %s", warning.c_str());
}
GST_END_TEST;

Suite* robot_suite() {
  Suite* s = suite_create("robot");
  TCase* tc = pickdetect::test_harness::add_tcase(s, "robot", 600);
  tcase_add_test(tc, test_world_positions_within_half_a_millimetre);
  tcase_add_test(tc, test_velocity_on_the_plane_in_millimetres_per_second);
  tcase_add_test(tc, test_json_lines_match_the_metas);
  tcase_add_test(tc, test_bad_calibration_fails_the_start_naming_the_file);
  return s;
}

} // namespace

GST_CHECK_MAIN(robot);
