// SPDX-License-Identifier: LGPL-2.1-or-later
// Tracking in the element (the `tracking`, `track-timeout` and `count-line` properties): ids
// stable across frames in every place they are written, the same with frame threads, counts,
// and what the stream events do to the tracks (docs/tracking.md).
// OpenCV comes before gstcheck.h, whose `fail` macro would clash with OpenCV's identifiers.
#include "common/scene.hpp"

#include <opencv2/imgcodecs.hpp>

#include <gst/check/gstcheck.h>
#include <gst/check/gstharness.h>

#include "../support/harness.hpp"
#include <gst/pickdetect/pickdetect-meta.h>
#include <gst/video/video.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

namespace {

using pickdetect::test_scene::Pose;

using pickdetect::test_harness::kBoxPath;
constexpr GstClockTime kFrame = GST_SECOND / 30;
const cv::Size kSize(640, 480);

/// Frame i of a belt: two boxes riding right 20 px a frame.
GstBuffer* belt_frame(int i, GstClockTime pts, cv::Size size = kSize) {
  static const cv::Mat picture = cv::imread(kBoxPath, cv::IMREAD_GRAYSCALE);
  cv::Mat scene = pickdetect::test_scene::plain_background(size, 110, 100 + i);
  const float x = 130.f + 20.f * i;
  pickdetect::test_scene::paste(
      scene, picture, {Pose{{x, 130.f}, 10.0, 0.45}, Pose{{x + 60.f, 340.f}, 200.0, 0.45}});
  GstBuffer* buffer = gst_buffer_new_allocate(nullptr, scene.total(), nullptr);
  GstMapInfo map;
  fail_unless(gst_buffer_map(buffer, &map, GST_MAP_WRITE));
  for (int y = 0; y < scene.rows; y++)
    std::memcpy(map.data + static_cast<size_t>(y) * scene.cols, scene.ptr(y), scene.cols);
  gst_buffer_unmap(buffer, &map);
  GST_BUFFER_PTS(buffer) = pts;
  GST_BUFFER_DURATION(buffer) = kFrame;
  return buffer;
}

std::string caps(cv::Size size = kSize) {
  return "video/x-raw,format=GRAY8,width=" + std::to_string(size.width) +
         ",height=" + std::to_string(size.height) + ",framerate=30/1";
}

/// The track ids of a buffer's instances (meta order), checking that the ROI metas and their
/// params carry the same ids.
std::vector<guint64> track_ids(GstBuffer* buffer) {
  const GstPickDetectMeta* meta = gst_buffer_get_pickdetect_meta(buffer);
  fail_unless(meta != nullptr);
  std::vector<guint64> ids;
  for (guint k = 0; k < meta->n_instances; k++)
    ids.push_back(meta->instances[k].track_id);
  guint n = 0;
  for (GstVideoRegionOfInterestMeta* roi : pickdetect::test_harness::roi_metas(buffer)) {
    const GstStructure* s = pickdetect::test_harness::roi_param(roi);
    const GstStructure* object = gst_video_region_of_interest_meta_get_param(roi, "object_id");
    guint64 id = 0;
    gint object_id = -1;
    fail_unless(s && gst_structure_get_uint64(s, "track-id", &id), "pick-instance has no track-id");
    fail_unless(object && gst_structure_get_int(object, "id", &object_id), "no object_id param");
    fail_unless_equals_uint64(id, ids.at(n));
    fail_unless_equals_int(roi->id, static_cast<gint>(id));
    fail_unless_equals_int(object_id, static_cast<gint>(id));
    n++;
  }
  fail_unless_equals_int(n, ids.size());
  return ids;
}

/// The "pickdetect-track" end messages on the bus: their reasons.
std::vector<std::string> ended(GstBus* bus) {
  std::vector<std::string> reasons;
  while (GstMessage* msg = gst_bus_pop_filtered(bus, GST_MESSAGE_ELEMENT)) {
    const GstStructure* s = gst_message_get_structure(msg);
    if (gst_structure_has_name(s, "pickdetect-track") &&
        g_strcmp0(gst_structure_get_string(s, "event"), "end") == 0)
      reasons.emplace_back(gst_structure_get_string(s, "reason"));
    gst_message_unref(msg);
  }
  return reasons;
}

/// Pushes frames [from, to) and returns the ids of the last, all frames needing two instances.
std::vector<guint64> run_belt(GstHarness* h, int from, int to, GstClockTime base = 0) {
  std::vector<guint64> ids;
  for (int i = from; i < to; i++) {
    GstBuffer* out = gst_harness_push_and_pull(h, belt_frame(i, base + kFrame * i));
    fail_unless(out != nullptr);
    ids = track_ids(out);
    fail_unless_equals_int(ids.size(), 2);
    gst_buffer_unref(out);
  }
  return ids;
}

} // namespace

GST_START_TEST(test_ids_stable_and_velocity) {
  // Frame threads detect several frames at once; the tracks must follow the frames in their
  // order all the same. All frames are pushed, then end of stream, before any is pulled:
  // threads > 1 hold frames back.
  for (int threads : {1, 2}) {
    GstHarness* h =
        pickdetect::test_harness::pickdetect_harness("model", kBoxPath.c_str(), "threads", threads);
    gst_harness_set_src_caps_str(h, caps().c_str());
    for (int i = 0; i < 8; i++)
      fail_unless_equals_int(gst_harness_push(h, belt_frame(i, kFrame * i)), GST_FLOW_OK);
    fail_unless(gst_harness_push_event(h, gst_event_new_eos())); // drains the frame threads
    GstBuffer* out = gst_harness_pull(h);
    const std::vector<guint64> start = track_ids(out);
    fail_unless_equals_int(start.size(), 2);
    fail_unless(start[0] != start[1] && start[0] > 0 && start[1] > 0);
    for (int i = 1; i < 8; i++) {
      gst_buffer_unref(out);
      out = gst_harness_pull(h);
      fail_unless(out != nullptr, "threads=%d: frame %d did not come out", threads, i);
      fail_unless_equals_uint64(GST_BUFFER_PTS(out), kFrame * i);
      fail_unless(track_ids(out) == start, "threads=%d: ids changed at frame %d", threads, i);
    }
    const GstPickDetectMeta* meta = gst_buffer_get_pickdetect_meta(out);
    for (guint k = 0; k < meta->n_instances; k++) {
      const GstPickDetectInstance& in = meta->instances[k];
      fail_unless(std::fabs(in.velocity_x - 600.0) < 30.0 && std::fabs(in.velocity_y) < 30.0,
                  "velocity (%f, %f), expected (600, 0) px/s", in.velocity_x, in.velocity_y);
      fail_unless_equals_int(in.frames_seen, 8);
      fail_unless_equals_uint64(in.first_seen, 0);
      fail_unless(!in.tracked);
    }
    fail_unless(meta->has_motion && std::fabs(meta->motion_x - 600.0) < 30.0,
                "belt motion %d (%f, %f)", meta->has_motion, meta->motion_x, meta->motion_y);
    gst_buffer_unref(out);
    gst_harness_teardown(h);
  }
}
GST_END_TEST;

GST_START_TEST(test_tracking_off_gives_frame_by_frame) {
  GstHarness* h =
      pickdetect::test_harness::pickdetect_harness("model", kBoxPath.c_str(), "tracking", FALSE);
  gst_harness_set_src_caps_str(h, caps().c_str());
  GstBuffer* out = gst_harness_push_and_pull(h, belt_frame(0, 0));
  const GstPickDetectMeta* meta = gst_buffer_get_pickdetect_meta(out);
  fail_unless_equals_int(meta->n_instances, 2);
  for (guint k = 0; k < meta->n_instances; k++)
    fail_unless_equals_uint64(meta->instances[k].track_id, 0);
  fail_unless(!meta->has_motion);
  GstVideoRegionOfInterestMeta* roi = gst_buffer_get_video_region_of_interest_meta(out);
  fail_unless(gst_video_region_of_interest_meta_get_param(roi, "object_id") == nullptr);
  gst_buffer_unref(out);
  gst_harness_teardown(h);
}
GST_END_TEST;

GST_START_TEST(test_stream_events_reset_or_keep) {
  GstHarness* h = pickdetect::test_harness::pickdetect_harness("model", kBoxPath.c_str());
  GstBus* bus = gst_bus_new();
  gst_element_set_bus(h->element, bus);
  gst_harness_set_src_caps_str(h, caps().c_str());
  std::vector<guint64> ids = run_belt(h, 0, 3);
  ended(bus);

  // A flush (a flushing seek) ends every track; new ids, greater than any before.
  fail_unless(gst_harness_push_event(h, gst_event_new_flush_start()));
  fail_unless(gst_harness_push_event(h, gst_event_new_flush_stop(TRUE)));
  fail_unless(ended(bus) == std::vector<std::string>({"reset", "reset"}));
  GstSegment segment;
  gst_segment_init(&segment, GST_FORMAT_TIME);
  fail_unless(gst_harness_push_event(h, gst_event_new_segment(&segment)));
  std::vector<guint64> after = run_belt(h, 3, 5);
  fail_unless(after[0] > ids[1] && after[1] > ids[1], "ids reused after a flush");
  ids = after;

  // A new segment: running times start again, the tracks too.
  fail_unless(gst_harness_push_event(h, gst_event_new_segment(&segment)));
  fail_unless_equals_int(ended(bus).size(), 2);
  after = run_belt(h, 5, 7);
  fail_unless(after[0] > ids[1]);
  ids = after;

  // The same models set again while playing: the tracks of models still there go on.
  g_object_set(h->element, "model", kBoxPath.c_str(), nullptr);
  fail_unless(run_belt(h, 7, 9) == ids, "tracks ended by a model set that kept their model");
  fail_unless(ended(bus).empty());

  // A gap in the timestamps beyond the timeout ends the tracks (timeout), then new ones.
  after = run_belt(h, 9, 11, GST_SECOND);
  fail_unless(after[0] > ids[1]);
  fail_unless_equals_int(ended(bus).size(), 2);
  ids = after;

  // Tracking turned off and on again: the tracks end, the next get new ids.
  g_object_set(h->element, "tracking", FALSE, nullptr);
  GstBuffer* out = gst_harness_push_and_pull(h, belt_frame(11, GST_SECOND + kFrame * 11));
  fail_unless_equals_uint64(gst_buffer_get_pickdetect_meta(out)->instances[0].track_id, 0);
  gst_buffer_unref(out);
  fail_unless(ended(bus) == std::vector<std::string>({"reset", "reset"}));
  g_object_set(h->element, "tracking", TRUE, nullptr);
  after = run_belt(h, 12, 13, GST_SECOND);
  fail_unless(after[0] > ids[1]);
  ids = after;

  // New caps of another size (the harness sends a new segment with them) end the tracks.
  const cv::Size larger(704, 480);
  gst_harness_set_src_caps_str(h, caps(larger).c_str());
  GstBuffer* big = gst_harness_push_and_pull(h, belt_frame(14, GST_SECOND + kFrame * 14, larger));
  const std::vector<guint64> resized = track_ids(big);
  gst_buffer_unref(big);
  fail_unless(resized.size() == 2 && resized[0] > ids[1], "tracks kept across a size change");
  fail_unless_equals_int(ended(bus).size(), 2);

  gst_element_set_bus(h->element, nullptr);
  gst_object_unref(bus);
  gst_harness_teardown(h);
}
GST_END_TEST;

GST_START_TEST(test_count_line_counts_each_once) {
  // A vertical line the boxes cross (the first at frame ~4, the second at ~1).
  GstHarness* h = pickdetect::test_harness::pickdetect_harness("model", kBoxPath.c_str(),
                                                               "count-line", "220,0,220,480");
  GstBus* bus = gst_bus_new();
  gst_element_set_bus(h->element, bus);
  gst_harness_set_src_caps_str(h, caps().c_str());
  // On its way for 8 frames, then stopped on the far side, jittering by a frame's travel.
  for (int t = 0; t < 12; t++) {
    const int at = t < 8 ? t : 7 + t % 2;
    GstBuffer* out = gst_harness_push_and_pull(h, belt_frame(at, kFrame * t));
    gst_buffer_unref(out);
  }
  std::vector<guint64> counted;
  int last_total = 0;
  while (GstMessage* msg = gst_bus_pop_filtered(bus, GST_MESSAGE_ELEMENT)) {
    const GstStructure* s = gst_message_get_structure(msg);
    if (gst_structure_has_name(s, "pickdetect-count")) {
      guint64 id = 0;
      gint count = 0, total = 0;
      fail_unless(gst_structure_get_uint64(s, "track-id", &id) &&
                  gst_structure_get_int(s, "count", &count) &&
                  gst_structure_get_int(s, "total", &total));
      fail_unless_equals_string(gst_structure_get_string(s, "model"), "box");
      fail_unless_equals_int(count, total);
      fail_unless_equals_int(total, last_total + 1);
      last_total = total;
      counted.push_back(id);
    }
    gst_message_unref(msg);
  }
  fail_unless_equals_int(counted.size(), 2);
  fail_unless(counted[0] != counted[1]);
  gchar* line = nullptr;
  g_object_set(h->element, "count-line", "1,2,3", nullptr); // Malformed: refused, kept.
  g_object_get(h->element, "count-line", &line, nullptr);
  fail_unless_equals_string(line, "220,0,220,480");
  g_free(line);
  gst_element_set_bus(h->element, nullptr);
  gst_object_unref(bus);
  gst_harness_teardown(h);
}
GST_END_TEST;

GST_START_TEST(test_qos_drops_keep_tracks) {
  // Frames the base transform's QoS drops (a sink reporting the stream late) never reach the
  // tracker: the tracks bridge them like a gap in the timestamps, keeping their ids.
  GstHarness* h = pickdetect::test_harness::pickdetect_harness("model", kBoxPath.c_str());
  gst_harness_set_src_caps_str(h, caps().c_str());
  const std::vector<guint64> ids = run_belt(h, 0, 3);
  // Frame 2 reached the sink one frame late: frames due before about two frames later are
  // dropped.
  fail_unless(gst_harness_push_upstream_event(
      h, gst_event_new_qos(GST_QOS_TYPE_UNDERFLOW, 2.0, static_cast<GstClockTimeDiff>(kFrame),
                           2 * kFrame)));
  int out_count = 0;
  std::vector<guint64> last;
  for (int i = 3; i < 9; i++) {
    fail_unless_equals_int(gst_harness_push(h, belt_frame(i, kFrame * i)), GST_FLOW_OK);
    while (GstBuffer* out = gst_harness_try_pull(h)) {
      last = track_ids(out);
      fail_unless(last == ids, "ids changed across frames dropped by QoS");
      out_count++;
      gst_buffer_unref(out);
    }
  }
  fail_unless(out_count > 0 && out_count < 6, "%d of 6 frames came out: QoS dropped none or all",
              out_count);
  gst_harness_teardown(h);
}
GST_END_TEST;

GST_START_TEST(test_timestamps_going_back_reset_tracks) {
  // A frame stamped before the previous one (a source restarted without a new segment): the
  // motion between them means nothing, so the tracks end and the next get new ids.
  GstHarness* h = pickdetect::test_harness::pickdetect_harness("model", kBoxPath.c_str());
  GstBus* bus = gst_bus_new();
  gst_element_set_bus(h->element, bus);
  gst_harness_set_src_caps_str(h, caps().c_str());
  const std::vector<guint64> ids = run_belt(h, 0, 4);
  ended(bus);
  GstBuffer* out = gst_harness_push_and_pull(h, belt_frame(4, kFrame)); // after frame 3's
  const std::vector<guint64> after = track_ids(out);
  gst_buffer_unref(out);
  fail_unless_equals_int(after.size(), 2);
  fail_unless(after[0] > ids[1] && after[1] > ids[1], "tracks kept across time going back");
  fail_unless(ended(bus) == std::vector<std::string>({"reset", "reset"}));
  gst_element_set_bus(h->element, nullptr);
  gst_object_unref(bus);
  gst_harness_teardown(h);
}
GST_END_TEST;

/// The "pickdetect" frame messages on the bus, in order.
std::vector<GstStructure*> frame_messages(GstBus* bus) {
  std::vector<GstStructure*> out;
  while (GstMessage* msg = gst_bus_pop_filtered(bus, GST_MESSAGE_ELEMENT)) {
    const GstStructure* s = gst_message_get_structure(msg);
    if (gst_structure_has_name(s, "pickdetect"))
      out.push_back(gst_structure_copy(s));
    gst_message_unref(msg);
  }
  return out;
}

/// The instance centres of a frame message.
std::vector<cv::Point2d> centres(const GstStructure* s) {
  std::vector<cv::Point2d> out;
  const GValue* list = gst_structure_get_value(s, "instances");
  for (guint k = 0; list && k < gst_value_list_get_size(list); k++) {
    const GstStructure* in = gst_value_get_structure(gst_value_list_get_value(list, k));
    cv::Point2d c;
    gst_structure_get_double(in, "center-x", &c.x);
    gst_structure_get_double(in, "center-y", &c.y);
    out.push_back(c);
  }
  std::sort(out.begin(), out.end(),
            [](const cv::Point2d& a, const cv::Point2d& b) { return a.x < b.x; });
  return out;
}

/// Pushes frames i = 0, 1, ... (belt_frame(frame_index(i))) through a harness with
/// `tracking`, the frame messages back.
template <typename FrameIndex>
std::vector<GstStructure*> run_frames(gboolean tracking, int n, FrameIndex frame_index) {
  GstHarness* h =
      pickdetect::test_harness::pickdetect_harness("model", kBoxPath.c_str(), "tracking", tracking);
  GstBus* bus = gst_bus_new();
  gst_element_set_bus(h->element, bus);
  gst_harness_set_src_caps_str(h, caps().c_str());
  for (int i = 0; i < n; i++)
    gst_buffer_unref(gst_harness_push_and_pull(h, belt_frame(frame_index(i), kFrame * i)));
  std::vector<GstStructure*> messages = frame_messages(bus);
  gst_element_set_bus(h->element, nullptr);
  gst_object_unref(bus);
  gst_harness_teardown(h);
  fail_unless_equals_int(messages.size(), n);
  return messages;
}

void free_all(std::vector<GstStructure*>& messages) {
  for (GstStructure* s : messages)
    gst_structure_free(s);
  messages.clear();
}

GST_START_TEST(test_still_frames_extract_no_features) {
  // The same picture three times: after the first, nothing is extracted and the instances are
  // the first frame's. Without tracking every frame is detected whole, as before.
  std::vector<GstStructure*> on = run_frames(TRUE, 3, [](int) { return 0; });
  gint extracted = -1, reused = -1;
  fail_unless(gst_structure_get_int(on[0], "features-extracted", &extracted));
  fail_unless(extracted > 100, "first frame: %d features extracted", extracted);
  for (int i = 1; i < 3; i++) {
    fail_unless(gst_structure_get_int(on[i], "features-extracted", &extracted));
    fail_unless(gst_structure_get_int(on[i], "features-reused", &reused));
    fail_unless_equals_int(extracted, 0);
    fail_unless(reused > 100, "frame %d: %d features reused", i, reused);
    fail_unless(centres(on[i]) == centres(on[0]));
  }
  std::vector<GstStructure*> off = run_frames(FALSE, 2, [](int) { return 0; });
  fail_if(gst_structure_has_field(off[1], "features-extracted"));
  fail_unless(centres(off[1]) == centres(on[1]));
  free_all(on);
  free_all(off);
}
GST_END_TEST;

GST_START_TEST(test_belt_found_by_motion_as_frame_by_frame) {
  // Two boxes riding 20 px a frame: after the first frame, SIFT runs on a small share of the
  // frame at most, and the centres are those of frame-by-frame detection within 0.1 px.
  std::vector<GstStructure*> on = run_frames(TRUE, 5, [](int i) { return i; });
  std::vector<GstStructure*> off = run_frames(FALSE, 5, [](int i) { return i; });
  for (int i = 0; i < 5; i++) {
    const std::vector<cv::Point2d> a = centres(on[i]), b = centres(off[i]);
    fail_unless_equals_int(a.size(), 2);
    fail_unless_equals_int(b.size(), 2);
    for (size_t k = 0; k < a.size(); k++)
      fail_unless(cv::norm(a[k] - b[k]) <= 0.1, "frame %d: (%.3f, %.3f) against (%.3f, %.3f)", i,
                  a[k].x, a[k].y, b[k].x, b[k].y);
    if (i == 0)
      continue;
    gdouble share = 1.0;
    fail_unless(gst_structure_get_double(on[i], "extracted-share", &share));
    fail_unless(share < 0.25, "frame %d: SIFT ran on %.2f of the frame", i, share);
  }
  free_all(on);
  free_all(off);
}
GST_END_TEST;

static Suite* tracking_suite(void) {
  Suite* s = suite_create("tracking");
  TCase* tc = pickdetect::test_harness::add_tcase(s, "tracking", 300);
  tcase_add_test(tc, test_ids_stable_and_velocity);
  tcase_add_test(tc, test_tracking_off_gives_frame_by_frame);
  tcase_add_test(tc, test_stream_events_reset_or_keep);
  tcase_add_test(tc, test_count_line_counts_each_once);
  tcase_add_test(tc, test_qos_drops_keep_tracks);
  tcase_add_test(tc, test_timestamps_going_back_reset_tracks);
  tcase_add_test(tc, test_still_frames_extract_no_features);
  tcase_add_test(tc, test_belt_found_by_motion_as_frame_by_frame);
  return s;
}

GST_CHECK_MAIN(tracking);
