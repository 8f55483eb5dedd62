/* SPDX-License-Identifier: LGPL-2.1-or-later
 *
 * GstPickDetectMeta: the object instances the pickdetect element found in a video frame.
 *
 * Every buffer that went through pickdetect carries exactly one GstPickDetectMeta (also when
 * nothing was found: then it holds no instance). Coordinates are in pixels of the frame the meta
 * is attached to, x to the right and y down; they follow the frame through videoscale (the meta
 * is rescaled) and are copied unchanged on buffer copies and through videoconvert.
 *
 * Build against it with `pkg-config --cflags --libs gstreamer-pickdetect-meta-1.0`.
 */
#ifndef GST_PICKDETECT_META_H
#define GST_PICKDETECT_META_H

#include <gst/gst.h>

G_BEGIN_DECLS

#if defined(_WIN32) && !defined(GST_PICKDETECT_META_STATIC)
#ifdef GST_PICKDETECT_META_BUILDING
#define GST_PICKDETECT_META_API __declspec(dllexport) extern
#else
#define GST_PICKDETECT_META_API __declspec(dllimport) extern
#endif
#elif defined(GST_PICKDETECT_META_BUILDING)
#define GST_PICKDETECT_META_API __attribute__((visibility("default"))) extern
#else
#define GST_PICKDETECT_META_API extern
#endif

/**
 * GstPickDetectPoint:
 * @x: column in pixels
 * @y: row in pixels (y axis down)
 *
 * A point of a frame.
 *
 * Since: 0.1
 */
typedef struct {
  gdouble x;
  gdouble y;
} GstPickDetectPoint;

/**
 * GstPickDetectInstance:
 * @model_name: name of the model the instance is of (never %NULL in a meta)
 * @center_x: centre column in pixels
 * @center_y: centre row in pixels
 * @angle: rotation in degrees in [0, 360), clockwise on screen
 * @scale: size in the frame / size in the model picture
 * @score: confidence in [0, 1]
 * @matches: number of feature matches that support the instance
 * @n_points: number of principal points
 * @points: (array length=n_points): principal points; points[0] is the centre
 * @n_outline: number of outline vertices
 * @outline: (array length=n_outline): outline polygon
 * @visibility: estimated share of the outline that is seen (inside the frame and under no other
 *   instance), in [0, 1]
 * @covered: %TRUE when another detected instance lies on this one (or when which of two
 *   overlapping instances is on top could not be told), or when the frame shows something
 *   else than the object over a patch of it (an object of no model lying on it)
 * @pickable: %TRUE when a gripper may take it now: not covered, grasp point in the frame and
 *   enough of it seen
 * @pick_order: 1 = pick first among the pickable instances, 2 = next, ...; 0 = not pickable
 * @grasp_x: grasp point column in pixels
 * @grasp_y: grasp point row in pixels
 * @grasp_angle: gripper angle in degrees
 * @calibrated: %TRUE when the element had a calibration: the world fields below are then set
 *   (otherwise they are all 0 and @world_outline is %NULL)
 * @world_x: centre on the work plane, x in millimetres (plane axes: docs/robot-output.md)
 * @world_y: centre on the work plane, y in millimetres
 * @world_angle: angle on the plane in degrees in [0, 360), from its x axis towards its y axis
 * @grasp_world_x: grasp point on the plane, x in millimetres
 * @grasp_world_y: grasp point on the plane, y in millimetres
 * @n_world_outline: number of vertices of @world_outline (@n_outline when calibrated, else 0)
 * @world_outline: (array length=n_world_outline): the outline on the plane, in millimetres
 * @height: height of the instance's top face above the plane in millimetres (its model's)
 * @track_id: with tracking, the identity of the physical object across the frames of the
 *   stream (unique, never reused, 1 the first); 0 without tracking
 * @first_seen: running time in nanoseconds of the first frame that detected it
 * @frames_seen: frames that detected it, this one included
 * @velocity_x: motion in pixels per second, x
 * @velocity_y: motion in pixels per second, y
 * @tracked: %TRUE when not detected in this frame but carried forward from the earlier ones
 *   (its pose predicted; never pickable)
 * @world_velocity_x: with tracking and a calibration (@calibrated), the motion on the work
 *   plane in millimetres per second, x; 0 otherwise
 * @world_velocity_y: the same, y
 * @view_name: which view of the product it matched: the view's name, for a model file that lists
 *   several pictures of one product (`views`, docs/models.md); "" for a model of one picture
 *   (never %NULL in a meta; @model_name is the product's name). Since: 0.1
 *
 * One object instance. Inside a meta every array and string belongs to the meta. The world
 * fields (on the work plane, in millimetres, lens distortion and the model's height accounted
 * for) come after the pixel ones, and @view_name last, so that code built against the earlier
 * struct reads the same fields. Plane positions do not change when the frame is scaled.
 *
 * Since: 0.1
 */
typedef struct {
  gchar* model_name;
  gdouble center_x;
  gdouble center_y;
  gdouble angle;
  gdouble scale;
  gdouble score;
  gint matches;
  guint n_points;
  GstPickDetectPoint* points;
  guint n_outline;
  GstPickDetectPoint* outline;
  gdouble visibility;
  gboolean covered;
  gboolean pickable;
  gint pick_order;
  gdouble grasp_x;
  gdouble grasp_y;
  gdouble grasp_angle;
  gboolean calibrated;
  gdouble world_x;
  gdouble world_y;
  gdouble world_angle;
  gdouble grasp_world_x;
  gdouble grasp_world_y;
  guint n_world_outline;
  GstPickDetectPoint* world_outline;
  gdouble height;
  guint64 track_id;
  guint64 first_seen;
  guint frames_seen;
  gdouble velocity_x;
  gdouble velocity_y;
  gboolean tracked;
  gdouble world_velocity_x;
  gdouble world_velocity_y;
  gchar* view_name;
} GstPickDetectInstance;

typedef struct _GstPickDetectMeta GstPickDetectMeta;

/**
 * GstPickDetectMeta:
 * @meta: parent #GstMeta
 * @n_instances: number of instances
 * @instances: (array length=n_instances): the instances, in the order the detector gave them
 *   (with tracking, those carried forward after them)
 * @has_motion: %TRUE when tracked instances move together (a belt): @motion_x, @motion_y
 * @motion_x: their common motion in pixels per second, x
 * @motion_y: their common motion in pixels per second, y
 *
 * Read it with gst_pickdetect_meta_get_n_instances() and gst_pickdetect_meta_get_instance().
 *
 * Since: 0.1
 */
struct _GstPickDetectMeta {
  GstMeta meta;
  guint n_instances;
  GstPickDetectInstance* instances;
  gboolean has_motion;
  gdouble motion_x;
  gdouble motion_y;
};

/**
 * GST_PICKDETECT_META_API_TYPE:
 *
 * The #GType of the GstPickDetectMeta API, for gst_buffer_get_meta() and meta transforms.
 *
 * Since: 0.1
 */
#define GST_PICKDETECT_META_API_TYPE (gst_pickdetect_meta_api_get_type())

/**
 * GST_PICKDETECT_META_INFO:
 *
 * The #GstMetaInfo of GstPickDetectMeta, for gst_buffer_add_meta().
 *
 * Since: 0.1
 */
#define GST_PICKDETECT_META_INFO (gst_pickdetect_meta_get_info())

GST_PICKDETECT_META_API
GType gst_pickdetect_meta_api_get_type(void);

GST_PICKDETECT_META_API
const GstMetaInfo* gst_pickdetect_meta_get_info(void);

GST_PICKDETECT_META_API
GstPickDetectMeta* gst_buffer_add_pickdetect_meta(GstBuffer* buffer);

GST_PICKDETECT_META_API
GstPickDetectMeta* gst_buffer_get_pickdetect_meta(GstBuffer* buffer);

GST_PICKDETECT_META_API
guint gst_pickdetect_meta_get_n_instances(const GstPickDetectMeta* meta);

GST_PICKDETECT_META_API
const GstPickDetectInstance* gst_pickdetect_meta_get_instance(const GstPickDetectMeta* meta,
                                                              guint index);

GST_PICKDETECT_META_API
const GstPickDetectInstance*
gst_pickdetect_meta_add_instance(GstPickDetectMeta* meta, const GstPickDetectInstance* instance);

G_END_DECLS

#endif /* GST_PICKDETECT_META_H */
