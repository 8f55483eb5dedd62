// SPDX-License-Identifier: LGPL-2.1-or-later
// Frame threads (the `threads` property): several frames detected at once must come out in
// their order, with the same instances as one frame at a time, events kept in order with the
// frames around them, nothing left behind by flushes, EOS or stops, and the added latency
// reported.
// OpenCV comes before gstcheck.h, whose `fail` macro would clash with OpenCV's identifiers.
#include "common/scene.hpp"
#include "common/video-buffer.hpp"

#include <opencv2/imgcodecs.hpp>

#include <gst/check/gstcheck.h>
#include <gst/check/gstharness.h>

#include "../support/harness.hpp"
#include <gst/pickdetect/pickdetect-meta.h>
#include <gst/video/video.h>

#include <cstring>
#include <mutex>
#include <string>
#include <vector>

namespace {

using pickdetect::test_scene::Pose;

using pickdetect::test_harness::kBoxPath;
constexpr GstClockTime kFrameDuration = GST_SECOND / 30;

const cv::Mat& box_picture() {
  static const cv::Mat picture = cv::imread(kBoxPath, cv::IMREAD_GRAYSCALE);
  return picture;
}

/// Frame `i`: 1 + i % 3 boxes at poses that change with i, so every frame's result differs.
cv::Mat frame_picture(int i, cv::Size size) {
  cv::Mat scene = pickdetect::test_scene::plain_background(size, 110, 100 + i);
  std::vector<Pose> poses;
  for (int k = 0; k <= i % 3; k++) {
    const float x = size.width * (0.2f + 0.3f * k) + 7.f * i;
    const float y = size.height * (0.3f + 0.2f * (k % 2)) + 5.f * i;
    poses.push_back(Pose{cv::Point2f(x, y), 40.0 * i + 70.0 * k, 0.45 + 0.03 * k});
  }
  pickdetect::test_scene::paste(scene, box_picture(), poses);
  return scene;
}

GstBuffer* gray_buffer(const cv::Mat& grey, int index) {
  GstBuffer* buffer = pickdetect::tools::video_buffer(grey, "GRAY8");
  GST_BUFFER_PTS(buffer) = kFrameDuration * index;
  GST_BUFFER_DURATION(buffer) = kFrameDuration;
  return buffer;
}

std::string gray_caps(cv::Size size) {
  return pickdetect::tools::caps_string("GRAY8", size);
}

GstHarness* threads_harness(int threads) {
  return pickdetect::test_harness::pickdetect_harness("model", kBoxPath.c_str(), "threads",
                                                      threads);
}

/// What one frame's metadata says: its timestamp and instance centres, in the meta's order.
struct FrameResult {
  GstClockTime pts = GST_CLOCK_TIME_NONE;
  std::vector<double> values; ///< model name length, x, y, angle of each instance.
};

FrameResult read_result(GstBuffer* buffer) {
  FrameResult r;
  r.pts = GST_BUFFER_PTS(buffer);
  const GstPickDetectMeta* meta = gst_buffer_get_pickdetect_meta(buffer);
  fail_unless(meta != nullptr, "a buffer came out without its GstPickDetectMeta");
  for (guint i = 0; i < gst_pickdetect_meta_get_n_instances(meta); i++) {
    const GstPickDetectInstance* in = gst_pickdetect_meta_get_instance(meta, i);
    r.values.insert(r.values.end(), {static_cast<double>(std::strlen(in->model_name)), in->center_x,
                                     in->center_y, in->angle});
  }
  return r;
}

/// Pushes `n` frames then EOS through pickdetect with `threads`; the frames that came out.
std::vector<FrameResult> run_frames(int threads, int n, cv::Size size) {
  GstHarness* h = threads_harness(threads);
  gst_harness_set_src_caps_str(h, gray_caps(size).c_str());
  for (int i = 0; i < n; i++)
    fail_unless_equals_int(gst_harness_push(h, gray_buffer(frame_picture(i, size), i)),
                           GST_FLOW_OK);
  fail_unless(gst_harness_push_event(h, gst_event_new_eos()));
  std::vector<FrameResult> out;
  while (GstBuffer* b = gst_harness_try_pull(h)) {
    out.push_back(read_result(b));
    gst_buffer_unref(b);
  }
  gst_harness_teardown(h);
  return out;
}

} // namespace

GST_START_TEST(test_threads_same_results_in_order) {
  const cv::Size size(640, 480);
  constexpr int kFrames = 7;
  const std::vector<FrameResult> one = run_frames(1, kFrames, size);
  fail_unless_equals_int(static_cast<int>(one.size()), kFrames);
  int found = 0;
  for (const FrameResult& r : one)
    found += static_cast<int>(r.values.size() / 4);
  fail_unless(found >= kFrames, "the frames should show boxes (found %d instances)", found);

  for (int threads : {2, 3, 0}) {
    const std::vector<FrameResult> many = run_frames(threads, kFrames, size);
    fail_unless_equals_int(static_cast<int>(many.size()), kFrames);
    for (int i = 0; i < kFrames; i++) {
      fail_unless_equals_uint64(many[i].pts, kFrameDuration * i);
      fail_unless(many[i].values == one[i].values,
                  "threads=%d: frame %d has other instances than with threads=1", threads, i);
    }
  }
}
GST_END_TEST;

namespace {

/// Everything reaching the harness's sink pad, in order: "B<index>" for a buffer, the event's
/// name otherwise (caps events with their width).
struct Sequence {
  std::mutex lock;
  std::vector<std::string> items;
};

GstPadProbeReturn record_item(GstPad*, GstPadProbeInfo* info, gpointer data) {
  auto* seq = static_cast<Sequence*>(data);
  std::string item;
  if (GST_PAD_PROBE_INFO_TYPE(info) & GST_PAD_PROBE_TYPE_BUFFER) {
    item = "B" + std::to_string(GST_BUFFER_PTS(GST_PAD_PROBE_INFO_BUFFER(info)) / kFrameDuration);
  } else if (GST_PAD_PROBE_INFO_TYPE(info) & GST_PAD_PROBE_TYPE_EVENT_DOWNSTREAM) {
    GstEvent* event = GST_PAD_PROBE_INFO_EVENT(info);
    item = GST_EVENT_TYPE_NAME(event);
    if (GST_EVENT_TYPE(event) == GST_EVENT_CAPS) {
      GstCaps* caps = nullptr;
      gst_event_parse_caps(event, &caps);
      gint width = 0;
      gst_structure_get_int(gst_caps_get_structure(caps, 0), "width", &width);
      item += std::to_string(width);
    }
  }
  if (!item.empty()) {
    std::lock_guard<std::mutex> hold(seq->lock);
    seq->items.push_back(item);
  }
  return GST_PAD_PROBE_OK;
}

std::string joined(const std::vector<std::string>& items) {
  std::string s;
  for (const std::string& i : items)
    s += (s.empty() ? "" : " ") + i;
  return s;
}

} // namespace

GST_START_TEST(test_threads_events_keep_their_place) {
  GstHarness* h = threads_harness(2);
  Sequence seq;
  gst_pad_add_probe(
      h->sinkpad,
      static_cast<GstPadProbeType>(GST_PAD_PROBE_TYPE_BUFFER | GST_PAD_PROBE_TYPE_EVENT_DOWNSTREAM),
      record_item, &seq, nullptr);
  const cv::Size big(640, 480), small(320, 240);
  gst_harness_set_src_caps_str(h, gray_caps(big).c_str());
  for (int i = 0; i < 3; i++)
    fail_unless_equals_int(gst_harness_push(h, gray_buffer(frame_picture(i, big), i)), GST_FLOW_OK);
  // Renegotiation mid-stream: the frames before must go out with the old caps, before the new.
  gst_harness_set_src_caps_str(h, gray_caps(small).c_str());
  for (int i = 3; i < 5; i++)
    fail_unless_equals_int(gst_harness_push(h, gray_buffer(frame_picture(i, small), i)),
                           GST_FLOW_OK);
  fail_unless(gst_harness_push_event(h, gst_event_new_eos()));

  std::vector<std::string> items;
  {
    std::lock_guard<std::mutex> hold(seq.lock);
    for (const std::string& i : seq.items)
      if (i != "stream-start" && i != "segment")
        items.push_back(i);
  }
  const std::string seen = joined(items);
  fail_unless_equals_string(seen.c_str(), "caps640 B0 B1 B2 caps320 B3 B4 eos");
  fail_unless_equals_int(gst_harness_buffers_received(h), 5);
  gst_harness_teardown(h);
}
GST_END_TEST;

GST_START_TEST(test_threads_flush_and_stop_drop_frames) {
  const cv::Size size(640, 480);
  GstHarness* h = threads_harness(3);
  gst_harness_set_src_caps_str(h, gray_caps(size).c_str());
  for (int i = 0; i < 4; i++)
    fail_unless_equals_int(gst_harness_push(h, gray_buffer(frame_picture(i, size), i)),
                           GST_FLOW_OK);
  const guint before = gst_harness_buffers_received(h);
  // At most threads - 1 = 2 frames stay in the works (fewer when they finish quickly).
  fail_unless(before >= 2, "%u of 4 frames out before the flush", before);
  // A flush drops the frames in the works: none of them may come out afterwards.
  fail_unless(gst_harness_push_event(h, gst_event_new_flush_start()));
  fail_unless(gst_harness_push_event(h, gst_event_new_flush_stop(TRUE)));
  GstSegment segment;
  gst_segment_init(&segment, GST_FORMAT_TIME);
  fail_unless(gst_harness_push_event(h, gst_event_new_segment(&segment)));
  for (int i = 10; i < 12; i++)
    fail_unless_equals_int(gst_harness_push(h, gray_buffer(frame_picture(i, size), i)),
                           GST_FLOW_OK);
  fail_unless(gst_harness_push_event(h, gst_event_new_eos()));
  std::vector<GstClockTime> after;
  while (GstBuffer* b = gst_harness_try_pull(h)) {
    after.push_back(GST_BUFFER_PTS(b));
    gst_buffer_unref(b);
  }
  fail_unless_equals_int(static_cast<int>(after.size()), 2 + static_cast<int>(before));
  fail_unless_equals_uint64(after[after.size() - 2], kFrameDuration * 10);
  fail_unless_equals_uint64(after.back(), kFrameDuration * 11);

  // Stopping with frames in the works drops them and joins the threads; starting again works.
  for (int i = 20; i < 22; i++)
    gst_harness_push(h, gray_buffer(frame_picture(i, size), i));
  fail_unless_equals_int(gst_element_set_state(h->element, GST_STATE_NULL),
                         GST_STATE_CHANGE_SUCCESS);
  fail_unless_equals_int(gst_element_set_state(h->element, GST_STATE_PLAYING),
                         GST_STATE_CHANGE_SUCCESS);
  gst_harness_teardown(h);
}
GST_END_TEST;

GST_START_TEST(test_threads_latency) {
  GstClockTime latency[2] = {0, 0};
  int index = 0;
  for (int threads : {1, 3}) {
    GstHarness* h = threads_harness(threads);
    gst_harness_set_upstream_latency(h, 10 * GST_MSECOND);
    gst_harness_set_src_caps_str(h, gray_caps(cv::Size(320, 240)).c_str());
    gst_harness_push(h, gray_buffer(frame_picture(0, cv::Size(320, 240)), 0));
    latency[index++] = gst_harness_query_latency(h);
    gst_harness_teardown(h);
  }
  fail_unless_equals_uint64(latency[0], 10 * GST_MSECOND);
  fail_unless_equals_uint64(latency[1], 10 * GST_MSECOND + 2 * kFrameDuration);
}
GST_END_TEST;

GST_START_TEST(test_threads_property) {
  GstElement* e = gst_element_factory_make("pickdetect", nullptr);
  fail_unless(e != nullptr);
  gint threads = -1;
  g_object_get(e, "threads", &threads, nullptr);
  fail_unless_equals_int(threads, 1); // One frame at a time unless asked: no added latency.
  GParamSpec* spec = g_object_class_find_property(G_OBJECT_GET_CLASS(e), "threads");
  fail_unless(spec != nullptr);
  fail_unless_equals_int(G_PARAM_SPEC_INT(spec)->minimum, 0);
  fail_unless(spec->flags & GST_PARAM_MUTABLE_READY);
  gst_object_unref(e);
}
GST_END_TEST;

static Suite* threads_suite(void) {
  Suite* s = suite_create("pickdetect-threads");
  TCase* tc = pickdetect::test_harness::add_tcase(s, "threads");
  tcase_add_test(tc, test_threads_property);
  tcase_add_test(tc, test_threads_same_results_in_order);
  tcase_add_test(tc, test_threads_events_keep_their_place);
  tcase_add_test(tc, test_threads_flush_and_stop_drop_frames);
  tcase_add_test(tc, test_threads_latency);
  return s;
}

GST_CHECK_MAIN(threads);
