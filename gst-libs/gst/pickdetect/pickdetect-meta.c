/* SPDX-License-Identifier: LGPL-2.1-or-later */
/**
 * SECTION:gstpickdetectmeta
 * @title: GstPickDetectMeta
 * @short_description: the object instances the pickdetect element found in a frame
 * @see_also: #GstVideoRegionOfInterestMeta
 *
 * Every buffer that went through pickdetect carries exactly one #GstPickDetectMeta, also when
 * nothing was found. Its instances (#GstPickDetectInstance) give each object's model, pose,
 * principal points, outline, score, visibility, whether it is covered, whether it can be picked
 * and in which order, and with a calibration its place on the work plane in millimetres.
 * Positions are in pixels of the frame the meta is attached to; they follow the frame through
 * videoscale. Build against it with `pkg-config --cflags --libs gstreamer-pickdetect-meta-1.0`
 * and include <gst/pickdetect/pickdetect-meta.h>.
 *
 * Since: 0.1
 */
#include <gst/pickdetect/pickdetect-meta.h>

#include <gst/video/video.h>

#include <math.h>
#include <string.h>

static void instance_clear(GstPickDetectInstance* instance) {
  g_free(instance->model_name);
  g_free(instance->view_name);
  g_free(instance->points);
  g_free(instance->outline);
  g_free(instance->world_outline);
  memset(instance, 0, sizeof(*instance));
}

static void instance_copy(GstPickDetectInstance* dest, const GstPickDetectInstance* src) {
  *dest = *src;
  dest->model_name = g_strdup(src->model_name ? src->model_name : "");
  dest->view_name = g_strdup(src->view_name ? src->view_name : "");
  dest->points =
      src->n_points ? g_memdup2(src->points, sizeof(GstPickDetectPoint) * src->n_points) : NULL;
  dest->outline =
      src->n_outline ? g_memdup2(src->outline, sizeof(GstPickDetectPoint) * src->n_outline) : NULL;
  dest->world_outline =
      src->n_world_outline && src->world_outline
          ? g_memdup2(src->world_outline, sizeof(GstPickDetectPoint) * src->n_world_outline)
          : NULL;
  if (!dest->world_outline)
    dest->n_world_outline = 0;
  if (!dest->points)
    dest->n_points = 0;
  if (!dest->outline)
    dest->n_outline = 0;
}

/* An angle in degrees (clockwise, y down) after stretching the picture by sx, sy. */
static gdouble stretch_angle(gdouble angle, gdouble sx, gdouble sy) {
  if (sx == sy)
    return angle;
  const gdouble radians = angle * G_PI / 180.0;
  gdouble out = atan2(sy * sin(radians), sx * cos(radians)) * 180.0 / G_PI;
  if (out < 0.0)
    out += 360.0;
  if (out >= 360.0)
    out -= 360.0;
  return out;
}

/* Pixel positions follow the frame; those on the plane (world_*) stay as they are. */
static void instance_scale(GstPickDetectInstance* instance, gdouble sx, gdouble sy) {
  instance->center_x *= sx;
  instance->center_y *= sy;
  instance->grasp_x *= sx;
  instance->grasp_y *= sy;
  for (guint i = 0; i < instance->n_points; i++) {
    instance->points[i].x *= sx;
    instance->points[i].y *= sy;
  }
  for (guint i = 0; i < instance->n_outline; i++) {
    instance->outline[i].x *= sx;
    instance->outline[i].y *= sy;
  }
  instance->velocity_x *= sx;
  instance->velocity_y *= sy;
  instance->angle = stretch_angle(instance->angle, sx, sy);
  instance->grasp_angle = stretch_angle(instance->grasp_angle, sx, sy);
  instance->scale *= sqrt(sx * sy);
}

static gboolean gst_pickdetect_meta_init(GstMeta* meta, gpointer params, GstBuffer* buffer) {
  (void)params;
  (void)buffer;
  GstPickDetectMeta* pmeta = (GstPickDetectMeta*)meta;
  pmeta->n_instances = 0;
  pmeta->instances = NULL;
  pmeta->has_motion = FALSE;
  pmeta->motion_x = 0.0;
  pmeta->motion_y = 0.0;
  return TRUE;
}

static void gst_pickdetect_meta_free(GstMeta* meta, GstBuffer* buffer) {
  (void)buffer;
  GstPickDetectMeta* pmeta = (GstPickDetectMeta*)meta;
  for (guint i = 0; i < pmeta->n_instances; i++)
    instance_clear(&pmeta->instances[i]);
  g_free(pmeta->instances);
  pmeta->instances = NULL;
  pmeta->n_instances = 0;
}

static gboolean gst_pickdetect_meta_transform(GstBuffer* dest, GstMeta* meta, GstBuffer* buffer,
                                              GQuark type, gpointer data) {
  (void)buffer;
  const GstPickDetectMeta* src = (const GstPickDetectMeta*)meta;
  gdouble sx = 1.0, sy = 1.0;

  if (GST_META_TRANSFORM_IS_COPY(type)) {
    /* Copied whole, also for region copies: the meta describes the frame, not bytes. */
  } else if (GST_VIDEO_META_TRANSFORM_IS_SCALE(type)) {
    const GstVideoMetaTransform* trans = (const GstVideoMetaTransform*)data;
    const gint in_w = GST_VIDEO_INFO_WIDTH(trans->in_info);
    const gint in_h = GST_VIDEO_INFO_HEIGHT(trans->in_info);
    if (in_w <= 0 || in_h <= 0)
      return FALSE;
    sx = (gdouble)GST_VIDEO_INFO_WIDTH(trans->out_info) / in_w;
    sy = (gdouble)GST_VIDEO_INFO_HEIGHT(trans->out_info) / in_h;
  } else {
    /* Unknown transform (crop, flip...): the coordinates would be wrong, so drop the meta. */
    return FALSE;
  }

  GstPickDetectMeta* out = gst_buffer_add_pickdetect_meta(dest);
  if (!out)
    return FALSE;
  out->has_motion = src->has_motion;
  out->motion_x = src->motion_x * sx;
  out->motion_y = src->motion_y * sy;
  for (guint i = 0; i < src->n_instances; i++) {
    GstPickDetectInstance* copy =
        (GstPickDetectInstance*)gst_pickdetect_meta_add_instance(out, &src->instances[i]);
    if (sx != 1.0 || sy != 1.0)
      instance_scale(copy, sx, sy);
  }
  return TRUE;
}

/**
 * gst_pickdetect_meta_api_get_type:
 *
 * The registered API type, "GstPickDetectMetaAPI", tagged video, size and orientation.
 *
 * Returns: the #GType of the meta's API
 *
 * Since: 0.1
 */
GType gst_pickdetect_meta_api_get_type(void) {
  static GType type = 0;
  static const gchar* tags[] = {GST_META_TAG_VIDEO_STR, GST_META_TAG_VIDEO_SIZE_STR,
                                GST_META_TAG_VIDEO_ORIENTATION_STR, NULL};
  if (g_once_init_enter(&type)) {
    GType registered = gst_meta_api_type_register("GstPickDetectMetaAPI", tags);
    g_once_init_leave(&type, registered);
  }
  return type;
}

/**
 * gst_pickdetect_meta_get_info:
 *
 * The implementation, "GstPickDetectMeta": its init, free and transform functions (copies are
 * deep; a scale transform rescales every pixel position).
 *
 * Returns: (transfer none): the meta's #GstMetaInfo
 *
 * Since: 0.1
 */
const GstMetaInfo* gst_pickdetect_meta_get_info(void) {
  static const GstMetaInfo* info = NULL;
  if (g_once_init_enter((GstMetaInfo**)&info)) {
    const GstMetaInfo* registered = gst_meta_register(
        GST_PICKDETECT_META_API_TYPE, "GstPickDetectMeta", sizeof(GstPickDetectMeta),
        gst_pickdetect_meta_init, gst_pickdetect_meta_free, gst_pickdetect_meta_transform);
    g_once_init_leave((GstMetaInfo**)&info, (GstMetaInfo*)registered);
  }
  return info;
}

/**
 * gst_buffer_add_pickdetect_meta:
 * @buffer: a writable #GstBuffer
 *
 * Adds an empty meta (no instance) to @buffer.
 *
 * Returns: (transfer none): the meta, owned by @buffer
 *
 * Since: 0.1
 */
GstPickDetectMeta* gst_buffer_add_pickdetect_meta(GstBuffer* buffer) {
  g_return_val_if_fail(GST_IS_BUFFER(buffer), NULL);
  g_return_val_if_fail(gst_buffer_is_writable(buffer), NULL);
  return (GstPickDetectMeta*)gst_buffer_add_meta(buffer, GST_PICKDETECT_META_INFO, NULL);
}

/**
 * gst_buffer_get_pickdetect_meta:
 * @buffer: a #GstBuffer
 *
 * Returns: (transfer none) (nullable): the first #GstPickDetectMeta of @buffer, or %NULL
 *
 * Since: 0.1
 */
GstPickDetectMeta* gst_buffer_get_pickdetect_meta(GstBuffer* buffer) {
  g_return_val_if_fail(GST_IS_BUFFER(buffer), NULL);
  return (GstPickDetectMeta*)gst_buffer_get_meta(buffer, GST_PICKDETECT_META_API_TYPE);
}

/**
 * gst_pickdetect_meta_get_n_instances:
 * @meta: a #GstPickDetectMeta
 *
 * Returns: the number of instances in @meta
 *
 * Since: 0.1
 */
guint gst_pickdetect_meta_get_n_instances(const GstPickDetectMeta* meta) {
  g_return_val_if_fail(meta != NULL, 0);
  return meta->n_instances;
}

/**
 * gst_pickdetect_meta_get_instance:
 * @meta: a #GstPickDetectMeta
 * @index: which instance, below gst_pickdetect_meta_get_n_instances()
 *
 * Returns: (transfer none) (nullable): the instance at @index, owned by @meta, or %NULL when
 *   @index is out of range
 *
 * Since: 0.1
 */
const GstPickDetectInstance* gst_pickdetect_meta_get_instance(const GstPickDetectMeta* meta,
                                                              guint index) {
  g_return_val_if_fail(meta != NULL, NULL);
  if (index >= meta->n_instances)
    return NULL;
  return &meta->instances[index];
}

/**
 * gst_pickdetect_meta_add_instance:
 * @meta: a #GstPickDetectMeta of a writable buffer
 * @instance: the instance to append
 *
 * Appends a deep copy of @instance (its strings and arrays are copied; the caller keeps its
 * own).
 *
 * Returns: (transfer none): the meta's copy
 *
 * Since: 0.1
 */
const GstPickDetectInstance*
gst_pickdetect_meta_add_instance(GstPickDetectMeta* meta, const GstPickDetectInstance* instance) {
  g_return_val_if_fail(meta != NULL, NULL);
  g_return_val_if_fail(instance != NULL, NULL);
  meta->instances = g_renew(GstPickDetectInstance, meta->instances, meta->n_instances + 1);
  GstPickDetectInstance* slot = &meta->instances[meta->n_instances];
  instance_copy(slot, instance);
  meta->n_instances++;
  return slot;
}
