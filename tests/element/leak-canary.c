/* SPDX-License-Identifier: LGPL-2.1-or-later
 *
 * Leaks a buffer on purpose. Run like the element tests (gst-check, GST_TRACERS=leaks) it must
 * fail: meson expects it to (should_fail), which proves a leak in the element tests would not go
 * unnoticed.
 */
#include <gst/check/gstcheck.h>

static GstBuffer* leaked;

GST_START_TEST(test_leak_on_purpose) {
  leaked = gst_buffer_new_allocate(NULL, 16, NULL);
  fail_unless(leaked != NULL);
}
GST_END_TEST;

static Suite* leakcanary_suite(void) {
  Suite* s = suite_create("leak-canary");
  TCase* tc = tcase_create("leak");
  suite_add_tcase(s, tc);
  tcase_add_test(tc, test_leak_on_purpose);
  return s;
}

GST_CHECK_MAIN(leakcanary);
