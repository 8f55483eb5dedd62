// SPDX-License-Identifier: LGPL-2.1-or-later
// libFuzzer target: the pickdetect element in a GstHarness, caps renegotiated on every input to
// a fuzzed format, size and padding (a GstVideoMeta with odd strides), content fuzzed too. The
// frame must come out with its meta.
#include "fuzz_common.hpp"

#include "common/video-buffer.hpp"

#include <gst/check/gstharness.h>
#include <gst/gst.h>
#include <gst/pickdetect/pickdetect-meta.h>
#include <gst/video/video.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#ifndef FUZZ_PLUGIN
#error "FUZZ_PLUGIN must name the built plugin"
#endif

namespace {

const char* const kFormats[] = {"GRAY8", "RGB",  "BGR",  "RGBx", "BGRx", "xRGB", "xBGR", "RGBA",
                                "BGRA",  "ARGB", "ABGR", "I420", "YV12", "NV12", "NV21"};

/// The harness and the pickdetect element in it: gst_harness_new_parse puts the element in a
/// bin (h->element), and the properties are the element's.
struct Harness {
  GstHarness* h;
  GstElement* pickdetect;
};

const Harness& harness() {
  static const Harness harness = [] {
    gst_init(nullptr, nullptr);
    GError* error = nullptr;
    GstPlugin* plugin = gst_plugin_load_file(FUZZ_PLUGIN, &error);
    if (!plugin) {
      std::fprintf(stderr, "cannot load %s: %s\n", FUZZ_PLUGIN, error->message);
      std::abort();
    }
    gst_object_unref(plugin);
    GstHarness* h = gst_harness_new_parse(
        ("pickdetect model=" + fuzz::work_dir() + "/small.png draw=true").c_str());
    GstElement* pickdetect = gst_harness_find_element(h, "pickdetect");
    if (!pickdetect)
      std::abort();
    return Harness{h, pickdetect};
  }();
  return harness;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  GstHarness* h = harness().h;
  fuzz::Input in(data, size);
  const char* format = kFormats[in.range(0, G_N_ELEMENTS(kFormats) - 1)];
  const int width = in.range(1, 160), height = in.range(1, 120);
  const bool pad = in.byte() & 1;
  GstVideoInfo info;
  if (!gst_video_info_set_format(&info, gst_video_format_from_string(format), width, height))
    __builtin_trap();
  GstVideoAlignment align;
  gst_video_alignment_reset(&align);
  if (pad) {
    align.padding_top = in.range(0, 4);
    align.padding_left = 2 * in.range(0, 4);
    align.padding_right = in.range(0, 9);
    align.padding_bottom = in.range(0, 4);
  }
  gst_harness_set_src_caps_str(
      h, pickdetect::tools::caps_string(format, cv::Size(width, height)).c_str());
  g_object_set(harness().pickdetect, "max-instances", in.range(0, 3), "allow-scale", in.byte() & 1,
               nullptr);

  GstBuffer* buffer = pickdetect::tools::allocate_video_buffer(info, pad ? &align : nullptr);
  if (!buffer)
    __builtin_trap();
  GstMapInfo map;
  gst_buffer_map(buffer, &map, GST_MAP_WRITE);
  cv::Mat bytes(1, static_cast<int>(map.size), CV_8UC1, map.data);
  fuzz::fill(bytes, in);
  gst_buffer_unmap(buffer, &map);
  GstBuffer* out = gst_harness_push_and_pull(h, buffer);
  if (!out || !gst_buffer_get_pickdetect_meta(out))
    __builtin_trap();
  gst_buffer_unref(out);
  // The per-frame element messages have no bus to go to in a harness; nothing piles up.
  return 0;
}
