// SPDX-License-Identifier: LGPL-2.1-or-later
// Robustness of the pickdetect element (issue 8): bad model files, out-of-range properties,
// odd / huge / padded / degenerate frames in many formats, renegotiation, flushes, EOS, state
// cycles and model swaps under load. Runs under GST_TRACERS=leaks like the element tests, so
// every test is also a leak test.
// OpenCV comes before gstcheck.h, whose `fail` macro would clash with OpenCV's identifiers.
#include <pickdetect/model.hpp>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <glib/gstdio.h>
#include <gst/check/gstcheck.h>
#include <gst/check/gstharness.h>
#include <gst/pickdetect/pickdetect-meta.h>
#include <gst/video/video.h>

#include "../support/harness.hpp"
#include "common/scene.hpp"
#include "common/video-buffer.hpp"

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fcntl.h>
#include <limits>
#include <string>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

namespace {

using pickdetect::test_harness::kBoxPath;

struct Pose {
  double x, y, angle, scale;
};

const pickdetect::Model& box_model() {
  static const pickdetect::Model model = pickdetect::load_model(kBoxPath);
  return model;
}

/// A grey scene: smooth noise around 100 with the box pasted at each pose.
cv::Mat make_scene(cv::Size size, const std::vector<Pose>& poses, int seed = 1234) {
  cv::Mat scene = pickdetect::test_scene::smooth_noise_background(size, seed);
  for (const Pose& p : poses)
    pickdetect::test_scene::paste(
        scene, box_model().image,
        {{cv::Point2f(static_cast<float>(p.x), static_cast<float>(p.y)), p.angle, p.scale}});
  return scene;
}

enum class Content { Black, White, Noise, Scene };

using pickdetect::tools::kCanary;

/// A buffer of `format` at the size of `grey` (or w x h for the flat contents). With `pad`,
/// planes get padding on all sides and wide strides, described by a GstVideoMeta; the padding
/// holds kCanary (see pickdetect::tools::video_buffer). Scene: R = G = B = grey, or Y = grey
/// with neutral chroma.
GstBuffer* make_buffer(const char* format, int width, int height, Content content, bool pad,
                       const cv::Mat& grey = cv::Mat(), GstVideoInfo* info_out = nullptr) {
  const cv::Size size(width, height);
  const auto layout = pad ? pickdetect::tools::Layout::Padded : pickdetect::tools::Layout::Default;
  GstBuffer* buffer = nullptr;
  switch (content) {
  case Content::Noise:
    buffer = pickdetect::tools::noise_video_buffer(format, size, layout, info_out);
    break;
  case Content::Scene:
    buffer = pickdetect::tools::video_buffer(grey, format, layout, info_out);
    break;
  case Content::Black:
  case Content::White:
    buffer = pickdetect::tools::video_buffer(
        cv::Mat(size, CV_8UC1, cv::Scalar(content == Content::White ? 255 : 0)), format, layout,
        info_out);
    break;
  }
  fail_unless(buffer != nullptr, "%s %dx%d", format, width, height);
  return buffer;
}

/// True when every byte of `buffer` outside the planes' pictures still holds kCanary.
bool canaries_intact(GstBuffer* buffer, const GstVideoInfo& info) {
  GstMapInfo map;
  fail_unless(gst_buffer_map(buffer, &map, GST_MAP_READ));
  std::vector<bool> inside(map.size, false);
  for (guint p = 0; p < GST_VIDEO_INFO_N_PLANES(&info); p++) {
    int comp[GST_VIDEO_MAX_COMPONENTS];
    gst_video_format_info_component(info.finfo, p, comp);
    const int rows = GST_VIDEO_INFO_COMP_HEIGHT(&info, comp[0]);
    const size_t row_bytes = static_cast<size_t>(GST_VIDEO_INFO_COMP_WIDTH(&info, comp[0])) *
                             GST_VIDEO_INFO_COMP_PSTRIDE(&info, comp[0]);
    for (int y = 0; y < rows; y++) {
      const size_t start = info.offset[p] + static_cast<size_t>(y) * info.stride[p];
      std::fill(inside.begin() + start, inside.begin() + start + row_bytes, true);
    }
  }
  bool intact = true;
  for (size_t i = 0; i < map.size && intact; i++)
    intact = inside[i] || map.data[i] == kCanary;
  gst_buffer_unmap(buffer, &map);
  return intact;
}

std::string caps_string(const char* format, int width, int height) {
  return pickdetect::tools::caps_string(format, cv::Size(width, height));
}

/// A harness around a lone pickdetect with the box model and a bus of its own.
GstHarness* pickdetect_harness(GstBus** bus, bool draw = false) {
  GstHarness* h = pickdetect::test_harness::pickdetect_harness("model", kBoxPath.c_str(), "draw",
                                                               static_cast<gboolean>(draw));
  *bus = gst_bus_new();
  gst_element_set_bus(h->element, *bus);
  return h;
}

void teardown(GstHarness* h, GstBus* bus) {
  gst_element_set_bus(h->element, nullptr);
  gst_bus_set_flushing(bus, TRUE);
  gst_object_unref(bus);
  gst_harness_teardown(h);
}

/// Fails on any error or warning message on the bus (and drops the others).
void expect_no_trouble(GstBus* bus, const char* what) {
  while (GstMessage* msg = gst_bus_pop(bus)) {
    if (GST_MESSAGE_TYPE(msg) == GST_MESSAGE_ERROR ||
        GST_MESSAGE_TYPE(msg) == GST_MESSAGE_WARNING) {
      GError* err = nullptr;
      gchar* debug = nullptr;
      if (GST_MESSAGE_TYPE(msg) == GST_MESSAGE_ERROR)
        gst_message_parse_error(msg, &err, &debug);
      else
        gst_message_parse_warning(msg, &err, &debug);
      fail("%s: %s (%s)", what, err->message, debug ? debug : "");
    }
    gst_message_unref(msg);
  }
}

guint n_instances(GstBuffer* buffer) {
  const GstPickDetectMeta* meta = gst_buffer_get_pickdetect_meta(buffer);
  fail_unless(meta != nullptr, "no pickdetect meta");
  return gst_pickdetect_meta_get_n_instances(meta);
}

/// A temporary folder, removed with what it holds.
struct TempDir {
  std::string path;
  TempDir() {
    gchar* p = g_dir_make_tmp("pickdetect-robust-XXXXXX", nullptr);
    fail_unless(p != nullptr);
    path = p;
    g_free(p);
  }
  ~TempDir() {
    GDir* dir = g_dir_open(path.c_str(), 0, nullptr);
    while (const gchar* name = dir ? g_dir_read_name(dir) : nullptr)
      g_unlink((path + "/" + name).c_str());
    if (dir)
      g_dir_close(dir);
    g_rmdir(path.c_str());
  }
  std::string file(const std::string& name) const { return path + "/" + name; }
  std::string write(const std::string& name, const std::string& text) const {
    const std::string p = file(name);
    fail_unless(
        g_file_set_contents(p.c_str(), text.data(), static_cast<gssize>(text.size()), nullptr));
    return p;
  }
};

std::string read_file(const std::string& path) {
  gchar* contents = nullptr;
  gsize length = 0;
  fail_unless(g_file_get_contents(path.c_str(), &contents, &length, nullptr));
  std::string out(contents, length);
  g_free(contents);
  return out;
}

/// Starts "videotestsrc ! pickdetect model=<path> ! fakesink" to PAUSED in another thread; the
/// start must fail within a minute. Returns the error message the element posted.
GError* start_error(const std::string& model) {
  GstElement* pipeline = gst_pipeline_new(nullptr);
  GstElement* src = gst_element_factory_make("videotestsrc", nullptr);
  GstElement* pd = gst_element_factory_make("pickdetect", nullptr);
  GstElement* sink = gst_element_factory_make("fakesink", nullptr);
  fail_unless(src && pd && sink);
  g_object_set(src, "num-buffers", 1, nullptr);
  g_object_set(pd, "model", model.c_str(), nullptr);
  gst_bin_add_many(GST_BIN(pipeline), src, pd, sink, nullptr);
  fail_unless(gst_element_link_many(src, pd, sink, nullptr));

  struct Start {
    GstElement* pipeline;
    std::atomic<int> result{-1};
  } start{pipeline};
  GThread* thread = g_thread_new(
      "start",
      [](gpointer data) -> gpointer {
        auto* s = static_cast<Start*>(data);
        s->result = gst_element_set_state(s->pipeline, GST_STATE_PAUSED);
        return nullptr;
      },
      &start);
  const gint64 deadline = g_get_monotonic_time() + 60 * G_TIME_SPAN_SECOND;
  while (start.result.load() < 0 && g_get_monotonic_time() < deadline)
    g_usleep(10000);
  if (start.result.load() < 0) {
    // Unblock a reader stuck on a FIFO before failing, so that the process can end.
    const int fd = open(model.c_str(), O_WRONLY | O_NONBLOCK);
    if (fd >= 0)
      close(fd);
    fail("starting with model %s hangs", model.c_str());
  }
  g_thread_join(thread);
  fail_unless(start.result.load() == GST_STATE_CHANGE_FAILURE, "model %s: the start did not fail",
              model.c_str());

  GstBus* bus = gst_element_get_bus(pipeline);
  GstMessage* msg = gst_bus_pop_filtered(bus, GST_MESSAGE_ERROR);
  fail_unless(msg != nullptr, "no error message for model %s", model.c_str());
  GError* err = nullptr;
  gst_message_parse_error(msg, &err, nullptr);
  fail_unless(GST_MESSAGE_SRC(msg) == GST_OBJECT(pd), "error not from pickdetect");
  gst_message_unref(msg);
  gst_object_unref(bus);
  gst_element_set_state(pipeline, GST_STATE_NULL);
  gst_object_unref(pipeline);
  return err;
}

/// The start fails with a RESOURCE error whose message names `names` and says `reason`.
void expect_refusal(const std::string& model, const std::string& names, const char* reason,
                    GstResourceError code = GST_RESOURCE_ERROR_SETTINGS) {
  GError* err = start_error(model);
  fail_unless(err->domain == GST_RESOURCE_ERROR, "%s: not a resource error: %s", model.c_str(),
              err->message);
  fail_unless(err->code == code, "%s: code %d, expected %d: %s", model.c_str(), err->code, code,
              err->message);
  fail_unless(std::strstr(err->message, names.c_str()) != nullptr, "%s not named in: %s",
              names.c_str(), err->message);
  fail_unless(std::strstr(err->message, reason) != nullptr, "'%s' not said in: %s", reason,
              err->message);
  g_error_free(err);
}

/// A model file for the picture `image` with the given YAML lines after it.
std::string model_yaml(const std::string& image, const std::string& rest = "") {
  return "%YAML:1.0\n---\nname: part\nimage: \"" + image + "\"\n" + rest;
}

} // namespace

/* ------------------------------------------------------------------------------------------- */
/* Model files                                                                                 */

// Every bad model file fails the start with an error naming the file and what is wrong.
GST_START_TEST(test_bad_models) {
  TempDir dir;
  const std::string box_copy = dir.write("box.png", read_file(kBoxPath));

  expect_refusal(dir.file("missing.yml"), dir.file("missing.yml"), "cannot be opened",
                 GST_RESOURCE_ERROR_NOT_FOUND);
  expect_refusal(dir.file("missing.png"), dir.file("missing.png"), "cannot be opened",
                 GST_RESOURCE_ERROR_NOT_FOUND);

  // A valid model file with cached features, then cut in half: truncated YAML.
  pickdetect::Model model = box_model();
  model.image_path = box_copy;
  const std::string good = dir.file("good.yml");
  pickdetect::save_model(model, good, true);
  const std::string text = read_file(good);
  // Cut inside the first matrix's data (an unclosed flow sequence), wherever the cache puts it.
  const size_t data = text.find("data: [");
  fail_unless(data != std::string::npos, "no matrix data in %s", good.c_str());
  expect_refusal(dir.write("truncated.yml", text.substr(0, data + 20)), dir.file("truncated.yml"),
                 "truncated.yml");
  // Cut inside the header: no 'image' key at all.
  expect_refusal(dir.write("header.yml", text.substr(0, 12)), dir.file("header.yml"),
                 "'image' key");
  expect_refusal(dir.write("empty.yml", ""), dir.file("empty.yml"), "empty.yml");
  expect_refusal(dir.write("corrupt.yml", "%YAML:1.0\nimage: [\"a\": {]]]\n\t\x01\x02\xff\n"),
                 dir.file("corrupt.yml"), "not valid");
  std::string binary(4096, '\0');
  for (size_t i = 0; i < binary.size(); i++)
    binary[i] = static_cast<char>((i * 2654435761u) >> 13);
  expect_refusal(dir.write("binary.yml", binary), dir.file("binary.yml"), "binary.yml");
  expect_refusal(dir.write("scalar.yml", "%YAML:1.0\n---\n42\n"), dir.file("scalar.yml"),
                 "not valid");
  expect_refusal(dir.write("imagelist.yml", "%YAML:1.0\n---\nimage: [1, 2]\n"),
                 dir.file("imagelist.yml"), "'image' must be a string");

  // The model file names a picture that is not there: both files are named.
  expect_refusal(dir.write("nopicture.yml", model_yaml("nothere.png")), "nothere.png",
                 "cannot be opened", GST_RESOURCE_ERROR_SETTINGS);
  expect_refusal(dir.file("nopicture.yml"), dir.file("nopicture.yml"), "cannot be opened");

  // Not a picture; a truncated picture.
  expect_refusal(dir.write("text.png", "this is not a PNG\n"), dir.file("text.png"),
                 "cannot be decoded");
  const std::string png = read_file(kBoxPath);
  expect_refusal(dir.write("cut.png", png.substr(0, png.size() / 3)), dir.file("cut.png"),
                 "cut.png");
  expect_refusal(dir.write("cutpic.yml", model_yaml("cut.png")), dir.file("cutpic.yml"), "cut.png");

  // A picture without texture: too few keypoints.
  const std::string flat = dir.file("flat.png");
  fail_unless(cv::imwrite(flat, cv::Mat(200, 300, CV_8UC1, cv::Scalar(128))));
  expect_refusal(flat, flat, "too little texture");
  expect_refusal(dir.write("flat.yml", model_yaml("flat.png")), dir.file("flat.yml"),
                 "too little texture");

  // Geometry: principal points outside the picture, empty or degenerate outline, bad grasp.
  expect_refusal(
      dir.write("outside.yml", model_yaml("box.png", "principal_points: [[10, 10], [500, 20]]\n")),
      dir.file("outside.yml"), "lies outside");
  expect_refusal(dir.write("negative.yml", model_yaml("box.png", "principal_points: [[-1, 10]]\n")),
                 dir.file("negative.yml"), "lies outside");
  expect_refusal(dir.write("nan.yml", model_yaml("box.png", "principal_points: [[.nan, 10]]\n")),
                 dir.file("nan.yml"), "non-finite");
  expect_refusal(dir.write("noline.yml", model_yaml("box.png", "outline: []\n")),
                 dir.file("noline.yml"), "'outline' is empty");
  expect_refusal(
      dir.write("flatline.yml", model_yaml("box.png", "outline: [[0, 0], [10, 10], [20, 20]]\n")),
      dir.file("flatline.yml"), "encloses no area");
  expect_refusal(dir.write("twopoints.yml", model_yaml("box.png", "outline: [[0, 0], [10, 10]]\n")),
                 dir.file("twopoints.yml"), "at least 3 points");
  expect_refusal(dir.write("grasp.yml", model_yaml("box.png", "grasp_point: 7\n")),
                 dir.file("grasp.yml"), "grasp_point 7");
  expect_refusal(dir.write("badpoints.yml", model_yaml("box.png", "principal_points: 3\n")),
                 dir.file("badpoints.yml"), "list of [x, y] pairs");

  // Cached features that disagree with each other.
  std::string cache = text;
  const size_t rows = cache.find("rows: ");
  fail_unless(rows != std::string::npos);
  cache.replace(rows, 6, "rows: 1");
  expect_refusal(dir.write("cache.yml", cache), dir.file("cache.yml"), "cache.yml");

  // A huge picture: refused for its size (a flat 12000 x 12000 PNG is small on disk).
  const std::string huge = dir.file("huge.png");
  fail_unless(cv::imwrite(huge, cv::Mat(12000, 12000, CV_8UC1, cv::Scalar(0))));
  expect_refusal(huge, huge, "12000x12000");
  expect_refusal(dir.write("huge.yml", model_yaml("huge.png")), dir.file("huge.yml"),
                 "12000x12000");
}
GST_END_TEST;

// Things that are not files: a folder, a FIFO (opening it would block until a writer comes),
// a character device. Each is refused at once.
GST_START_TEST(test_models_that_are_not_files) {
  TempDir dir;
  expect_refusal(TEST_DATA_DIR, TEST_DATA_DIR, "directory", GST_RESOURCE_ERROR_OPEN_READ);
  const std::string fifo = dir.file("fifo.yml");
  fail_unless(mkfifo(fifo.c_str(), 0600) == 0, "mkfifo: %s", g_strerror(errno));
  expect_refusal(fifo, fifo, "not a regular file");
  const std::string fifo_png = dir.file("fifo.png");
  fail_unless(mkfifo(fifo_png.c_str(), 0600) == 0);
  expect_refusal(fifo_png, fifo_png, "not a regular file");
  expect_refusal("/dev/zero", "/dev/zero", "not a regular file");
}
GST_END_TEST;

// A model file the process may not read: OPEN_READ, naming the file. Root reads everything, so
// as root this test (a forked child of its own) drops to the 'nobody' user first.
GST_START_TEST(test_unreadable_model) {
  TempDir dir;
  fail_unless(g_chmod(dir.path.c_str(), 0755) == 0);
  const std::string locked = dir.write("locked.yml", model_yaml(kBoxPath));
  const std::string locked_png = dir.write("locked.png", read_file(kBoxPath));
  fail_unless(g_chmod(locked.c_str(), 0) == 0 && g_chmod(locked_png.c_str(), 0) == 0);
  const bool root = geteuid() == 0;
  if (root) {
    // Back to root before TempDir's destructor runs (the saved set-user-ID keeps it possible).
    fail_unless(setresgid(65534, 65534, 0) == 0 && setresuid(65534, 65534, 0) == 0,
                "cannot drop to nobody: %s", g_strerror(errno));
  }
  fail_unless(g_access(locked.c_str(), R_OK) != 0, "the file is readable after chmod 0");
  expect_refusal(locked, locked, "Permission denied", GST_RESOURCE_ERROR_OPEN_READ);
  expect_refusal(locked_png, locked_png, "Permission denied", GST_RESOURCE_ERROR_OPEN_READ);
  if (root)
    fail_unless(setresuid(0, 0, 0) == 0 && setresgid(0, 0, 0) == 0);
}
GST_END_TEST;

/* ------------------------------------------------------------------------------------------- */
/* Properties                                                                                  */

// Out-of-range, infinite and NaN values are refused with a warning; the old value stays.
GST_START_TEST(test_property_ranges) {
  GstElement* pd = gst_element_factory_make("pickdetect", nullptr);
  fail_unless(pd != nullptr);
  gst_object_ref_sink(pd);
  g_object_set(pd, "ratio", 0.7, "bandwidth", 12.0, "min-matches", 9, "max-instances", 3,
               "contrast-threshold", 0.03, nullptr);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();

  for (const double bad : {nan, -nan, inf, -inf, 1.0, 1.5, -0.2})
    ASSERT_WARNING(g_object_set(pd, "ratio", bad, nullptr));
  for (const double bad : {nan, inf, -inf, -1.0, -0.001})
    ASSERT_WARNING(g_object_set(pd, "bandwidth", bad, nullptr));
  for (const double bad : {nan, inf, -inf, -0.01, 0.21})
    ASSERT_WARNING(g_object_set(pd, "contrast-threshold", bad, nullptr));
  for (const int bad : {0, -1, G_MININT})
    ASSERT_WARNING(g_object_set(pd, "min-matches", bad, nullptr));
  for (const int bad : {-1, G_MININT})
    ASSERT_WARNING(g_object_set(pd, "max-instances", bad, nullptr));
  ASSERT_WARNING(g_object_set(pd, "method", 42, nullptr));
  // Strings, as gst-launch and gst_util_set_object_arg give them.
  for (const char* bad : {"nan", "NAN", "-nan", "inf", "-inf", "1e999", "2"})
    ASSERT_WARNING(gst_util_set_object_arg(G_OBJECT(pd), "ratio", bad));
  for (const char* bad : {"nan", "inf", "-5"})
    ASSERT_WARNING(gst_util_set_object_arg(G_OBJECT(pd), "bandwidth", bad));

  double ratio = 0, bandwidth = 0, contrast = 0;
  int min_matches = 0, max_instances = 0, method = -1;
  g_object_get(pd, "ratio", &ratio, "bandwidth", &bandwidth, "min-matches", &min_matches,
               "max-instances", &max_instances, "method", &method, "contrast-threshold", &contrast,
               nullptr);
  fail_unless_equals_float(contrast, 0.03);
  fail_unless_equals_float(ratio, 0.7);
  fail_unless_equals_float(bandwidth, 12.0);
  fail_unless_equals_int(min_matches, 9);
  fail_unless_equals_int(max_instances, 3);
  fail_unless_equals_int(method, 0);
  gst_object_unref(pd);
}
GST_END_TEST;

// The extreme values the specs allow still give a clean result on a scene with boxes.
GST_START_TEST(test_property_extremes) {
  const cv::Size size(320, 240);
  const cv::Mat scene = make_scene(size, {{160, 120, 20, 0.5}});
  struct Case {
    const char* name;
    double ratio, bandwidth;
    int min_matches, max_instances, method;
    gboolean allow_scale;
  };
  const double denormal = std::numeric_limits<double>::denorm_min();
  const Case cases[] = {
      {"smallest ratio", 0.01, 0.0, 1, 0, 0, TRUE},
      {"largest ratio", 0.99, 0.0, 1, 0, 0, TRUE},
      {"denormal bandwidth", 0.8, denormal, 1, 0, 0, TRUE},
      {"huge bandwidth", 0.8, 1e300, 6, 0, 0, TRUE},
      {"largest bandwidth", 0.8, G_MAXDOUBLE, 6, 1, 0, FALSE},
      {"most matches", 0.8, 0.0, G_MAXINT, G_MAXINT, 0, TRUE},
      {"clustered, huge bandwidth", 0.99, G_MAXDOUBLE, 1, 0, 1, TRUE},
      {"clustered, denormal", 0.99, denormal, 1, 0, 1, FALSE},
      {"ransac-all, one match", 0.99, 0.0, 1, G_MAXINT, 2, TRUE},
  };
  for (const Case& c : cases) {
    for (const bool draw : {false, true}) {
      GstBus* bus = nullptr;
      GstHarness* h = pickdetect_harness(&bus, draw);
      g_object_set(h->element, "ratio", c.ratio, "bandwidth", c.bandwidth, "min-matches",
                   c.min_matches, "max-instances", c.max_instances, "method", c.method,
                   "allow-scale", c.allow_scale, nullptr);
      gst_harness_set_src_caps_str(h, caps_string("I420", size.width, size.height).c_str());
      GstBuffer* out = gst_harness_push_and_pull(
          h, make_buffer("I420", size.width, size.height, Content::Scene, false, scene));
      fail_unless(out != nullptr, "%s: no output", c.name);
      n_instances(out);
      gst_buffer_unref(out);
      expect_no_trouble(bus, c.name);
      teardown(h, bus);
    }
  }
}
GST_END_TEST;

struct Hammer {
  GstHarness* h = nullptr;
  std::string other_model;
  std::atomic<bool> stop{false};
  std::atomic<int> frames{0};
  std::atomic<int> sets{0};
  std::atomic<int> swaps{0};
  cv::Mat scene;
  int with_instances = 0; ///< Pusher only.
};

static gpointer hammer_push(gpointer data) {
  auto* st = static_cast<Hammer*>(data);
  while (!st->stop.load()) {
    GstBuffer* out =
        gst_harness_push_and_pull(st->h, make_buffer("NV12", st->scene.cols, st->scene.rows,
                                                     Content::Scene, false, st->scene));
    if (!out)
      break;
    if (n_instances(out) > 0)
      st->with_instances++;
    gst_buffer_unref(out);
    st->frames.fetch_add(1);
  }
  return nullptr;
}

static gpointer hammer_properties(gpointer data) {
  auto* st = static_cast<Hammer*>(data);
  GRand* rand = g_rand_new_with_seed(7);
  while (!st->stop.load()) {
    g_object_set(st->h->element, "ratio", g_rand_double_range(rand, 0.5, 0.99), "min-matches",
                 g_rand_int_range(rand, 1, 20), "bandwidth", g_rand_double_range(rand, 0.0, 80.0),
                 "max-instances", g_rand_int_range(rand, 0, 4), "method",
                 g_rand_int_range(rand, 0, 3), "allow-scale", g_rand_boolean(rand),
                 "pick-whole-in-view", g_rand_boolean(rand), "draw", g_rand_boolean(rand),
                 "post-messages", g_rand_boolean(rand), nullptr);
    double ratio = 0;
    g_object_get(st->h->element, "ratio", &ratio, nullptr);
    fail_unless(ratio >= 0.5 && ratio <= 0.99);
    st->sets.fetch_add(1);
    g_usleep(200);
  }
  g_rand_free(rand);
  return nullptr;
}

static gpointer hammer_models(gpointer data) {
  auto* st = static_cast<Hammer*>(data);
  for (int i = 0; !st->stop.load(); i++) {
    g_object_set(st->h->element, "model", (i % 2 ? kBoxPath : st->other_model).c_str(), nullptr);
    st->swaps.fetch_add(1);
  }
  return nullptr;
}

static void wait_for(const std::atomic<int>& counter, int n, const char* what) {
  const gint64 deadline = g_get_monotonic_time() + 300 * G_TIME_SPAN_SECOND;
  while (counter.load() < n && g_get_monotonic_time() < deadline)
    g_usleep(2000);
  fail_unless(counter.load() >= n, "%s: stuck at %d of %d", what, counter.load(), n);
}

// Every property, the model included, changed from two other threads while frames flow.
GST_START_TEST(test_properties_while_flowing) {
  TempDir dir;
  Hammer st;
  st.other_model = dir.write("crate.png", read_file(kBoxPath));
  GstBus* bus = nullptr;
  st.h = pickdetect_harness(&bus);
  st.scene = make_scene(cv::Size(320, 240), {{160, 120, 45, 0.5}});
  gst_harness_set_src_caps_str(st.h, caps_string("NV12", 320, 240).c_str());
  GThread* pusher = g_thread_new("push", hammer_push, &st);
  GThread* props = g_thread_new("props", hammer_properties, &st);
  GThread* models = g_thread_new("models", hammer_models, &st);
  wait_for(st.frames, 60, "frames");
  wait_for(st.swaps, 6, "model swaps");
  wait_for(st.sets, 100, "property sets");
  st.stop = true;
  g_thread_join(models);
  g_thread_join(props);
  g_thread_join(pusher);
  fail_unless(st.with_instances > 0, "no frame had an instance");
  expect_no_trouble(bus, "properties while flowing");
  teardown(st.h, bus);
}
GST_END_TEST;

/* ------------------------------------------------------------------------------------------- */
/* Frames                                                                                      */

const char* const kFrameFormats[] = {"GRAY8", "I420", "YV12", "NV12", "NV21",
                                     "RGB",   "BGR",  "BGRx", "xRGB", "ABGR"};

/// Pushes one frame of each content through a fresh element; a clean result each time, pixels
/// untouched (draw=false) and the padding untouched (both).
void check_frame(const char* format, int width, int height, bool pad, bool draw,
                 const std::vector<Content>& contents) {
  GstBus* bus = nullptr;
  GstHarness* h = pickdetect_harness(&bus, draw);
  gst_harness_set_src_caps_str(h, caps_string(format, width, height).c_str());
  for (const Content content : contents) {
    GstVideoInfo info;
    GstBuffer* in = make_buffer(format, width, height, content, pad, cv::Mat(), &info);
    GstBuffer* original = gst_buffer_copy_deep(in);
    GstBuffer* out = gst_harness_push_and_pull(h, in);
    fail_unless(out != nullptr, "%s %dx%d: no output", format, width, height);
    n_instances(out);
    fail_unless(canaries_intact(out, info), "%s %dx%d pad=%d: padding written", format, width,
                height, pad);
    if (!draw) {
      GstMapInfo map;
      fail_unless(gst_buffer_map(out, &map, GST_MAP_READ));
      fail_unless(gst_buffer_memcmp(original, 0, map.data, map.size) == 0,
                  "%s %dx%d: pixels changed", format, width, height);
      gst_buffer_unmap(out, &map);
    }
    gst_buffer_unref(original);
    gst_buffer_unref(out);
    gchar* what = g_strdup_printf("%s %dx%d pad=%d content=%d", format, width, height, pad,
                                  static_cast<int>(content));
    expect_no_trouble(bus, what);
    g_free(what);
  }
  teardown(h, bus);
}

// Tiny and odd sizes (odd chroma planes included), with and without padded strides.
GST_START_TEST(test_small_and_odd_frames) {
  const std::vector<Content> all = {Content::Black, Content::White, Content::Noise};
  const int sizes[][2] = {{1, 1}, {2, 2}, {3, 1}, {1, 3}, {7, 5}, {17, 9}, {641, 479}};
  for (const char* format : kFrameFormats)
    for (const auto& s : sizes)
      for (const bool pad : {false, true})
        check_frame(format, s[0], s[1], pad, pad, all);
}
GST_END_TEST;

// 8K frames: a flat one, and noise in padded NV12 drawn into. Only two: SIFT takes some 40 s
// on a 7680x4320 frame whatever it shows.
GST_START_TEST(test_large_frames) {
  check_frame("GRAY8", 7680, 4320, false, false, {Content::Black});
  check_frame("NV12", 7680, 4320, true, true, {Content::Noise});
}
GST_END_TEST;

// Boxes at odd sizes, drawn (draw=true) into odd chroma planes and padded strides: instances
// found, the padding never written.
GST_START_TEST(test_drawing_odd_frames) {
  const cv::Size size(641, 479);
  const cv::Mat scene = make_scene(size, {{160, 120, 30, 0.6}, {470, 330, 200, 0.7}});
  for (const char* format : kFrameFormats) {
    for (const bool pad : {false, true}) {
      GstBus* bus = nullptr;
      GstHarness* h = pickdetect_harness(&bus, true);
      gst_harness_set_src_caps_str(h, caps_string(format, size.width, size.height).c_str());
      GstVideoInfo info;
      GstBuffer* out = gst_harness_push_and_pull(
          h, make_buffer(format, size.width, size.height, Content::Scene, pad, scene, &info));
      fail_unless(out != nullptr);
      fail_unless_equals_int(n_instances(out), 2);
      fail_unless(canaries_intact(out, info), "%s pad=%d: padding written", format, pad);
      gst_buffer_unref(out);
      expect_no_trouble(bus, format);
      teardown(h, bus);
    }
  }
}
GST_END_TEST;

/* ------------------------------------------------------------------------------------------- */
/* Stream                                                                                      */

// Caps change mid-stream to other sizes and formats; flushes and new segments; EOS.
GST_START_TEST(test_renegotiation_flush_eos) {
  struct Step {
    const char* format;
    int width, height;
    guint expected;
  };
  const Step steps[] = {{"GRAY8", 320, 240, 1}, {"I420", 641, 479, 2}, {"BGRx", 320, 240, 1},
                        {"NV12", 7, 5, 0},      {"RGB", 641, 479, 2},  {"GRAY8", 1, 1, 0},
                        {"GRAY8", 320, 240, 1}};
  GstBus* bus = nullptr;
  GstHarness* h = pickdetect_harness(&bus, true);
  for (int round = 0; round < 2; round++) {
    for (const Step& s : steps) {
      const cv::Size size(s.width, s.height);
      const cv::Mat scene = s.expected == 0 ? make_scene(size, {})
                            : s.expected == 1
                                ? make_scene(size, {{160, 120, 10, 0.5}})
                                : make_scene(size, {{160, 120, 30, 0.6}, {470, 330, 200, 0.7}});
      gst_harness_set_src_caps_str(h, caps_string(s.format, s.width, s.height).c_str());
      for (int i = 0; i < 2; i++) {
        GstBuffer* out = gst_harness_push_and_pull(
            h, make_buffer(s.format, s.width, s.height, Content::Scene, i == 1, scene));
        fail_unless(out != nullptr);
        fail_unless_equals_int(n_instances(out), s.expected);
        gst_buffer_unref(out);
      }
      // A flush and a new segment in between.
      fail_unless(gst_harness_push_event(h, gst_event_new_flush_start()));
      fail_unless(gst_harness_push_event(h, gst_event_new_flush_stop(TRUE)));
      GstSegment segment;
      gst_segment_init(&segment, GST_FORMAT_TIME);
      segment.start = GST_SECOND * round;
      fail_unless(gst_harness_push_event(h, gst_event_new_segment(&segment)));
    }
  }
  fail_unless(gst_harness_push_event(h, gst_event_new_eos()));
  bool eos = false;
  while (GstEvent* ev = gst_harness_try_pull_event(h)) {
    eos = eos || GST_EVENT_TYPE(ev) == GST_EVENT_EOS;
    gst_event_unref(ev);
  }
  fail_unless(eos, "EOS did not come out");
  expect_no_trouble(bus, "renegotiation");
  teardown(h, bus);
}
GST_END_TEST;

// NULL -> PLAYING -> NULL (and through READY / PAUSED) again and again in a real pipeline, with
// the model swapped on some rounds.
GST_START_TEST(test_state_cycles) {
  TempDir dir;
  const std::string crate = dir.write("crate.png", read_file(kBoxPath));
  GError* error = nullptr;
  gchar* launch =
      g_strdup_printf("videotestsrc pattern=snow ! video/x-raw,format=I420,width=161,height=121 "
                      "! pickdetect name=pd model=\"%s\" ! fakesink name=sink",
                      kBoxPath.c_str());
  GstElement* pipeline = gst_parse_launch(launch, &error);
  g_free(launch);
  fail_unless(pipeline != nullptr && error == nullptr);
  GstElement* sink = gst_bin_get_by_name(GST_BIN(pipeline), "sink");
  GstElement* pd = gst_bin_get_by_name(GST_BIN(pipeline), "pd");
  std::atomic<int> buffers{0};
  GstPad* pad = gst_element_get_static_pad(sink, "sink");
  gst_pad_add_probe(
      pad, GST_PAD_PROBE_TYPE_BUFFER,
      [](GstPad*, GstPadProbeInfo*, gpointer data) {
        static_cast<std::atomic<int>*>(data)->fetch_add(1);
        return GST_PAD_PROBE_OK;
      },
      &buffers, nullptr);
  gst_object_unref(pad);
  GstBus* bus = gst_element_get_bus(pipeline);

  const GstState lows[] = {GST_STATE_NULL, GST_STATE_READY, GST_STATE_PAUSED};
  for (int round = 0; round < 12; round++) {
    if (round % 4 == 3)
      g_object_set(pd, "model", (round % 8 == 3 ? crate : kBoxPath).c_str(), nullptr);
    fail_if(gst_element_set_state(pipeline, GST_STATE_PLAYING) == GST_STATE_CHANGE_FAILURE);
    wait_for(buffers, buffers.load() + 3, "buffers");
    if (round % 3 == 1) // Swapped while playing.
      g_object_set(pd, "model", crate.c_str(), nullptr);
    fail_if(gst_element_set_state(pipeline, lows[round % 3]) == GST_STATE_CHANGE_FAILURE);
    fail_unless(gst_element_get_state(pipeline, nullptr, nullptr, GST_CLOCK_TIME_NONE) !=
                GST_STATE_CHANGE_FAILURE);
    expect_no_trouble(bus, "state cycles");
  }
  gst_element_set_state(pipeline, GST_STATE_NULL);
  expect_no_trouble(bus, "state cycles");
  gst_object_unref(bus);
  gst_object_unref(pd);
  gst_object_unref(sink);
  gst_object_unref(pipeline);
}
GST_END_TEST;

static Suite* robustness_suite(void) {
  Suite* s = suite_create("pickdetect-robustness");
  TCase* models = pickdetect::test_harness::add_tcase(s, "models", 600);
  tcase_add_test(models, test_bad_models);
  tcase_add_test(models, test_models_that_are_not_files);
  tcase_add_test(models, test_unreadable_model);

  TCase* props = pickdetect::test_harness::add_tcase(s, "properties", 600);
  tcase_add_test(props, test_property_ranges);
  tcase_add_test(props, test_property_extremes);
  tcase_add_test(props, test_properties_while_flowing);

  TCase* frames = pickdetect::test_harness::add_tcase(s, "frames", 1200);
  tcase_add_test(frames, test_small_and_odd_frames);
  tcase_add_test(frames, test_drawing_odd_frames);
  tcase_add_test(frames, test_large_frames);

  TCase* stream = pickdetect::test_harness::add_tcase(s, "stream", 600);
  tcase_add_test(stream, test_renegotiation_flush_eos);
  tcase_add_test(stream, test_state_cycles);
  return s;
}

GST_CHECK_MAIN(robustness);
