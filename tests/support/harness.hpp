// SPDX-License-Identifier: LGPL-2.1-or-later
// A GstHarness around a lone pickdetect element, set up before it starts. Include after
// gst/check/gstcheck.h and gst/check/gstharness.h.
#pragma once

namespace pickdetect::test_harness {

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

} // namespace pickdetect::test_harness
