/* SPDX-License-Identifier: LGPL-2.1-or-later
 *
 * Uses GstPickDetectMeta from plain C, through its public header and library only: adds a meta
 * with an instance, copies the buffer, scales it the way videoscale does, and reads it back.
 * Built by meson against the library and, in pkg-config-build.sh, with
 * `cc $(pkg-config --cflags --libs gstreamer-pickdetect-meta-1.0)`.
 */
#include <gst/pickdetect/pickdetect-meta.h>
#include <gst/video/video.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#define CHECK(cond)                                                                                \
  do {                                                                                             \
    if (!(cond)) {                                                                                 \
      fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond);                     \
      return 1;                                                                                    \
    }                                                                                              \
  } while (0)

int main(int argc, char** argv) {
  gst_init(&argc, &argv);

  GstBuffer* buffer = gst_buffer_new_allocate(NULL, 640 * 480, NULL);
  GstPickDetectMeta* meta = gst_buffer_add_pickdetect_meta(buffer);
  CHECK(meta != NULL);
  CHECK(gst_pickdetect_meta_get_n_instances(meta) == 0);

  GstPickDetectPoint points[3] = {{100.0, 50.0}, {80.0, 40.0}, {120.0, 60.0}};
  GstPickDetectPoint outline[4] = {{70.0, 30.0}, {130.0, 30.0}, {130.0, 70.0}, {70.0, 70.0}};
  GstPickDetectInstance instance = {0};
  instance.model_name = "box";
  instance.center_x = 100.0;
  instance.center_y = 50.0;
  instance.angle = 30.0;
  instance.scale = 0.8;
  instance.score = 0.9;
  instance.matches = 42;
  instance.n_points = 3;
  instance.points = points;
  instance.n_outline = 4;
  instance.outline = outline;
  instance.visibility = 0.75;
  instance.covered = TRUE;
  instance.pickable = FALSE;
  instance.pick_order = 0;
  instance.grasp_x = 100.0;
  instance.grasp_y = 50.0;
  instance.grasp_angle = 30.0;
  GstPickDetectPoint world_outline[4] = {{-10.0, 5.0}, {50.0, 5.0}, {50.0, 45.0}, {-10.0, 45.0}};
  instance.calibrated = TRUE;
  instance.world_x = 20.0;
  instance.world_y = 25.0;
  instance.world_angle = 300.0;
  instance.grasp_world_x = 21.0;
  instance.grasp_world_y = 26.0;
  instance.n_world_outline = 4;
  instance.world_outline = world_outline;
  instance.height = 35.0;
  instance.view_name = "front";
  const GstPickDetectInstance* added = gst_pickdetect_meta_add_instance(meta, &instance);
  CHECK(added != NULL && added->points != points && added->model_name != instance.model_name);
  CHECK(added->world_outline != world_outline && added->world_outline[1].x == 50.0);
  points[0].x = -1.0; /* The meta holds its own copy. */
  world_outline[1].x = -1.0;

  CHECK(gst_buffer_get_pickdetect_meta(buffer) == meta);
  CHECK(gst_pickdetect_meta_get_n_instances(meta) == 1);
  CHECK(gst_pickdetect_meta_get_instance(meta, 1) == NULL);
  const GstPickDetectInstance* got = gst_pickdetect_meta_get_instance(meta, 0);
  CHECK(strcmp(got->model_name, "box") == 0);
  CHECK(got->view_name != instance.view_name && strcmp(got->view_name, "front") == 0);
  CHECK(got->points[0].x == 100.0 && got->n_outline == 4 && got->matches == 42);
  CHECK(got->visibility == 0.75 && got->covered && !got->pickable && got->pick_order == 0);

  /* The API type carries the video tags that let videoscale and videoconvert keep it. */
  CHECK(gst_meta_api_type_has_tag(GST_PICKDETECT_META_API_TYPE,
                                  g_quark_from_string(GST_META_TAG_VIDEO_STR)));
  CHECK(gst_meta_api_type_has_tag(GST_PICKDETECT_META_API_TYPE,
                                  g_quark_from_string(GST_META_TAG_VIDEO_SIZE_STR)));
  CHECK(gst_meta_api_type_has_tag(GST_PICKDETECT_META_API_TYPE,
                                  g_quark_from_string(GST_META_TAG_VIDEO_ORIENTATION_STR)));
  CHECK(GST_PICKDETECT_META_INFO->api == GST_PICKDETECT_META_API_TYPE);

  /* A buffer copy copies the meta. */
  GstBuffer* copy = gst_buffer_copy(buffer);
  GstPickDetectMeta* copied = gst_buffer_get_pickdetect_meta(copy);
  CHECK(copied != NULL && copied != meta && copied->n_instances == 1);
  CHECK(copied->instances[0].points != got->points);
  CHECK(copied->instances[0].outline[2].x == 130.0);
  CHECK(copied->instances[0].covered && !copied->instances[0].pickable);
  CHECK(copied->instances[0].world_outline != got->world_outline);
  CHECK(copied->instances[0].view_name != got->view_name &&
        strcmp(copied->instances[0].view_name, "front") == 0);
  CHECK(copied->instances[0].n_world_outline == 4 &&
        copied->instances[0].world_outline[1].x == 50.0);

  /* The videoscale transform: 640x480 -> 320x240 halves everything. */
  GstVideoInfo in_info, out_info;
  gst_video_info_set_format(&in_info, GST_VIDEO_FORMAT_GRAY8, 640, 480);
  gst_video_info_set_format(&out_info, GST_VIDEO_FORMAT_GRAY8, 320, 240);
  GstVideoMetaTransform trans = {&in_info, &out_info};
  GstBuffer* scaled = gst_buffer_new_allocate(NULL, 320 * 240, NULL);
  CHECK(meta->meta.info->transform_func(scaled, (GstMeta*)meta, buffer,
                                        gst_video_meta_transform_scale_get_quark(), &trans));
  GstPickDetectMeta* half = gst_buffer_get_pickdetect_meta(scaled);
  CHECK(half != NULL && half->n_instances == 1);
  const GstPickDetectInstance* h = gst_pickdetect_meta_get_instance(half, 0);
  CHECK(h->center_x == 50.0 && h->center_y == 25.0 && h->grasp_x == 50.0);
  CHECK(h->outline[2].x == 65.0 && h->outline[2].y == 35.0 && h->points[1].y == 20.0);
  CHECK(fabs(h->scale - 0.4) < 1e-12 && h->angle == 30.0);
  /* Occlusion does not change with the frame's size. */
  CHECK(h->covered && !h->pickable && h->pick_order == 0 && h->visibility == 0.75);
  /* Nor do positions on the work plane. */
  CHECK(h->calibrated && h->world_x == 20.0 && h->world_y == 25.0 && h->world_angle == 300.0);
  CHECK(h->grasp_world_x == 21.0 && h->grasp_world_y == 26.0 && h->height == 35.0);
  CHECK(h->n_world_outline == 4 && h->world_outline[2].x == 50.0 && h->world_outline[2].y == 45.0);

  gst_buffer_unref(scaled);
  gst_buffer_unref(copy);
  gst_buffer_unref(buffer);
  gst_deinit();
  printf("GstPickDetectMeta C API: ok\n");
  return 0;
}
