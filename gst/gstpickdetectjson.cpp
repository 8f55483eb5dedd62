// SPDX-License-Identifier: LGPL-2.1-or-later
/**
 * SECTION:element-pickdetectjson
 * @title: pickdetectjson
 *
 * Turns the video buffers that pickdetect annotated into JSON lines: one JSON object per frame,
 * on one line ending in a newline, in one output buffer (caps application/x-json) carrying the
 * frame's timestamps, for any sink: filesink, fdsink, tcpserversink, udpsink, appsink...
 *
 * Each line holds the frame's number (counted from 0 since the element started), pts, dts,
 * duration, running_time and stream_time (nanoseconds, null when unknown), width and height
 * (pixels, from the caps), and "instances": one object per instance of the frame's
 * GstPickDetectMeta, in the meta's order, with the meta's fields under the same names: model,
 * view (the meta's view_name: the product's view it matched, "" for a model of one picture),
 * center_x, center_y, angle, scale, score, matches, visibility, covered, pickable, pick_order,
 * grasp_x, grasp_y, grasp_angle, points and outline ([[x, y], ...], pixels), height and
 * calibrated, and, when calibrated (pickdetect's calibration property), world_x, world_y,
 * world_angle, grasp_world_x, grasp_world_y and world_outline (millimetres on the work plane);
 * with tracking (pickdetect's tracking property), track_id, first_seen (ns), frames_seen,
 * velocity_x, velocity_y (pixels per second), tracked, and, when calibrated too,
 * world_velocity_x and world_velocity_y (millimetres per second).
 * The format, with an example, is in docs/robot-output.md.
 *
 * #GstPickDetectJson:add-empty-results chooses whether frames with no instance (or with no
 * GstPickDetectMeta at all) are written; when they are not, a gap event takes their place, so
 * that downstream keeps the time.
 *
 * The video itself goes no further: put a tee before this element to also show or record it.
 *
 * ## Example launch line
 * |[
 * gst-launch-1.0 filesrc location=/usr/share/doc/opencv-doc/examples/data/box_in_scene.png ! \
 *   pngdec ! imagefreeze num-buffers=3 ! videoconvert ! \
 *   pickdetect model=/usr/share/doc/opencv-doc/examples/data/box.png ! pickdetectjson ! \
 *   fdsink fd=1
 * ]| Prints three JSON lines, each with the box found in the scene.
 */
#include "gstpickdetectjson.h"

#include <gst/pickdetect/pickdetect-meta.h>

#include <json-glib/json-glib.h>

#include <cmath>
#include <initializer_list>

GST_DEBUG_CATEGORY_STATIC(gst_pick_detect_json_debug);
#define GST_CAT_DEFAULT gst_pick_detect_json_debug

enum {
  PROP_0,
  PROP_ADD_EMPTY_RESULTS,
};

constexpr gboolean DEFAULT_ADD_EMPTY_RESULTS = FALSE;

struct _GstPickDetectJson {
  GstElement parent;
  GstPad* sinkpad;
  GstPad* srcpad;
  gboolean add_empty_results; ///< Property; object lock.
  // ---- streaming thread ----
  guint64 frame;      ///< Frames seen since start.
  gint width, height; ///< From the caps; 0 before.
  GstSegment segment; ///< For running and stream time.
};

#define gst_pick_detect_json_parent_class parent_class
G_DEFINE_TYPE(GstPickDetectJson, gst_pick_detect_json, GST_TYPE_ELEMENT);
GST_ELEMENT_REGISTER_DEFINE_WITH_CODE(pickdetectjson, "pickdetectjson", GST_RANK_NONE,
                                      GST_TYPE_PICK_DETECT_JSON,
                                      GST_DEBUG_CATEGORY_INIT(gst_pick_detect_json_debug,
                                                              "pickdetectjson", 0,
                                                              "pickdetectjson element"));

#define PICKDETECT_JSON_CAPS "application/x-json"

static GstStaticPadTemplate sink_template = GST_STATIC_PAD_TEMPLATE(
    "sink", GST_PAD_SINK, GST_PAD_ALWAYS, GST_STATIC_CAPS("video/x-raw(ANY)"));
static GstStaticPadTemplate src_template = GST_STATIC_PAD_TEMPLATE(
    "src", GST_PAD_SRC, GST_PAD_ALWAYS, GST_STATIC_CAPS(PICKDETECT_JSON_CAPS));

namespace {

/// JSON has no NaN nor infinity: such a value is written as null.
void add_number(JsonBuilder* b, const char* name, double value) {
  json_builder_set_member_name(b, name);
  if (std::isfinite(value))
    json_builder_add_double_value(b, value);
  else
    json_builder_add_null_value(b);
}

void add_time(JsonBuilder* b, const char* name, GstClockTime t) {
  json_builder_set_member_name(b, name);
  if (GST_CLOCK_TIME_IS_VALID(t))
    json_builder_add_int_value(b, static_cast<gint64>(t));
  else
    json_builder_add_null_value(b);
}

void add_points(JsonBuilder* b, const char* name, const GstPickDetectPoint* points, guint n) {
  json_builder_set_member_name(b, name);
  json_builder_begin_array(b);
  for (guint i = 0; i < n; i++) {
    json_builder_begin_array(b);
    for (const double v : {points[i].x, points[i].y}) {
      if (std::isfinite(v))
        json_builder_add_double_value(b, v);
      else
        json_builder_add_null_value(b);
    }
    json_builder_end_array(b);
  }
  json_builder_end_array(b);
}

void add_instance(JsonBuilder* b, const GstPickDetectInstance& in) {
  json_builder_begin_object(b);
  json_builder_set_member_name(b, "model");
  json_builder_add_string_value(b, in.model_name ? in.model_name : "");
  json_builder_set_member_name(b, "view");
  json_builder_add_string_value(b, in.view_name ? in.view_name : "");
  add_number(b, "center_x", in.center_x);
  add_number(b, "center_y", in.center_y);
  add_number(b, "angle", in.angle);
  add_number(b, "scale", in.scale);
  add_number(b, "score", in.score);
  json_builder_set_member_name(b, "matches");
  json_builder_add_int_value(b, in.matches);
  add_number(b, "visibility", in.visibility);
  json_builder_set_member_name(b, "covered");
  json_builder_add_boolean_value(b, in.covered);
  json_builder_set_member_name(b, "pickable");
  json_builder_add_boolean_value(b, in.pickable);
  json_builder_set_member_name(b, "pick_order");
  json_builder_add_int_value(b, in.pick_order);
  add_number(b, "grasp_x", in.grasp_x);
  add_number(b, "grasp_y", in.grasp_y);
  add_number(b, "grasp_angle", in.grasp_angle);
  add_points(b, "points", in.points, in.n_points);
  add_points(b, "outline", in.outline, in.n_outline);
  add_number(b, "height", in.height);
  json_builder_set_member_name(b, "calibrated");
  json_builder_add_boolean_value(b, in.calibrated);
  if (in.calibrated) {
    add_number(b, "world_x", in.world_x);
    add_number(b, "world_y", in.world_y);
    add_number(b, "world_angle", in.world_angle);
    add_number(b, "grasp_world_x", in.grasp_world_x);
    add_number(b, "grasp_world_y", in.grasp_world_y);
    add_points(b, "world_outline", in.world_outline, in.n_world_outline);
  }
  if (in.track_id != 0) { // tracking (pickdetect's tracking property)
    json_builder_set_member_name(b, "track_id");
    json_builder_add_int_value(b, static_cast<gint64>(in.track_id));
    json_builder_set_member_name(b, "first_seen");
    json_builder_add_int_value(b, static_cast<gint64>(in.first_seen));
    json_builder_set_member_name(b, "frames_seen");
    json_builder_add_int_value(b, in.frames_seen);
    add_number(b, "velocity_x", in.velocity_x);
    add_number(b, "velocity_y", in.velocity_y);
    json_builder_set_member_name(b, "tracked");
    json_builder_add_boolean_value(b, in.tracked);
    if (in.calibrated) {
      add_number(b, "world_velocity_x", in.world_velocity_x);
      add_number(b, "world_velocity_y", in.world_velocity_y);
    }
  }
  json_builder_end_object(b);
}

/// The frame's line, newline included; g_free it.
gchar* frame_line(GstPickDetectJson* self, GstBuffer* buffer, const GstPickDetectMeta* meta,
                  gsize* length) {
  JsonBuilder* b = json_builder_new_immutable();
  json_builder_begin_object(b);
  json_builder_set_member_name(b, "frame");
  json_builder_add_int_value(b, static_cast<gint64>(self->frame));
  const GstClockTime pts = GST_BUFFER_PTS(buffer);
  add_time(b, "pts", pts);
  add_time(b, "dts", GST_BUFFER_DTS(buffer));
  add_time(b, "duration", GST_BUFFER_DURATION(buffer));
  GstClockTime running = GST_CLOCK_TIME_NONE, stream = GST_CLOCK_TIME_NONE;
  if (self->segment.format == GST_FORMAT_TIME && GST_CLOCK_TIME_IS_VALID(pts)) {
    running = gst_segment_to_running_time(&self->segment, GST_FORMAT_TIME, pts);
    stream = gst_segment_to_stream_time(&self->segment, GST_FORMAT_TIME, pts);
  }
  add_time(b, "running_time", running);
  add_time(b, "stream_time", stream);
  json_builder_set_member_name(b, "width");
  json_builder_add_int_value(b, self->width);
  json_builder_set_member_name(b, "height");
  json_builder_add_int_value(b, self->height);
  json_builder_set_member_name(b, "instances");
  json_builder_begin_array(b);
  const guint n = meta ? gst_pickdetect_meta_get_n_instances(meta) : 0;
  for (guint i = 0; i < n; i++)
    add_instance(b, *gst_pickdetect_meta_get_instance(meta, i));
  json_builder_end_array(b);
  json_builder_end_object(b);

  JsonNode* root = json_builder_get_root(b);
  JsonGenerator* generator = json_generator_new();
  json_generator_set_root(generator, root);
  gsize size = 0;
  gchar* text = json_generator_to_data(generator, &size);
  g_object_unref(generator);
  json_node_unref(root);
  g_object_unref(b);
  gchar* line = static_cast<gchar*>(g_realloc(text, size + 2));
  line[size] = '\n';
  line[size + 1] = '\0';
  *length = size + 1;
  return line;
}

} // namespace

static GstFlowReturn gst_pick_detect_json_chain(GstPad* pad, GstObject* parent, GstBuffer* buffer) {
  (void)pad;
  GstPickDetectJson* self = GST_PICK_DETECT_JSON(parent);
  GST_OBJECT_LOCK(self);
  const gboolean add_empty = self->add_empty_results;
  GST_OBJECT_UNLOCK(self);

  const GstPickDetectMeta* meta = gst_buffer_get_pickdetect_meta(buffer);
  const guint n = meta ? gst_pickdetect_meta_get_n_instances(meta) : 0;
  if (!meta)
    GST_LOG_OBJECT(self, "frame %" G_GUINT64_FORMAT " has no GstPickDetectMeta", self->frame);
  if (n == 0 && !add_empty) {
    GST_LOG_OBJECT(self, "frame %" G_GUINT64_FORMAT ": no instance, not written", self->frame);
    self->frame++;
    const GstClockTime pts = GST_BUFFER_PTS(buffer);
    const GstClockTime duration = GST_BUFFER_DURATION(buffer);
    gst_buffer_unref(buffer);
    if (GST_CLOCK_TIME_IS_VALID(pts))
      gst_pad_push_event(self->srcpad, gst_event_new_gap(pts, duration));
    return GST_FLOW_OK;
  }

  gsize length = 0;
  gchar* line = frame_line(self, buffer, meta, &length);
  self->frame++;
  GstBuffer* out = gst_buffer_new_wrapped(line, length);
  gst_buffer_copy_into(out, buffer, GST_BUFFER_COPY_TIMESTAMPS, 0, static_cast<gsize>(-1));
  GST_BUFFER_OFFSET(out) = GST_BUFFER_OFFSET_NONE;
  GST_BUFFER_OFFSET_END(out) = GST_BUFFER_OFFSET_NONE;
  if (GST_BUFFER_FLAG_IS_SET(buffer, GST_BUFFER_FLAG_DISCONT))
    GST_BUFFER_FLAG_SET(out, GST_BUFFER_FLAG_DISCONT);
  gst_buffer_unref(buffer);
  return gst_pad_push(self->srcpad, out);
}

static gboolean gst_pick_detect_json_sink_event(GstPad* pad, GstObject* parent, GstEvent* event) {
  GstPickDetectJson* self = GST_PICK_DETECT_JSON(parent);
  switch (GST_EVENT_TYPE(event)) {
  case GST_EVENT_CAPS: {
    GstCaps* caps = nullptr;
    gst_event_parse_caps(event, &caps);
    const GstStructure* s = gst_caps_get_structure(caps, 0);
    gint width = 0, height = 0;
    if (!gst_structure_get_int(s, "width", &width) ||
        !gst_structure_get_int(s, "height", &height)) {
      GST_ELEMENT_ERROR(self, CORE, NEGOTIATION, (nullptr),
                        ("video caps without width and height: %" GST_PTR_FORMAT, caps));
      gst_event_unref(event);
      return FALSE;
    }
    self->width = width;
    self->height = height;
    gst_event_unref(event);
    GstCaps* out = gst_caps_from_string(PICKDETECT_JSON_CAPS);
    const gboolean ok = gst_pad_push_event(self->srcpad, gst_event_new_caps(out));
    gst_caps_unref(out);
    return ok;
  }
  case GST_EVENT_SEGMENT:
    gst_event_copy_segment(event, &self->segment);
    break;
  case GST_EVENT_FLUSH_STOP:
    gst_segment_init(&self->segment, GST_FORMAT_TIME);
    break;
  default:
    break;
  }
  return gst_pad_event_default(pad, parent, event);
}

static GstStateChangeReturn gst_pick_detect_json_change_state(GstElement* element,
                                                              GstStateChange transition) {
  GstPickDetectJson* self = GST_PICK_DETECT_JSON(element);
  if (transition == GST_STATE_CHANGE_READY_TO_PAUSED) {
    self->frame = 0;
    self->width = self->height = 0;
    gst_segment_init(&self->segment, GST_FORMAT_TIME);
  }
  return GST_ELEMENT_CLASS(parent_class)->change_state(element, transition);
}

static void gst_pick_detect_json_set_property(GObject* object, guint prop_id, const GValue* value,
                                              GParamSpec* pspec) {
  GstPickDetectJson* self = GST_PICK_DETECT_JSON(object);
  switch (prop_id) {
  case PROP_ADD_EMPTY_RESULTS:
    GST_OBJECT_LOCK(self);
    self->add_empty_results = g_value_get_boolean(value);
    GST_OBJECT_UNLOCK(self);
    break;
  default:
    G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
    break;
  }
}

static void gst_pick_detect_json_get_property(GObject* object, guint prop_id, GValue* value,
                                              GParamSpec* pspec) {
  GstPickDetectJson* self = GST_PICK_DETECT_JSON(object);
  switch (prop_id) {
  case PROP_ADD_EMPTY_RESULTS:
    GST_OBJECT_LOCK(self);
    g_value_set_boolean(value, self->add_empty_results);
    GST_OBJECT_UNLOCK(self);
    break;
  default:
    G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
    break;
  }
}

static void gst_pick_detect_json_init(GstPickDetectJson* self) {
  self->sinkpad = gst_pad_new_from_static_template(&sink_template, "sink");
  gst_pad_set_chain_function(self->sinkpad, GST_DEBUG_FUNCPTR(gst_pick_detect_json_chain));
  gst_pad_set_event_function(self->sinkpad, GST_DEBUG_FUNCPTR(gst_pick_detect_json_sink_event));
  gst_element_add_pad(GST_ELEMENT(self), self->sinkpad);
  self->srcpad = gst_pad_new_from_static_template(&src_template, "src");
  gst_pad_use_fixed_caps(self->srcpad);
  gst_element_add_pad(GST_ELEMENT(self), self->srcpad);
  self->add_empty_results = DEFAULT_ADD_EMPTY_RESULTS;
  gst_segment_init(&self->segment, GST_FORMAT_TIME);
}

static void gst_pick_detect_json_class_init(GstPickDetectJsonClass* klass) {
  GObjectClass* gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass* element_class = GST_ELEMENT_CLASS(klass);
  gobject_class->set_property = gst_pick_detect_json_set_property;
  gobject_class->get_property = gst_pick_detect_json_get_property;
  element_class->change_state = GST_DEBUG_FUNCPTR(gst_pick_detect_json_change_state);

  g_object_class_install_property(
      gobject_class, PROP_ADD_EMPTY_RESULTS,
      g_param_spec_boolean(
          "add-empty-results", "Add empty results",
          "Also write a line for frames with no instance (\"instances\": []), as DL Streamer's "
          "add-empty-results; otherwise such frames give no line (a gap event instead)",
          DEFAULT_ADD_EMPTY_RESULTS,
          static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                   GST_PARAM_MUTABLE_PLAYING)));

  gst_element_class_set_static_metadata(
      element_class, "Pick detection to JSON", "Formatter/Metadata",
      "Writes the instances pickdetect found in each frame as one JSON line per frame, for any "
      "sink (file, socket, appsink, a broker through fdsink)",
      "gst-pickdetect authors");
  gst_element_class_add_static_pad_template(element_class, &sink_template);
  gst_element_class_add_static_pad_template(element_class, &src_template);
}
