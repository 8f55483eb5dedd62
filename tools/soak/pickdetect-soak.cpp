// SPDX-License-Identifier: LGPL-2.1-or-later
// pickdetect-soak: pushes many frames with the object in view through
//   appsrc ! videoconvert ! pickdetect ! fakesink
// and compares the process's resident memory after the first frames with that at the end, both
// taken after malloc_trim (see trimmed_rss_kb).
// Frames: the model picture pasted at a few poses on fresh noise (a new buffer each frame).
#include "common/video-buffer.hpp"

#include <pickdetect/model.hpp>

#include <opencv2/imgproc.hpp>

#include <gst/app/gstappsrc.h>
#include <gst/gst.h>
#include <gst/pickdetect/pickdetect-meta.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <malloc.h>
#include <string>
#include <vector>

namespace {

struct Options {
  std::string model = "/usr/share/doc/opencv-doc/examples/data/box.png";
  int frames = 10000;
  int baseline = 500;
  int width = 320;
  int height = 240;
  double scale = 0.5;
  double tolerance = 0.05;
  int every = 0; ///< Print the resident memory every this many frames (0: only the two samples).
};

long rss_kb() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmRSS:", 0) == 0)
      return std::strtol(line.c_str() + 6, nullptr, 10);
  return -1;
}

/// Resident memory once glibc has handed back what its arenas keep free (malloc_trim): the
/// memory held for live data. Untrimmed, the arenas' free part grows over the first thousand
/// frames or so to a plateau (about 5 MB at 320x240, 5 % of the process): the allocator's
/// high-water mark, not growth; glibc's count of bytes in use stays flat meanwhile.
long trimmed_rss_kb() {
  malloc_trim(0);
  return rss_kb();
}

struct State {
  int baseline = 0;
  int every = 0;
  std::atomic<int> frames{0};
  std::atomic<int> with_instances{0};
  std::atomic<long> rss_baseline{-1};
};

GstPadProbeReturn count_frame(GstPad*, GstPadProbeInfo* info, gpointer data) {
  auto* st = static_cast<State*>(data);
  GstBuffer* buffer = GST_PAD_PROBE_INFO_BUFFER(info);
  const GstPickDetectMeta* meta = gst_buffer_get_pickdetect_meta(buffer);
  if (meta && gst_pickdetect_meta_get_n_instances(meta) > 0)
    st->with_instances.fetch_add(1);
  const int frame = st->frames.fetch_add(1) + 1;
  if (st->every > 0 && frame % st->every == 0) {
    // glibc's heap, summed over its arenas: what is allocated and what is free but kept.
    const struct mallinfo2 heap = mallinfo2();
    const long untrimmed = rss_kb();
    std::printf("RSS after %d frames: %ld kB (untrimmed %ld kB; malloc: %zu kB in use, %zu kB "
                "free in %zu kB of arenas, %zu kB mmapped)\n",
                frame, trimmed_rss_kb(), untrimmed, heap.uordblks / 1024, heap.fordblks / 1024,
                heap.arena / 1024, heap.hblkhd / 1024);
  }
  if (frame == st->baseline)
    st->rss_baseline = trimmed_rss_kb();
  return GST_PAD_PROBE_OK;
}

/// Only errors and EOS stay on the bus; the per-frame element messages are dropped at once, so
/// that nothing piles up unread. A sync handler that drops a message must unref it (the bus
/// does not): without that, every frame's message stayed allocated, about 2.5 kB a frame.
GstBusSyncReply keep_errors_and_eos(GstBus*, GstMessage* msg, gpointer) {
  switch (GST_MESSAGE_TYPE(msg)) {
  case GST_MESSAGE_ERROR:
  case GST_MESSAGE_WARNING:
  case GST_MESSAGE_EOS:
    return GST_BUS_PASS;
  default:
    gst_message_unref(msg);
    return GST_BUS_DROP;
  }
}

std::vector<cv::Mat> make_scenes(const Options& o, const pickdetect::Model& model) {
  std::vector<cv::Mat> scenes;
  const cv::Point2f c = model.principal_points.at(0);
  const cv::Mat ones(model.image.size(), CV_8UC1, cv::Scalar(255));
  for (int k = 0; k < 8; k++) {
    cv::Mat noise(o.height, o.width, CV_8UC1);
    cv::RNG rng(100 + k);
    rng.fill(noise, cv::RNG::UNIFORM, 0, 60);
    cv::GaussianBlur(noise, noise, cv::Size(0, 0), 1.5);
    cv::Mat scene = noise + cv::Scalar(90);
    const double a = k * 45.0 * CV_PI / 180.0;
    const double ca = std::cos(a) * o.scale, sa = std::sin(a) * o.scale;
    const double x = o.width / 2.0 + (k % 3 - 1) * o.width / 10.0;
    const double y = o.height / 2.0 + (k % 2 ? 1 : -1) * o.height / 12.0;
    const cv::Mat m = (cv::Mat_<double>(2, 3) << ca, -sa, x - (ca * c.x - sa * c.y), sa, ca,
                       y - (sa * c.x + ca * c.y));
    cv::Mat warped, mask;
    cv::warpAffine(model.image, warped, m, scene.size(), cv::INTER_LINEAR);
    cv::warpAffine(ones, mask, m, scene.size(), cv::INTER_NEAREST);
    warped.copyTo(scene, mask);
    cv::Mat bgr;
    cv::cvtColor(scene, bgr, cv::COLOR_GRAY2BGR);
    scenes.push_back(bgr);
  }
  return scenes;
}

int usage(const char* argv0) {
  std::fprintf(stderr,
               "usage: %s [--model FILE] [--frames N] [--baseline N] [--size WxH] [--scale S] "
               "[--tolerance F] [--every N]\n",
               argv0);
  return 2;
}

} // namespace

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0); // The --every lines as they come, also into a file.
  gst_init(&argc, &argv);
  Options o;
  for (int i = 1; i < argc; i++) {
    const std::string a = argv[i];
    if (i + 1 >= argc)
      return usage(argv[0]);
    const char* v = argv[++i];
    if (a == "--model")
      o.model = v;
    else if (a == "--frames")
      o.frames = std::atoi(v);
    else if (a == "--baseline")
      o.baseline = std::atoi(v);
    else if (a == "--size" && std::sscanf(v, "%dx%d", &o.width, &o.height) == 2)
      ;
    else if (a == "--scale")
      o.scale = std::atof(v);
    else if (a == "--tolerance")
      o.tolerance = std::atof(v);
    else if (a == "--every")
      o.every = std::atoi(v);
    else
      return usage(argv[0]);
  }
  if (o.frames <= o.baseline || o.baseline <= 0 || o.width <= 0 || o.height <= 0)
    return usage(argv[0]);

  const std::vector<cv::Mat> scenes = make_scenes(o, pickdetect::load_model(o.model));
  GError* error = nullptr;
  GstElement* pipeline =
      gst_parse_launch("appsrc name=src is-live=false format=time block=true max-bytes=2000000 ! "
                       "videoconvert ! pickdetect name=pd ! fakesink name=sink sync=false",
                       &error);
  if (!pipeline) {
    std::fprintf(stderr, "pipeline: %s\n", error ? error->message : "?");
    return 1;
  }
  GstElement* src = gst_bin_get_by_name(GST_BIN(pipeline), "src");
  GstElement* pd = gst_bin_get_by_name(GST_BIN(pipeline), "pd");
  GstElement* sink = gst_bin_get_by_name(GST_BIN(pipeline), "sink");
  g_object_set(pd, "model", o.model.c_str(), nullptr);
  GstCaps* caps = gst_caps_from_string(
      pickdetect::tools::caps_string("BGR", cv::Size(o.width, o.height)).c_str());
  gst_app_src_set_caps(GST_APP_SRC(src), caps);
  gst_caps_unref(caps);
  State st;
  st.baseline = o.baseline;
  st.every = o.every;
  GstPad* pad = gst_element_get_static_pad(sink, "sink");
  gst_pad_add_probe(pad, GST_PAD_PROBE_TYPE_BUFFER, count_frame, &st, nullptr);
  gst_object_unref(pad);
  GstBus* bus = gst_element_get_bus(pipeline);
  gst_bus_set_sync_handler(bus, keep_errors_and_eos, nullptr, nullptr);

  if (gst_element_set_state(pipeline, GST_STATE_PLAYING) == GST_STATE_CHANGE_FAILURE) {
    std::fprintf(stderr, "the pipeline does not start\n");
    return 1;
  }
  const gint64 t0 = g_get_monotonic_time();
  bool pushed_all = true;
  for (int i = 0; i < o.frames; i++) {
    const cv::Mat& scene = scenes[i % scenes.size()];
    GstBuffer* buffer = pickdetect::tools::video_buffer(scene, "BGR");
    GST_BUFFER_PTS(buffer) = gst_util_uint64_scale(i, GST_SECOND, 30);
    GST_BUFFER_DURATION(buffer) = GST_SECOND / 30;
    if (gst_app_src_push_buffer(GST_APP_SRC(src), buffer) != GST_FLOW_OK) {
      pushed_all = false;
      break;
    }
  }
  gst_app_src_end_of_stream(GST_APP_SRC(src));
  GstMessage* msg = gst_bus_timed_pop_filtered(
      bus, GST_CLOCK_TIME_NONE,
      static_cast<GstMessageType>(GST_MESSAGE_EOS | GST_MESSAGE_ERROR | GST_MESSAGE_WARNING));
  bool ok = pushed_all && msg && GST_MESSAGE_TYPE(msg) == GST_MESSAGE_EOS;
  if (msg && GST_MESSAGE_TYPE(msg) != GST_MESSAGE_EOS) {
    GError* err = nullptr;
    if (GST_MESSAGE_TYPE(msg) == GST_MESSAGE_ERROR)
      gst_message_parse_error(msg, &err, nullptr);
    else
      gst_message_parse_warning(msg, &err, nullptr);
    std::fprintf(stderr, "%s: %s\n", GST_MESSAGE_TYPE_NAME(msg), err->message);
    g_error_free(err);
  }
  if (msg)
    gst_message_unref(msg);
  const long rss_end = trimmed_rss_kb(); // Still PLAYING, like at the baseline.
  const double seconds = (g_get_monotonic_time() - t0) / 1e6;
  gst_element_set_state(pipeline, GST_STATE_NULL);

  const int frames = st.frames.load();
  const long rss_base = st.rss_baseline.load();
  const double growth = rss_base > 0 ? (rss_end - rss_base) / static_cast<double>(rss_base) : 1.0;
  std::printf("frames: %d of %d in %.1f s (%.1f frames/s), %d with instances\n", frames, o.frames,
              seconds, frames / seconds, st.with_instances.load());
  std::printf("RSS after %d frames: %ld kB\n", o.baseline, rss_base);
  std::printf("RSS after %d frames: %ld kB (%+.2f %%, limit %+.2f %%)\n", frames, rss_end,
              100.0 * growth, 100.0 * o.tolerance);
  if (frames != o.frames) {
    ok = false;
    std::printf("not every frame came out\n");
  }
  if (st.with_instances.load() < frames * 9 / 10) {
    ok = false;
    std::printf("fewer than 90 %% of the frames had an instance\n");
  }
  if (growth > o.tolerance)
    ok = false;
  std::printf("%s\n", ok ? "PASS" : "FAIL");

  gst_object_unref(bus);
  gst_object_unref(src);
  gst_object_unref(pd);
  gst_object_unref(sink);
  gst_object_unref(pipeline);
  gst_deinit();
  return ok ? 0 : 1;
}
