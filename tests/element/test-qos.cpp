// SPDX-License-Identifier: LGPL-2.1-or-later
// Quality of service: a live source that outruns the element. appsrc (is-live) pushes 1280x960
// frames with ten boxes in real time at 30 frames per second, far faster than SIFT detection;
// fakesink syncs on the clock and sends QoS events upstream. The element must drop the frames
// that are already late (the base transform's QoS: a QoS message, no detection) instead of
// queueing them up, so that the latency stays bounded by about one frame's processing time.
//
//   test-qos            the element as it is (QoS on by default): must pass
//   test-qos --no-qos   the same with pickdetect qos=false: every frame is processed, the
//                       latency grows with the stream, and the test must fail (meson runs it
//                       with should_fail, so that this test is shown able to fail)
//
// OpenCV comes before gstcheck.h, whose `fail` macro would clash with OpenCV's identifiers.
#include "common/scene.hpp"
#include "common/video-buffer.hpp"

#include <opencv2/imgcodecs.hpp>

#include <gst/app/gstappsrc.h>
#include <gst/check/gstcheck.h>
#include <gst/video/video.h>

#include "../support/harness.hpp"

#include <algorithm>
#include <cstring>
#include <mutex>
#include <string>
#include <vector>

namespace {

using pickdetect::test_harness::kBoxPath;
constexpr int kWidth = 1280, kHeight = 960;
constexpr int kFrames = 90;                              // 3 s of stream.
constexpr GstClockTime kFrameDuration = GST_SECOND / 30; // 30 frames per second.
bool g_qos = true;                                       // false with --no-qos.

/// What one run through the pipeline saw.
struct Observed {
  std::mutex lock;
  GstClockTime base_time = GST_CLOCK_TIME_NONE;
  GstClock* clock = nullptr;
  GstClockTime entered = GST_CLOCK_TIME_NONE; ///< Clock time the last buffer entered pickdetect.
  GstClockTime max_processing = 0;            ///< Longest time a processed frame spent inside.
  int processed = 0;                          ///< Buffers that came out of pickdetect.
  int rendered = 0;                           ///< Buffers that reached the sink.
  GstClockTimeDiff last_lateness = 0; ///< Arrival at the sink minus running time, last buffer.
  GstClockTimeDiff max_lateness = 0;
  int qos_messages = 0; ///< QoS messages posted by pickdetect.
  guint64 dropped = 0;  ///< The largest `dropped` count they reported.
  guint64 qos_processed = 0;
};

GstPadProbeReturn on_sink_pad(GstPad*, GstPadProbeInfo*, gpointer data) {
  auto* o = static_cast<Observed*>(data);
  std::lock_guard<std::mutex> guard(o->lock);
  o->entered = gst_clock_get_time(o->clock);
  return GST_PAD_PROBE_OK;
}

GstPadProbeReturn on_src_pad(GstPad*, GstPadProbeInfo*, gpointer data) {
  auto* o = static_cast<Observed*>(data);
  std::lock_guard<std::mutex> guard(o->lock);
  // One streaming thread: the last buffer that entered is the one coming out.
  o->max_processing = std::max(o->max_processing, gst_clock_get_time(o->clock) - o->entered);
  o->processed++;
  return GST_PAD_PROBE_OK;
}

void on_handoff(GstElement*, GstBuffer* buffer, GstPad*, gpointer data) {
  auto* o = static_cast<Observed*>(data);
  std::lock_guard<std::mutex> guard(o->lock);
  const GstClockTime now = gst_clock_get_time(o->clock) - o->base_time;
  // The segment starts at 0, so a buffer's running time is its PTS.
  o->last_lateness = GST_CLOCK_DIFF(GST_BUFFER_PTS(buffer), now);
  o->max_lateness = std::max(o->max_lateness, o->last_lateness);
  o->rendered++;
}

/// Ten boxes at seeded random poses on noise, as GRAY8 buffers.
std::vector<GstBuffer*> make_frames(int count) {
  const cv::Mat box = cv::imread(kBoxPath, cv::IMREAD_GRAYSCALE);
  fail_unless(!box.empty(), "cannot read %s", kBoxPath.c_str());
  std::vector<GstBuffer*> frames;
  cv::RNG rng(20260107);
  for (int f = 0; f < count; f++) {
    cv::Mat scene = pickdetect::test_scene::plain_background(cv::Size(kWidth, kHeight), 110, f);
    std::vector<pickdetect::test_scene::Pose> poses;
    for (int i = 0; i < 10; i++)
      poses.push_back(
          {cv::Point2f(rng.uniform(120.f, kWidth - 120.f), rng.uniform(120.f, kHeight - 120.f)),
           rng.uniform(0.0, 360.0), rng.uniform(0.5, 0.7)});
    pickdetect::test_scene::paste(scene, box, poses);
    GstBuffer* buffer = pickdetect::tools::video_buffer(scene, "GRAY8");
    frames.push_back(buffer);
  }
  return frames;
}

void on_bus_message(GstMessage* m, GstElement* detect, Observed& o) {
  if (GST_MESSAGE_TYPE(m) == GST_MESSAGE_QOS && GST_MESSAGE_SRC(m) == GST_OBJECT(detect)) {
    GstFormat format;
    guint64 processed = 0, dropped = 0;
    gst_message_parse_qos_stats(m, &format, &processed, &dropped);
    o.qos_messages++;
    o.dropped = std::max(o.dropped, dropped);
    o.qos_processed = std::max(o.qos_processed, processed);
  } else if (GST_MESSAGE_TYPE(m) == GST_MESSAGE_ERROR) {
    GError* err = nullptr;
    gchar* debug = nullptr;
    gst_message_parse_error(m, &err, &debug);
    const std::string text = std::string(err->message) + " (" + (debug ? debug : "") + ")";
    g_clear_error(&err);
    g_free(debug);
    fail("pipeline error: %s", text.c_str());
  }
}

GST_START_TEST(test_late_frames_are_dropped) {
  std::vector<GstBuffer*> frames = make_frames(8);
  GstElement* pipeline = gst_parse_launch(
      "appsrc name=src is-live=true format=time min-latency=0 max-bytes=0 ! "
      "pickdetect name=detect ! fakesink name=sink sync=true qos=true signal-handoffs=true",
      nullptr);
  fail_unless(pipeline != nullptr);
  GstElement* src = gst_bin_get_by_name(GST_BIN(pipeline), "src");
  GstElement* detect = gst_bin_get_by_name(GST_BIN(pipeline), "detect");
  GstElement* sink = gst_bin_get_by_name(GST_BIN(pipeline), "sink");
  g_object_set(detect, "model", kBoxPath.c_str(), "qos", g_qos ? TRUE : FALSE, nullptr);
  GstCaps* caps = gst_caps_from_string(
      pickdetect::tools::caps_string("GRAY8", cv::Size(kWidth, kHeight)).c_str());
  g_object_set(src, "caps", caps, nullptr);
  gst_caps_unref(caps);

  Observed o;
  o.clock = gst_system_clock_obtain();
  gst_pipeline_use_clock(GST_PIPELINE(pipeline), o.clock);
  GstPad* detect_sink = gst_element_get_static_pad(detect, "sink");
  GstPad* detect_src = gst_element_get_static_pad(detect, "src");
  gst_pad_add_probe(detect_sink, GST_PAD_PROBE_TYPE_BUFFER, on_sink_pad, &o, nullptr);
  gst_pad_add_probe(detect_src, GST_PAD_PROBE_TYPE_BUFFER, on_src_pad, &o, nullptr);
  g_signal_connect(sink, "handoff", G_CALLBACK(on_handoff), &o);

  fail_if(gst_element_set_state(pipeline, GST_STATE_PLAYING) == GST_STATE_CHANGE_FAILURE);
  {
    std::lock_guard<std::mutex> guard(o.lock);
    o.base_time = gst_element_get_base_time(pipeline);
  }
  // A live camera: frame i is pushed when the clock reaches its running time.
  GstBus* bus = gst_element_get_bus(pipeline);
  for (int i = 0; i < kFrames; i++) {
    const GstClockTime pts = static_cast<GstClockTime>(i) * kFrameDuration;
    GstClockID id = gst_clock_new_single_shot_id(o.clock, o.base_time + pts);
    gst_clock_id_wait(id, nullptr);
    gst_clock_id_unref(id);
    GstBuffer* buffer = gst_buffer_copy(frames[static_cast<size_t>(i) % frames.size()]);
    GST_BUFFER_PTS(buffer) = pts;
    GST_BUFFER_DURATION(buffer) = kFrameDuration;
    fail_unless_equals_int(gst_app_src_push_buffer(GST_APP_SRC(src), buffer), GST_FLOW_OK);
    while (GstMessage* m = gst_bus_pop(bus)) {
      on_bus_message(m, detect, o);
      gst_message_unref(m);
    }
  }
  fail_unless_equals_int(gst_app_src_end_of_stream(GST_APP_SRC(src)), GST_FLOW_OK);
  for (bool eos = false; !eos;) {
    GstMessage* m = gst_bus_timed_pop(bus, 600 * GST_SECOND);
    fail_unless(m != nullptr, "no EOS within 10 minutes");
    eos = GST_MESSAGE_TYPE(m) == GST_MESSAGE_EOS;
    on_bus_message(m, detect, o);
    gst_message_unref(m);
  }
  gst_element_set_state(pipeline, GST_STATE_NULL);
  while (GstMessage* m = gst_bus_pop(bus)) {
    on_bus_message(m, detect, o);
    gst_message_unref(m);
  }

  GST_INFO(
      "qos=%d: pushed %d, processed %d, rendered %d; QoS messages %d (processed %" G_GUINT64_FORMAT
      ", dropped %" G_GUINT64_FORMAT "); longest processing %" GST_TIME_FORMAT
      ", last lateness %" GST_STIME_FORMAT ", largest %" GST_STIME_FORMAT,
      g_qos, kFrames, o.processed, o.rendered, o.qos_messages, o.qos_processed, o.dropped,
      GST_TIME_ARGS(o.max_processing), GST_STIME_ARGS(o.last_lateness),
      GST_STIME_ARGS(o.max_lateness));
  g_print("qos=%s: pushed %d frames at 30/s; pickdetect processed %d, sink rendered %d; %d QoS "
          "messages from pickdetect, dropped %" G_GUINT64_FORMAT "; longest processing %.0f ms; "
          "last frame %.0f ms late, largest lateness %.0f ms\n",
          g_qos ? "true" : "false", kFrames, o.processed, o.rendered, o.qos_messages, o.dropped,
          static_cast<double>(o.max_processing) / GST_MSECOND,
          static_cast<double>(o.last_lateness) / GST_MSECOND,
          static_cast<double>(o.max_lateness) / GST_MSECOND);

  // The premise: the source outruns the element.
  fail_unless(o.max_processing > kFrameDuration,
              "the element took at most %" GST_TIME_FORMAT
              " a frame, faster than the source; nothing is late, the test proves nothing",
              GST_TIME_ARGS(o.max_processing));
  fail_unless(o.rendered == o.processed, "every processed frame reaches the sink");
  fail_unless(o.qos_messages > 0 && o.dropped > 0,
              "pickdetect posted %d QoS messages, dropped %" G_GUINT64_FORMAT, o.qos_messages,
              o.dropped);
  fail_unless(o.processed < kFrames, "processed %d of %d frames: late frames were not dropped",
              o.processed, kFrames);
  fail_unless(o.processed + static_cast<int>(o.dropped) <= kFrames);
  // Bounded latency: a processed frame waits for at most the frame processed before it, plus
  // a few frame intervals; it does not grow with the number of frames pushed.
  const GstClockTimeDiff bound =
      static_cast<GstClockTimeDiff>(2 * o.max_processing + 5 * kFrameDuration);
  fail_unless(o.max_lateness <= bound,
              "a frame reached the sink %" GST_STIME_FORMAT " after its running time, more than "
              "%" GST_STIME_FORMAT " (twice the longest processing plus 5 frames)",
              GST_STIME_ARGS(o.max_lateness), GST_STIME_ARGS(bound));

  gst_object_unref(bus);
  gst_object_unref(detect_sink);
  gst_object_unref(detect_src);
  gst_object_unref(src);
  gst_object_unref(detect);
  gst_object_unref(sink);
  gst_object_unref(pipeline);
  gst_object_unref(o.clock);
  for (GstBuffer* b : frames)
    gst_buffer_unref(b);
}
GST_END_TEST

Suite* qos_suite() {
  Suite* s = suite_create("pickdetect-qos");
  TCase* tc = pickdetect::test_harness::add_tcase(s, "qos");
  tcase_add_test(tc, test_late_frames_are_dropped);
  return s;
}

} // namespace

int main(int argc, char** argv) {
  std::vector<char*> args;
  for (int i = 0; i < argc; i++) {
    if (std::strcmp(argv[i], "--no-qos") == 0)
      g_qos = false;
    else
      args.push_back(argv[i]);
  }
  int n = static_cast<int>(args.size());
  args.push_back(nullptr);
  char** list = args.data();
  gst_check_init(&n, &list);
  return gst_check_run_suite(qos_suite(), "pickdetect-qos", __FILE__);
}
