// SPDX-License-Identifier: LGPL-2.1-or-later
// What the element tests (tests/element, tests/robustness) share: the box model's path, a
// GstHarness around a lone pickdetect element set up before it starts, the region-of-interest
// metas of a buffer, and gst-check test cases. The tests' meson.build gives TEST_DATA_DIR.
#pragma once

#include <gst/check/gstcheck.h>
#include <gst/check/gstharness.h>
#include <gst/video/video.h>

#include <string>
#include <vector>

#ifndef TEST_DATA_DIR
#error "TEST_DATA_DIR must name the folder holding box.png"
#endif

namespace pickdetect::test_harness {

/// OpenCV's box.png (Debian's opencv-doc), the model of the element tests.
inline const std::string kBoxPath = std::string(TEST_DATA_DIR) + "/box.png";

/// A harness around a new pickdetect (h->element) whose properties are set, as by g_object_set,
/// before the harness starts it: pickdetect_harness("model", path, "threads", 2).
template <typename... Rest>
GstHarness* pickdetect_harness(const char* first_property, Rest... rest) {
  GstElement* element = gst_element_factory_make("pickdetect", nullptr);
  fail_unless(element != nullptr, "pickdetect not found: is GST_PLUGIN_PATH set?");
  gst_object_ref_sink(element);
  g_object_set(element, first_property, rest..., nullptr);
  GstHarness* h = gst_harness_new_with_element(element, "sink", "src");
  gst_object_unref(element);
  return h;
}

/// The GstVideoRegionOfInterestMetas of `buffer`, in the buffer's order (owned by the buffer).
inline std::vector<GstVideoRegionOfInterestMeta*> roi_metas(GstBuffer* buffer) {
  std::vector<GstVideoRegionOfInterestMeta*> rois;
  gpointer state = nullptr;
  while (GstMeta* m = gst_buffer_iterate_meta_filtered(buffer, &state,
                                                       GST_VIDEO_REGION_OF_INTEREST_META_API_TYPE))
    rois.push_back(reinterpret_cast<GstVideoRegionOfInterestMeta*>(m));
  return rois;
}

/// The "pick-instance" parameters pickdetect gives a region of interest (nullptr: none).
inline const GstStructure* roi_param(GstVideoRegionOfInterestMeta* roi) {
  return gst_video_region_of_interest_meta_get_param(roi, "pick-instance");
}

/// A new test case `name` added to `suite`, its timeout `timeout_seconds` (0: gst-check's
/// default, CK_DEFAULT_TIMEOUT). Its tests are added with tcase_add_test, which keeps their
/// names for GST_CHECKS.
inline TCase* add_tcase(Suite* suite, const char* name, double timeout_seconds = 0) {
  TCase* tc = tcase_create(name);
  if (timeout_seconds > 0)
    tcase_set_timeout(tc, timeout_seconds);
  suite_add_tcase(suite, tc);
  return tc;
}

} // namespace pickdetect::test_harness
