// SPDX-License-Identifier: LGPL-2.1-or-later
/**
 * SECTION:element-pickdetect
 * @title: pickdetect
 *
 * Finds every instance of one or several known objects in each video frame, for pick-and-place,
 * by the method of "Multiple Object Detection for Pick-and-Place Applications": SIFT features of
 * the frame, matched against those of all the model pictures at once, vote for where each
 * object's principal points (centre, grasping and delimiting points) lie, and mean shift gathers
 * the votes into instances; the paper's two RANSAC baselines can be chosen instead. Each instance
 * comes with its model's name (and, for a product with several pictures, the view it matched),
 * pose, principal points, outline, score, visibility, whether
 * something lies on it (covered), whether it can be picked and in which order, and its grasp
 * point. The frame is worked on in place; its pixels change only with #GstPickDetect:draw.
 *
 * Every buffer that goes through gets, also when nothing was found, one GstPickDetectMeta holding
 * all instances (gst/pickdetect/pickdetect-meta.h, pkg-config gstreamer-pickdetect-meta-1.0;
 * rescaled whole through videoscale) and one #GstVideoRegionOfInterestMeta per instance, whose
 * roi_type is the model name and whose "pick-instance" #GstStructure param holds the same fields.
 * With #GstPickDetect:post-messages an element message "pickdetect" per frame lists those
 * structures and the time of each stage. The metas of the input buffer are kept; on a copy, metas
 * tagged only with video, size, orientation or colorspace tags (or untagged) are copied.
 * With #GstPickDetect:calibration (a file written by pickdetect-calibrate) every instance is
 * also placed on the work plane, in millimetres (docs/robot-output.md).
 *
 * ## Example launch line
 * |[
 * gst-launch-1.0 filesrc location=/usr/share/doc/opencv-doc/examples/data/box_in_scene.png ! \
 *   pngdec ! imagefreeze num-buffers=1 ! videoconvert ! \
 *   pickdetect model=/usr/share/doc/opencv-doc/examples/data/box.png draw=true ! \
 *   videoconvert ! pngenc ! filesink location=annotated.png
 * ]| Writes annotated.png: the box found in the scene, outlined, with its centre and number of
 * matches.
 */
#include "gstpickdetect.h"

#include "frame.hpp"
#include "frame-threads.hpp"

#include <gst/pickdetect/pickdetect-meta.h>
#include <pickdetect/calibration.hpp>
#include <pickdetect/detector.hpp>
#include <pickdetect/error.hpp>
#include <pickdetect/model.hpp>
#include <pickdetect/tracker.hpp>

#include <gst/video/video.h>

#include <algorithm>
#include <exception>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

GST_DEBUG_CATEGORY(gst_pick_detect_debug); // Also used by frame.cpp.
#define GST_CAT_DEFAULT gst_pick_detect_debug

/* The formats the element takes and gives, without any conversion (both pad templates). */
#define PICKDETECT_VIDEO_FORMATS                                                                   \
  "{ GRAY8, RGB, BGR, RGBx, BGRx, xRGB, xBGR, RGBA, BGRA, ARGB, ABGR, I420, YV12, NV12, NV21 }"
#define PICKDETECT_CAPS GST_VIDEO_CAPS_MAKE(PICKDETECT_VIDEO_FORMATS)

enum {
  PROP_0,
  PROP_MODEL,
  PROP_METHOD,
  PROP_RATIO,
  PROP_MIN_MATCHES,
  PROP_BANDWIDTH,
  PROP_MAX_INSTANCES,
  PROP_ALLOW_SCALE,
  PROP_PICK_WHOLE_IN_VIEW,
  PROP_FEATURES,
  PROP_DETECTION_SCALE,
  PROP_CONTRAST_THRESHOLD,
  PROP_REFINE,
  PROP_DRAW,
  PROP_POST_MESSAGES,
  PROP_THREADS,
  PROP_CALIBRATION,
  PROP_TRACKING,
  PROP_TRACK_TIMEOUT,
  PROP_COUNT_LINE,
  PROP_FULL_DETECTION_INTERVAL,
};

#define DEFAULT_MODEL nullptr
constexpr GstPickDetectMethod DEFAULT_METHOD = GST_PICK_DETECT_METHOD_VOTING;
constexpr double DEFAULT_RATIO = 0.0;
constexpr int DEFAULT_MIN_MATCHES = 4;
constexpr double DEFAULT_BANDWIDTH = 0.0;
constexpr int DEFAULT_MAX_INSTANCES = 0;
constexpr gboolean DEFAULT_ALLOW_SCALE = TRUE;
constexpr gboolean DEFAULT_PICK_WHOLE_IN_VIEW = FALSE;
constexpr GstPickDetectFeatures DEFAULT_FEATURES = GST_PICK_DETECT_FEATURES_SIFT;
constexpr double DEFAULT_DETECTION_SCALE = 1.0;
constexpr double DEFAULT_CONTRAST_THRESHOLD = 0.0;
constexpr gboolean DEFAULT_REFINE = TRUE;
constexpr gboolean DEFAULT_DRAW = FALSE;
constexpr gboolean DEFAULT_POST_MESSAGES = TRUE;
constexpr int DEFAULT_THREADS = 1;
#define DEFAULT_CALIBRATION nullptr
constexpr gboolean DEFAULT_TRACKING = TRUE;
constexpr guint DEFAULT_TRACK_TIMEOUT = 500;
#define DEFAULT_COUNT_LINE nullptr
constexpr guint DEFAULT_FULL_DETECTION_INTERVAL = 15;

// The element's defaults are the core's.
static_assert(pickdetect::Settings{}.method == pickdetect::Method::Voting);
static_assert(pickdetect::Settings{}.ratio == DEFAULT_RATIO);
static_assert(pickdetect::Settings{}.min_matches == DEFAULT_MIN_MATCHES);
static_assert(pickdetect::Settings{}.bandwidth == DEFAULT_BANDWIDTH);
static_assert(pickdetect::Settings{}.max_instances == DEFAULT_MAX_INSTANCES);
static_assert(pickdetect::Settings{}.allow_scale == static_cast<bool>(DEFAULT_ALLOW_SCALE));
static_assert(pickdetect::Settings{}.pick_whole_in_view ==
              static_cast<bool>(DEFAULT_PICK_WHOLE_IN_VIEW));
static_assert(pickdetect::Settings{}.features == pickdetect::FeatureKind::Sift &&
              DEFAULT_FEATURES == GST_PICK_DETECT_FEATURES_SIFT);
static_assert(pickdetect::Settings{}.detection_scale == DEFAULT_DETECTION_SCALE);
static_assert(pickdetect::Settings{}.contrast_threshold == DEFAULT_CONTRAST_THRESHOLD);
static_assert(pickdetect::Settings{}.refine == static_cast<bool>(DEFAULT_REFINE));
static_assert(pickdetect::TrackerSettings{}.timeout_ms == DEFAULT_TRACK_TIMEOUT);

namespace {

struct LoadFailure {
  GstResourceError code = GST_RESOURCE_ERROR_SETTINGS;
  std::string message;
};

} // namespace

/// The element's C++ state. Fields above the line are guarded by the object lock.
struct GstPickDetectPrivate {
  std::string model_path;       ///< The `model` property.
  std::string loaded_path;      ///< The file `detector` was built from.
  guint64 model_generation = 0; ///< Bumped by each `model` set; stale loads are dropped.
  bool started = false;         ///< Between start and stop.
  gstpickdetect::FrameConfig config;
  std::shared_ptr<const pickdetect::Detector> detector;
  int threads = DEFAULT_THREADS; ///< The `threads` property.
  int active_threads = 1;        ///< Frame threads since start (`threads` resolved).
  std::string calibration_path;  ///< The `calibration` property (loaded at start).
  std::string count_line;        ///< The `count-line` property as set.
  // ---- streaming thread (and state changes while it is stopped) only ----
  std::shared_ptr<const gstpickdetect::FrameFormat> format;   ///< From the caps, for new frames.
  std::unique_ptr<gstpickdetect::FrameThreads> frame_threads; ///< With more than one thread.
  bool size_error_posted = false; ///< Caps of the wrong size for the calibration, told once.
  // Tracking (docs/tracking.md): the tracker lives from the first tracked frame on and keeps
  // counting its ids across resets and restarts, so that no id is ever given twice.
  pickdetect::Tracker tracker;
  gstpickdetect::FrameTracking tracking;
  bool tracking_on = false; ///< The tracker followed the last frame.
  std::optional<pickdetect::CountLine> tracker_line;
  const pickdetect::Detector* tracked_detector = nullptr; ///< The models the tracks are of.
  int tracked_width = 0, tracked_height = 0;
};

struct _GstPickDetect {
  GstVideoFilter parent;
  GstPickDetectPrivate* priv;
};

#define gst_pick_detect_parent_class parent_class
G_DEFINE_TYPE(GstPickDetect, gst_pick_detect, GST_TYPE_VIDEO_FILTER);
GST_ELEMENT_REGISTER_DEFINE_WITH_CODE(pickdetect, "pickdetect", GST_RANK_NONE, GST_TYPE_PICK_DETECT,
                                      GST_DEBUG_CATEGORY_INIT(gst_pick_detect_debug, "pickdetect",
                                                              0, "pickdetect element"));

static GstStaticPadTemplate sink_template =
    GST_STATIC_PAD_TEMPLATE("sink", GST_PAD_SINK, GST_PAD_ALWAYS, GST_STATIC_CAPS(PICKDETECT_CAPS));
static GstStaticPadTemplate src_template =
    GST_STATIC_PAD_TEMPLATE("src", GST_PAD_SRC, GST_PAD_ALWAYS, GST_STATIC_CAPS(PICKDETECT_CAPS));

GType gst_pick_detect_method_get_type(void) {
  static GType type = 0;
  static const GEnumValue values[] = {
      {GST_PICK_DETECT_METHOD_VOTING,
       "Votes of every match for the principal points, gathered by mean shift", "voting"},
      {GST_PICK_DETECT_METHOD_RANSAC_CLUSTERED,
       "One RANSAC homography per mean-shift cluster of centre votes", "ransac-clustered"},
      {GST_PICK_DETECT_METHOD_RANSAC_ALL,
       "One RANSAC homography over all matches (one instance at most)", "ransac-all"},
      {0, nullptr, nullptr},
  };
  if (g_once_init_enter(&type)) {
    GType registered = g_enum_register_static("GstPickDetectMethod", values);
    g_once_init_leave(&type, registered);
  }
  return type;
}

GType gst_pick_detect_features_get_type(void) {
  static GType type = 0;
  static const GEnumValue values[] = {
      {GST_PICK_DETECT_FEATURES_SIFT, "SIFT (the paper's): the most distinctive, the most costly",
       "sift"},
      {GST_PICK_DETECT_FEATURES_ORB,
       "ORB: oriented FAST corners with binary descriptors, ten times cheaper or more", "orb"},
      {0, nullptr, nullptr},
  };
  if (g_once_init_enter(&type)) {
    GType registered = g_enum_register_static("GstPickDetectFeatures", values);
    g_once_init_leave(&type, registered);
  }
  return type;
}

static pickdetect::Method to_core_method(gint method) {
  switch (method) {
  case GST_PICK_DETECT_METHOD_RANSAC_CLUSTERED:
    return pickdetect::Method::RansacClustered;
  case GST_PICK_DETECT_METHOD_RANSAC_ALL:
    return pickdetect::Method::RansacAll;
  default:
    return pickdetect::Method::Voting;
  }
}

static GstPickDetectMethod from_core_method(pickdetect::Method method) {
  switch (method) {
  case pickdetect::Method::RansacClustered:
    return GST_PICK_DETECT_METHOD_RANSAC_CLUSTERED;
  case pickdetect::Method::RansacAll:
    return GST_PICK_DETECT_METHOD_RANSAC_ALL;
  case pickdetect::Method::Voting:
    break;
  }
  return GST_PICK_DETECT_METHOD_VOTING;
}

/* ------------------------------------------------------------------------------------------- */
/* Model loading                                                                               */

/// The resource error a failure of the core is reported as: not found, unreadable, or wrong
/// contents.
static GstResourceError resource_error_code(pickdetect::ErrorKind kind) {
  switch (kind) {
  case pickdetect::ErrorKind::NotFound:
    return GST_RESOURCE_ERROR_NOT_FOUND;
  case pickdetect::ErrorKind::CannotRead:
    return GST_RESOURCE_ERROR_OPEN_READ;
  case pickdetect::ErrorKind::Invalid:
    break;
  }
  return GST_RESOURCE_ERROR_SETTINGS;
}

/// Builds one detector over every model the `model` property names (see its blurb and
/// pickdetect::load_models). nullptr and `failure` filled when any of them cannot be loaded,
/// when two models share a name, or when the list has an empty entry. Never throws.
static std::shared_ptr<const pickdetect::Detector> load_detector(const std::string& value,
                                                                 LoadFailure& failure) {
  std::string path = value; // The file being read when something failed.
  std::string reason;
  pickdetect::ErrorKind kind = pickdetect::ErrorKind::Invalid;
  try {
    return std::make_shared<const pickdetect::Detector>(pickdetect::load_models(value));
  } catch (const pickdetect::Error& e) {
    failure.code = resource_error_code(e.kind());
    if (e.path().empty()) { // The list as a whole.
      failure.message = "Could not load the models \"" + value + "\": " + e.what();
      return nullptr;
    }
    path = e.path();
    reason = e.what();
    kind = e.kind();
  } catch (const std::exception& e) {
    reason = e.what();
    kind = pickdetect::file_error_kind(path);
  }
  failure.code = resource_error_code(kind);
  if (reason.find(path) != std::string::npos)
    failure.message = "Could not load the model: " + reason;
  else
    failure.message = "Could not load the model \"" + path + "\": " + reason;
  return nullptr;
}

/// Posts an error (or warning) message in the RESOURCE domain.
static void post_resource_message(GstPickDetect* self, GstMessageType type, GstResourceError code,
                                  const std::string& text, const std::string& debug) {
  gst_element_message_full(GST_ELEMENT(self), type, GST_RESOURCE_ERROR, code,
                           g_strdup(text.c_str()), g_strdup(debug.c_str()), __FILE__, GST_FUNCTION,
                           __LINE__);
}

/// Loads the model while playing, outside the lock, and swaps it in between two frames.
static void reload_model(GstPickDetect* self, const std::string& path, guint64 generation) {
  GstPickDetectPrivate* priv = self->priv;
  LoadFailure failure;
  GST_INFO_OBJECT(self, "loading model %s", path.c_str());
  std::shared_ptr<const pickdetect::Detector> detector =
      path.empty() ? nullptr : load_detector(path, failure);
  if (path.empty()) {
    failure.code = GST_RESOURCE_ERROR_NOT_FOUND;
    failure.message = "No model: the \"model\" property was set to nothing";
  }

  std::string kept;
  GST_OBJECT_LOCK(self);
  const bool current = generation == priv->model_generation && priv->started;
  if (current && detector) {
    priv->detector = detector; // The next frame takes it; the old one lives on with its frame.
    priv->loaded_path = path;
  } else if (current) {
    priv->model_path = priv->loaded_path;
    kept = priv->loaded_path;
  }
  GST_OBJECT_UNLOCK(self);

  if (!current) {
    GST_DEBUG_OBJECT(self, "model %s superseded or element stopped, dropped", path.c_str());
  } else if (detector) {
    GST_INFO_OBJECT(self, "now using model %s", path.c_str());
  } else {
    GST_WARNING_OBJECT(self, "%s", failure.message.c_str());
    post_resource_message(self, GST_MESSAGE_WARNING, failure.code, failure.message,
                          "keeping the model " + kept);
    g_object_notify(G_OBJECT(self), "model");
  }
}

/* ------------------------------------------------------------------------------------------- */
/* Properties                                                                                  */

static void gst_pick_detect_set_property(GObject* object, guint prop_id, const GValue* value,
                                         GParamSpec* pspec) {
  GstPickDetect* self = GST_PICK_DETECT(object);
  GstPickDetectPrivate* priv = self->priv;

  if (prop_id == PROP_MODEL) {
    const gchar* path = g_value_get_string(value);
    GST_OBJECT_LOCK(self);
    priv->model_path = path ? path : "";
    const guint64 generation = ++priv->model_generation;
    const bool started = priv->started;
    const std::string model = priv->model_path;
    GST_OBJECT_UNLOCK(self);
    if (started)
      reload_model(self, model, generation);
    return;
  }

  GST_OBJECT_LOCK(self);
  gstpickdetect::FrameConfig& config = priv->config;
  switch (prop_id) {
  case PROP_METHOD:
    config.settings.method = to_core_method(g_value_get_enum(value));
    break;
  case PROP_RATIO:
    config.settings.ratio = g_value_get_double(value);
    break;
  case PROP_MIN_MATCHES:
    config.settings.min_matches = g_value_get_int(value);
    break;
  case PROP_BANDWIDTH:
    config.settings.bandwidth = g_value_get_double(value);
    break;
  case PROP_MAX_INSTANCES:
    config.settings.max_instances = g_value_get_int(value);
    break;
  case PROP_ALLOW_SCALE:
    config.settings.allow_scale = g_value_get_boolean(value);
    break;
  case PROP_PICK_WHOLE_IN_VIEW:
    config.settings.pick_whole_in_view = g_value_get_boolean(value);
    break;
  case PROP_FEATURES:
    config.settings.features = g_value_get_enum(value) == GST_PICK_DETECT_FEATURES_ORB
                                   ? pickdetect::FeatureKind::Orb
                                   : pickdetect::FeatureKind::Sift;
    break;
  case PROP_DETECTION_SCALE:
    config.settings.detection_scale = g_value_get_double(value);
    break;
  case PROP_CONTRAST_THRESHOLD:
    config.settings.contrast_threshold = g_value_get_double(value);
    break;
  case PROP_REFINE:
    config.settings.refine = g_value_get_boolean(value);
    break;
  case PROP_DRAW:
    config.draw = g_value_get_boolean(value);
    break;
  case PROP_POST_MESSAGES:
    config.post_messages = g_value_get_boolean(value);
    break;
  case PROP_THREADS:
    priv->threads = g_value_get_int(value);
    break;
  case PROP_CALIBRATION: {
    const gchar* path = g_value_get_string(value);
    priv->calibration_path = path ? path : "";
    break;
  }
  case PROP_TRACKING:
    config.tracking = g_value_get_boolean(value);
    break;
  case PROP_TRACK_TIMEOUT:
    config.track_timeout_ms = g_value_get_uint(value);
    break;
  case PROP_FULL_DETECTION_INTERVAL:
    config.full_detection_interval = static_cast<int>(g_value_get_uint(value));
    break;
  case PROP_COUNT_LINE: {
    const gchar* text = g_value_get_string(value);
    try {
      config.count_line = pickdetect::parse_count_line(text ? text : "");
      priv->count_line = text ? text : "";
    } catch (const std::exception& e) {
      GST_WARNING_OBJECT(self, "count-line not changed: %s", e.what());
    }
    break;
  }
  default:
    G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
    break;
  }
  GST_OBJECT_UNLOCK(self);
}

static void gst_pick_detect_get_property(GObject* object, guint prop_id, GValue* value,
                                         GParamSpec* pspec) {
  GstPickDetect* self = GST_PICK_DETECT(object);
  GstPickDetectPrivate* priv = self->priv;

  GST_OBJECT_LOCK(self);
  const gstpickdetect::FrameConfig& config = priv->config;
  switch (prop_id) {
  case PROP_MODEL:
    g_value_set_string(value, priv->model_path.empty() ? nullptr : priv->model_path.c_str());
    break;
  case PROP_METHOD:
    g_value_set_enum(value, from_core_method(config.settings.method));
    break;
  case PROP_RATIO:
    g_value_set_double(value, config.settings.ratio);
    break;
  case PROP_MIN_MATCHES:
    g_value_set_int(value, config.settings.min_matches);
    break;
  case PROP_BANDWIDTH:
    g_value_set_double(value, config.settings.bandwidth);
    break;
  case PROP_MAX_INSTANCES:
    g_value_set_int(value, config.settings.max_instances);
    break;
  case PROP_ALLOW_SCALE:
    g_value_set_boolean(value, config.settings.allow_scale);
    break;
  case PROP_PICK_WHOLE_IN_VIEW:
    g_value_set_boolean(value, config.settings.pick_whole_in_view);
    break;
  case PROP_FEATURES:
    g_value_set_enum(value, config.settings.features == pickdetect::FeatureKind::Orb
                                ? GST_PICK_DETECT_FEATURES_ORB
                                : GST_PICK_DETECT_FEATURES_SIFT);
    break;
  case PROP_DETECTION_SCALE:
    g_value_set_double(value, config.settings.detection_scale);
    break;
  case PROP_CONTRAST_THRESHOLD:
    g_value_set_double(value, config.settings.contrast_threshold);
    break;
  case PROP_REFINE:
    g_value_set_boolean(value, config.settings.refine);
    break;
  case PROP_DRAW:
    g_value_set_boolean(value, config.draw);
    break;
  case PROP_POST_MESSAGES:
    g_value_set_boolean(value, config.post_messages);
    break;
  case PROP_THREADS:
    g_value_set_int(value, priv->threads);
    break;
  case PROP_CALIBRATION:
    g_value_set_string(value,
                       priv->calibration_path.empty() ? nullptr : priv->calibration_path.c_str());
    break;
  case PROP_TRACKING:
    g_value_set_boolean(value, config.tracking);
    break;
  case PROP_TRACK_TIMEOUT:
    g_value_set_uint(value, static_cast<guint>(config.track_timeout_ms));
    break;
  case PROP_FULL_DETECTION_INTERVAL:
    g_value_set_uint(value, static_cast<guint>(config.full_detection_interval));
    break;
  case PROP_COUNT_LINE:
    g_value_set_string(value, priv->count_line.empty() ? nullptr : priv->count_line.c_str());
    break;
  default:
    G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
    break;
  }
  GST_OBJECT_UNLOCK(self);
}

/* ------------------------------------------------------------------------------------------- */
/* Start / stop / caps                                                                         */

/// Loads the `calibration` file into the frame settings (none when the property is unset).
/// False, with an error posted naming the file and the reason, when it cannot be loaded.
static bool load_calibration_file(GstPickDetect* self) {
  GstPickDetectPrivate* priv = self->priv;
  GST_OBJECT_LOCK(self);
  const std::string path = priv->calibration_path;
  GST_OBJECT_UNLOCK(self);
  std::shared_ptr<const pickdetect::Calibration> calibration;
  if (!path.empty()) {
    GST_INFO_OBJECT(self, "loading calibration %s", path.c_str());
    try {
      calibration =
          std::make_shared<const pickdetect::Calibration>(pickdetect::load_calibration(path));
    } catch (const std::exception& e) {
      const std::string message = std::string("Could not load the calibration: ") + e.what();
      GST_ERROR_OBJECT(self, "%s", message.c_str());
      post_resource_message(self, GST_MESSAGE_ERROR,
                            resource_error_code(pickdetect::file_error_kind(path)), message,
                            "calibration=" + path);
      return false;
    }
  }
  GST_OBJECT_LOCK(self);
  priv->config.calibration = calibration;
  GST_OBJECT_UNLOCK(self);
  return true;
}

/// A homography calibration knows no camera, so it cannot raise the plane to a model's height:
/// says so, once per start, when a model has one.
static void warn_heights_ignored(GstPickDetect* self) {
  GST_OBJECT_LOCK(self);
  std::shared_ptr<const pickdetect::Calibration> calibration = self->priv->config.calibration;
  std::shared_ptr<const pickdetect::Detector> detector = self->priv->detector;
  const std::string path = self->priv->calibration_path;
  GST_OBJECT_UNLOCK(self);
  if (!calibration || !detector || calibration->kind != pickdetect::CalibrationKind::Homography)
    return;
  for (const pickdetect::Model& model : detector->models()) {
    if (model.height_mm > 0.0) {
      GST_ELEMENT_WARNING(self, RESOURCE, SETTINGS,
                          ("The calibration \"%s\" is a plain homography (no camera): model %s's "
                           "height of %g mm is not accounted for; calibrate with chessboard "
                           "photos for that",
                           path.c_str(), model.name.c_str(), model.height_mm),
                          (nullptr));
      return;
    }
  }
}

static void reset_tracks(GstPickDetect* self, const char* why);
static GstFlowReturn attach_threaded_frame(GstPickDetect* self, GstBuffer* buffer,
                                           const gstpickdetect::FrameInputs& in,
                                           const GstSegment& segment,
                                           gstpickdetect::FrameDetection& found);

static gboolean gst_pick_detect_start(GstBaseTransform* trans) {
  GstPickDetect* self = GST_PICK_DETECT(trans);
  GstPickDetectPrivate* priv = self->priv;

  if (!load_calibration_file(self))
    return FALSE;

  // A `model` set while this loads is caught by its generation and loaded again.
  for (;;) {
    GST_OBJECT_LOCK(self);
    const std::string path = priv->model_path;
    const guint64 generation = priv->model_generation;
    GST_OBJECT_UNLOCK(self);

    if (path.empty()) {
      post_resource_message(self, GST_MESSAGE_ERROR, GST_RESOURCE_ERROR_NOT_FOUND,
                            "No model: set the \"model\" property to a model file (.yml) or a "
                            "picture of the object",
                            "property \"model\" is not set");
      return FALSE;
    }

    GST_INFO_OBJECT(self, "loading model %s", path.c_str());
    LoadFailure failure;
    std::shared_ptr<const pickdetect::Detector> detector = load_detector(path, failure);
    if (!detector) {
      GST_ERROR_OBJECT(self, "%s", failure.message.c_str());
      post_resource_message(self, GST_MESSAGE_ERROR, failure.code, failure.message,
                            "model=" + path);
      return FALSE;
    }

    GST_OBJECT_LOCK(self);
    const bool current = generation == priv->model_generation;
    if (current) {
      priv->detector = std::move(detector);
      priv->loaded_path = path;
      priv->started = true;
    }
    GST_OBJECT_UNLOCK(self);
    if (current)
      break;
  }
  warn_heights_ignored(self);

  GST_OBJECT_LOCK(self);
  int threads = priv->threads;
  GST_OBJECT_UNLOCK(self);
  if (threads == 0)
    threads = static_cast<int>(g_get_num_processors());
  threads = std::max(threads, 1);
  if (threads > 1)
    priv->frame_threads = std::make_unique<gstpickdetect::FrameThreads>(
        trans, threads,
        [self](GstBuffer* buffer, const gstpickdetect::FrameInputs& in, const GstSegment& segment,
               gstpickdetect::FrameDetection& found) {
          return attach_threaded_frame(self, buffer, in, segment, found);
        });
  priv->size_error_posted = false;
  GST_OBJECT_LOCK(self);
  priv->active_threads = threads;
  GST_OBJECT_UNLOCK(self);
  GST_DEBUG_OBJECT(self, "%d frame thread(s)", threads);
  return TRUE;
}

static gboolean gst_pick_detect_stop(GstBaseTransform* trans) {
  GstPickDetect* self = GST_PICK_DETECT(trans);
  self->priv->frame_threads.reset(); // Drops the frames in the works, joins the threads.
  reset_tracks(self, "stop");
  self->priv->tracked_detector = nullptr;
  self->priv->tracked_width = self->priv->tracked_height = 0;
  std::shared_ptr<const pickdetect::Detector> old;
  GST_OBJECT_LOCK(self);
  self->priv->started = false;
  self->priv->active_threads = 1;
  old = std::move(self->priv->detector);
  self->priv->loaded_path.clear();
  self->priv->config.calibration.reset();
  GST_OBJECT_UNLOCK(self);
  self->priv->format.reset();
  return TRUE; // `old` is released here, outside the lock.
}

static gboolean gst_pick_detect_set_info(GstVideoFilter* filter, GstCaps* incaps,
                                         GstVideoInfo* in_info, GstCaps* outcaps,
                                         GstVideoInfo* out_info) {
  (void)incaps;
  (void)outcaps;
  (void)out_info;
  GstPickDetect* self = GST_PICK_DETECT(filter);
  GST_OBJECT_LOCK(self);
  std::shared_ptr<const pickdetect::Calibration> calibration = self->priv->config.calibration;
  const std::string calibration_path = self->priv->calibration_path;
  GST_OBJECT_UNLOCK(self);
  if (calibration && (calibration->image_size.width != GST_VIDEO_INFO_WIDTH(in_info) ||
                      calibration->image_size.height != GST_VIDEO_INFO_HEIGHT(in_info))) {
    if (self->priv->size_error_posted) // Negotiation retries: the error is posted once.
      return FALSE;
    self->priv->size_error_posted = true;
    GST_ELEMENT_ERROR(self, RESOURCE, SETTINGS,
                      ("The calibration \"%s\" was made for %dx%d frames, these are %dx%d: "
                       "calibrate at this resolution, or scale the frames before pickdetect",
                       calibration_path.c_str(), calibration->image_size.width,
                       calibration->image_size.height, GST_VIDEO_INFO_WIDTH(in_info),
                       GST_VIDEO_INFO_HEIGHT(in_info)),
                      (nullptr));
    return FALSE;
  }
  // Frames in the works keep the format they started with (they are drained before new caps).
  auto format = std::make_shared<gstpickdetect::FrameFormat>();
  std::string error;
  if (!format->configure(*in_info, error)) {
    GST_ELEMENT_ERROR(self, CORE, NEGOTIATION, (nullptr), ("%s", error.c_str()));
    return FALSE;
  }
  GST_DEBUG_OBJECT(self, "format %s, grey from %s", GST_VIDEO_INFO_NAME(in_info),
                   format->grey_source_name());
  self->priv->format = std::move(format);
  if (GST_VIDEO_INFO_WIDTH(in_info) != self->priv->tracked_width ||
      GST_VIDEO_INFO_HEIGHT(in_info) != self->priv->tracked_height) {
    reset_tracks(self, "new frame size"); // Positions mean other places now.
    self->priv->tracked_width = GST_VIDEO_INFO_WIDTH(in_info);
    self->priv->tracked_height = GST_VIDEO_INFO_HEIGHT(in_info);
  }
  return TRUE;
}

/* ------------------------------------------------------------------------------------------- */
/* Per frame                                                                                   */

static bool take_frame_inputs(GstPickDetect* self, gstpickdetect::FrameInputs& in) {
  GST_OBJECT_LOCK(self);
  in.detector = self->priv->detector;
  in.config = self->priv->config;
  GST_OBJECT_UNLOCK(self);
  in.format = self->priv->format; // Streaming thread only.
  if (!in.detector) {
    GST_ELEMENT_ERROR(self, CORE, STATE_CHANGE, ("No model loaded"), (nullptr));
    return false;
  }
  if (!in.format) {
    GST_ELEMENT_ERROR(self, CORE, NEGOTIATION, (nullptr), ("frame before caps"));
    return false;
  }
  return true;
}

/// Posts the track and count messages gathered so far, in order. Streaming thread.
static void post_track_messages(GstPickDetect* self) {
  std::vector<GstStructure*> messages;
  messages.swap(self->priv->tracking.messages);
  for (GstStructure* s : messages)
    gstpickdetect::post_frame_message(GST_ELEMENT(self), s);
}

/// Ends every track (flush, seek, new segment, new frame size, tracking off, stop) and posts
/// their end. Streaming thread (or while it is stopped).
static void reset_tracks(GstPickDetect* self, const char* why) {
  GstPickDetectPrivate* priv = self->priv;
  const std::vector<pickdetect::TrackEvent> ends =
      priv->tracker.end_all(pickdetect::TrackEnd::Reset);
  if (!ends.empty())
    GST_DEBUG_OBJECT(self, "%zu tracks ended: %s", ends.size(), why);
  for (const pickdetect::TrackEvent& e : ends)
    priv->tracking.messages.push_back(gstpickdetect::track_structure(e));
  priv->tracking.last_time.reset();
  priv->tracking.reuse.reset();
  post_track_messages(self);
}

/// Brings the tracker up to the frame's settings and models; null when not tracking.
static gstpickdetect::FrameTracking* prepare_tracking(GstPickDetect* self,
                                                      const gstpickdetect::FrameInputs& in) {
  GstPickDetectPrivate* priv = self->priv;
  if (!in.config.tracking) {
    if (priv->tracking_on)
      reset_tracks(self, "tracking turned off");
    priv->tracking_on = false;
    return nullptr;
  }
  priv->tracking_on = true;
  pickdetect::TrackerSettings settings = priv->tracker.settings();
  settings.timeout_ms = in.config.track_timeout_ms;
  priv->tracker.set_settings(settings);
  const bool same_line =
      priv->tracker_line.has_value() == in.config.count_line.has_value() &&
      (!priv->tracker_line || (priv->tracker_line->a == in.config.count_line->a &&
                               priv->tracker_line->b == in.config.count_line->b));
  if (!same_line) {
    priv->tracker.set_count_line(in.config.count_line);
    priv->tracker_line = in.config.count_line;
  }
  if (priv->tracked_detector != in.detector.get()) {
    // New models: the tracks of models still there go on, the others end.
    std::vector<std::string> names;
    for (const pickdetect::Model& m : in.detector->models())
      names.push_back(m.name);
    for (const pickdetect::TrackEvent& e : priv->tracker.end_models_not_in(names))
      priv->tracking.messages.push_back(gstpickdetect::track_structure(e));
    priv->tracked_detector = in.detector.get();
    priv->tracking.reuse.reset();
  }
  priv->tracking.reuse.set_whole_interval(in.config.full_detection_interval);
  priv->tracking.tracker = &priv->tracker;
  return &priv->tracking;
}

/// One frame: everything at once, on the streaming thread (`threads` = 1).
static GstFlowReturn gst_pick_detect_transform_ip(GstBaseTransform* trans, GstBuffer* buffer) {
  GstPickDetect* self = GST_PICK_DETECT(trans);
  gstpickdetect::FrameInputs in;
  if (!take_frame_inputs(self, in))
    return GST_FLOW_ERROR;
  GstStructure* message = nullptr;
  gstpickdetect::FrameTracking* tracking = prepare_tracking(self, in);
  const GstFlowReturn ret =
      gstpickdetect::process_frame(GST_ELEMENT(self), buffer, *in.format, in.config, *in.detector,
                                   trans->segment, &message, tracking);
  gstpickdetect::post_frame_message(GST_ELEMENT(self), message);
  post_track_messages(self);
  return ret;
}

/// A frame detected on a frame thread (`threads` > 1): tracked, its metas attached and its
/// messages posted, in frame order on the streaming thread.
static GstFlowReturn attach_threaded_frame(GstPickDetect* self, GstBuffer* buffer,
                                           const gstpickdetect::FrameInputs& in,
                                           const GstSegment& segment,
                                           gstpickdetect::FrameDetection& found) {
  GstStructure* message = nullptr;
  const GstFlowReturn ret =
      gstpickdetect::attach_frame(GST_ELEMENT(self), buffer, *in.format, in.config, *in.detector,
                                  segment, found, &message, prepare_tracking(self, in));
  gstpickdetect::post_frame_message(GST_ELEMENT(self), message);
  post_track_messages(self);
  return ret;
}

/// With `threads` > 1 the frame threads (frame-threads.cpp); with 1, the base class's
/// one-frame-at-a-time path (transform_ip).
static GstFlowReturn gst_pick_detect_generate_output(GstBaseTransform* trans, GstBuffer** outbuf) {
  GstPickDetect* self = GST_PICK_DETECT(trans);
  *outbuf = nullptr;
  if (!self->priv->frame_threads)
    return GST_BASE_TRANSFORM_CLASS(parent_class)->generate_output(trans, outbuf);
  return self->priv->frame_threads->generate_output(
      GST_BASE_TRANSFORM_CLASS(parent_class),
      [self](gstpickdetect::FrameInputs& in) { return take_frame_inputs(self, in); }, outbuf);
}

static gboolean gst_pick_detect_sink_event(GstBaseTransform* trans, GstEvent* event) {
  GstPickDetect* self = GST_PICK_DETECT(trans);
  gstpickdetect::FrameThreads* frame_threads = self->priv->frame_threads.get();
  if (frame_threads && GST_EVENT_TYPE(event) == GST_EVENT_FLUSH_STOP)
    frame_threads->flush();
  else if (frame_threads && GST_EVENT_IS_SERIALIZED(event))
    frame_threads->drain();
  if (GST_EVENT_TYPE(event) == GST_EVENT_FLUSH_STOP)
    reset_tracks(self, "flush");
  else if (GST_EVENT_TYPE(event) == GST_EVENT_SEGMENT)
    reset_tracks(self, "new segment"); // Running times start again.
  return GST_BASE_TRANSFORM_CLASS(parent_class)->sink_event(trans, event);
}

/// Frame threads hold `threads` - 1 frames back: that much latency is added to upstream's.
static gboolean gst_pick_detect_query(GstBaseTransform* trans, GstPadDirection direction,
                                      GstQuery* query) {
  GstPickDetect* self = GST_PICK_DETECT(trans);
  if (!GST_BASE_TRANSFORM_CLASS(parent_class)->query(trans, direction, query))
    return FALSE;
  if (direction != GST_PAD_SRC || GST_QUERY_TYPE(query) != GST_QUERY_LATENCY)
    return TRUE;
  GST_OBJECT_LOCK(self);
  const int threads = self->priv->active_threads;
  GST_OBJECT_UNLOCK(self);
  gstpickdetect::add_frame_thread_latency(GST_OBJECT(self), query, threads,
                                          GST_VIDEO_FILTER(self)->in_info);
  return TRUE;
}

/// Keeps the metas that do not depend on anything the element could change.
static gboolean gst_pick_detect_transform_meta(GstBaseTransform* trans, GstBuffer* outbuf,
                                               GstMeta* meta, GstBuffer* inbuf) {
  (void)outbuf;
  (void)inbuf;
  const GstMetaInfo* info = meta->info;
  const gchar* const valid_tags[] = {GST_META_TAG_VIDEO_STR, GST_META_TAG_VIDEO_SIZE_STR,
                                     GST_META_TAG_VIDEO_ORIENTATION_STR,
                                     GST_META_TAG_VIDEO_COLORSPACE_STR, nullptr};
  const gchar* const* tags = gst_meta_api_type_get_tags(info->api);
  for (; tags && *tags; tags++) {
    if (!g_strv_contains(valid_tags, *tags)) {
      GST_LOG_OBJECT(trans, "dropping %s (tag %s)", g_type_name(info->api), *tags);
      return FALSE;
    }
  }
  return TRUE;
}

/* ------------------------------------------------------------------------------------------- */
/* GObject                                                                                     */

static void gst_pick_detect_finalize(GObject* object) {
  GstPickDetect* self = GST_PICK_DETECT(object);
  delete self->priv;
  self->priv = nullptr;
  G_OBJECT_CLASS(parent_class)->finalize(object);
}

static void gst_pick_detect_init(GstPickDetect* self) {
  self->priv = new GstPickDetectPrivate();
  self->priv->config.full_detection_interval = DEFAULT_FULL_DETECTION_INTERVAL;
  // As GStreamer's video filters: frames a sink reports late are dropped, not processed.
  gst_base_transform_set_qos_enabled(GST_BASE_TRANSFORM(self), TRUE);
}

static void gst_pick_detect_class_init(GstPickDetectClass* klass) {
  GObjectClass* gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass* element_class = GST_ELEMENT_CLASS(klass);
  GstBaseTransformClass* trans_class = GST_BASE_TRANSFORM_CLASS(klass);
  GstVideoFilterClass* filter_class = GST_VIDEO_FILTER_CLASS(klass);
  const auto flags = static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                              GST_PARAM_MUTABLE_PLAYING);

  gobject_class->set_property = gst_pick_detect_set_property;
  gobject_class->get_property = gst_pick_detect_get_property;
  gobject_class->finalize = gst_pick_detect_finalize;

  g_object_class_install_property(
      gobject_class, PROP_MODEL,
      g_param_spec_string("model", "Model",
                          "The objects to find: model files (.yml / .yaml; one may list several "
                          "'views' of one product), plain pictures or model-set files (YAML with "
                          "a 'models' list), several separated by commas; all are searched for "
                          "at once. Required. Set while playing, the "
                          "new list is loaded and then used whole from the next frame on; if any "
                          "of it cannot be loaded a warning is posted and the old models stay",
                          DEFAULT_MODEL, flags));
  g_object_class_install_property(
      gobject_class, PROP_METHOD,
      g_param_spec_enum("method", "Method",
                        "How instances are found from the matches: the paper's voting, or a RANSAC "
                        "baseline",
                        GST_TYPE_PICK_DETECT_METHOD, DEFAULT_METHOD, flags));
  g_object_class_install_property(
      gobject_class, PROP_RATIO,
      g_param_spec_double("ratio", "Ratio",
                          "2NN ratio test: a match is kept when its nearest descriptor distance "
                          "is below this fraction of the second nearest (0 < ratio < 1); 0 = "
                          "automatic: 0.9 for voting with refine (every instance is checked "
                          "against the frame), 0.8 (Lowe's, the paper's) for the RANSAC baselines "
                          "and plain voting",
                          0.0, 0.99, DEFAULT_RATIO, flags));
  g_object_class_install_property(
      gobject_class, PROP_MIN_MATCHES,
      g_param_spec_int("min-matches", "Minimum matches",
                       "Fewest supporting matches an instance needs (the RANSAC "
                       "baselines: at least 6)",
                       1, G_MAXINT, DEFAULT_MIN_MATCHES, flags));
  g_object_class_install_property(
      gobject_class, PROP_BANDWIDTH,
      g_param_spec_double("bandwidth", "Bandwidth",
                          "Mean-shift bandwidth in frame pixels; 0 = automatic (0.15 of the "
                          "model picture's smaller side, and the votes left clustered again "
                          "narrower for objects seen smaller than their picture)",
                          0.0, G_MAXDOUBLE, DEFAULT_BANDWIDTH, flags));
  g_object_class_install_property(
      gobject_class, PROP_MAX_INSTANCES,
      g_param_spec_int(
          "max-instances", "Maximum instances",
          "At most this many instances per frame (all models together), best first; 0 = no "
          "limit",
          0, G_MAXINT, DEFAULT_MAX_INSTANCES, flags));
  g_object_class_install_property(
      gobject_class, PROP_ALLOW_SCALE,
      g_param_spec_boolean("allow-scale", "Allow scale",
                           "Instances may be larger or smaller than the model (else the scale is "
                           "fixed at 1)",
                           DEFAULT_ALLOW_SCALE, flags));
  g_object_class_install_property(
      gobject_class, PROP_PICK_WHOLE_IN_VIEW,
      g_param_spec_boolean("pick-whole-in-view", "Pick whole in view",
                           "Flag an instance pickable only when the whole object lies in the "
                           "frame: what lies on a part the camera does not see is not known "
                           "(else half of it in view is enough)",
                           DEFAULT_PICK_WHOLE_IN_VIEW, flags));
  g_object_class_install_property(
      gobject_class, PROP_FEATURES,
      g_param_spec_enum("features", "Features",
                        "Local features of the frame and the models: sift (the paper's, the most "
                        "distinctive) or orb (oriented FAST corners, binary descriptors: much "
                        "faster, fewer objects found)",
                        GST_TYPE_PICK_DETECT_FEATURES, DEFAULT_FEATURES, flags));
  g_object_class_install_property(
      gobject_class, PROP_DETECTION_SCALE,
      g_param_spec_double("detection-scale", "Detection scale",
                          "Features are extracted from the frame shrunk by this factor (area "
                          "interpolation); positions stay in frame pixels. 0.5 costs SIFT about a "
                          "quarter of its time, and the smallest details",
                          0.1, 1.0, DEFAULT_DETECTION_SCALE, flags));
  g_object_class_install_property(
      gobject_class, PROP_CONTRAST_THRESHOLD,
      g_param_spec_double("contrast-threshold", "Contrast threshold",
                          "SIFT's contrast threshold for the frames, on OpenCV's scale (0.04 is "
                          "its default; lower keeps weaker keypoints, at more cost). 0: automatic, "
                          "0.04 lowered in proportion for a dim or flat frame (grey span from the "
                          "0.1 to the 99.9 percentile under 200 levels) and halved when a model "
                          "has faint print (docs/models.md), to 0.01 at the least. "
                          "Set it (e.g. 0.02) where the light changes across the frame",
                          0.0, 0.2, DEFAULT_CONTRAST_THRESHOLD, flags));
  g_object_class_install_property(
      gobject_class, PROP_REFINE,
      g_param_spec_boolean("refine", "Refine",
                           "Refit each instance's pose on its own inlier matches and share the "
                           "features of look-alike models (off: the paper's plain voting)",
                           DEFAULT_REFINE, flags));
  g_object_class_install_property(
      gobject_class, PROP_DRAW,
      g_param_spec_boolean(
          "draw", "Draw",
          "Draw each instance into the frame: outline in green with its pick "
          "order (#1, #2...) when pickable, in red when covered, orange otherwise; "
          "its model's name; green circle on the centre with the number of "
          "matches; small circles on the other principal points (otherwise "
          "pixels are left untouched)",
          DEFAULT_DRAW, flags));
  g_object_class_install_property(
      gobject_class, PROP_POST_MESSAGES,
      g_param_spec_boolean("post-messages", "Post messages",
                           "Post a \"pickdetect\" element message with the instances for each "
                           "frame (on by default, like facedetect's updates=every_frame)",
                           DEFAULT_POST_MESSAGES, flags));
  g_object_class_install_property(
      gobject_class, PROP_THREADS,
      g_param_spec_int(
          "threads", "Frame threads",
          "Frames detected at the same time, each on a thread of its own, given out in their "
          "order: 1 = one frame at a time on the streaming thread; 0 = one per CPU core. Each "
          "frame thread beyond the first raises the throughput on several cores and adds one "
          "frame of latency (reported in the latency query). Takes effect at the next start",
          0, 64, DEFAULT_THREADS,
          static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                   GST_PARAM_MUTABLE_READY)));

  g_object_class_install_property(
      gobject_class, PROP_CALIBRATION,
      g_param_spec_string(
          "calibration", "Calibration",
          "A calibration file (YAML, written by pickdetect-calibrate): every instance then also "
          "carries its centre, grasp point, outline and angle in millimetres on the work plane "
          "(world-x, world-y, world-angle, grasp-world-x, grasp-world-y, world-outline), lens "
          "distortion corrected and the top face raised by its model's height (model file key "
          "'height', mm). Frames must have the calibration's size. Unset: pixels only. A file "
          "that cannot be loaded fails the start. Takes effect at the next start",
          DEFAULT_CALIBRATION,
          static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                   GST_PARAM_MUTABLE_READY)));

  g_object_class_install_property(
      gobject_class, PROP_TRACKING,
      g_param_spec_boolean(
          "tracking", "Tracking",
          "Follow every instance across the frames of the stream: each gets a track-id (also the "
          "ROI's id and an object_id param), first-seen, frames-seen, velocity-x/-y and tracked "
          "(carried forward, not detected in this frame); \"pickdetect-track\" messages when a "
          "track starts and ends, the belt's motion in the frame message and meta. Off: each "
          "frame on its own (unrelated still pictures). Turned off while playing, every track "
          "ends",
          DEFAULT_TRACKING, flags));
  g_object_class_install_property(
      gobject_class, PROP_TRACK_TIMEOUT,
      g_param_spec_uint("track-timeout", "Track timeout",
                        "Milliseconds a tracked object may go unseen (hidden, missed) and keep its "
                        "id when it shows again where its motion says; then its track ends. "
                        "Till then one riding hidden under a neighbour that moves with it is "
                        "still reported (tracked, at its predicted pose)",
                        0, 600000, DEFAULT_TRACK_TIMEOUT, flags));
  g_object_class_install_property(
      gobject_class, PROP_COUNT_LINE,
      g_param_spec_string(
          "count-line", "Count line",
          "A segment \"x1,y1,x2,y2\" in frame pixels: each track crossing it is counted once "
          "(a \"pickdetect-count\" message with track-id, model, count of that model and total), "
          "however it stops, jitters or hides on it. Empty: no counting. A new line starts the "
          "counts again; a malformed one is refused with a warning in the log",
          DEFAULT_COUNT_LINE, flags));
  g_object_class_install_property(
      gobject_class, PROP_FULL_DETECTION_INTERVAL,
      g_param_spec_uint(
          "full-detection-interval", "Full detection interval",
          "With tracking and threads=1: every N-th frame is detected whole; in between, "
          "detection reuses the frames before (docs/tracking.md): an instance that moved rigidly "
          "(a belt) is found again by its measured motion, its keypoints and matches carried "
          "along; SIFT runs only around what else changed (8x8-pixel blocks whose mean grey moved "
          "by more than 4 levels: objects coming into view, taken away); a frame in which nothing "
          "changed keeps the last frame's instances. The frame message tells features-extracted, "
          "features-reused and extracted-share. 1: every frame detected whole, as with "
          "tracking=false",
          1, G_MAXINT, DEFAULT_FULL_DETECTION_INTERVAL, flags));

  gst_element_class_set_static_metadata(
      element_class, "Pick detection", "Filter/Analyzer/Video",
      "Finds every instance of one or several known objects in each frame (SIFT matches, votes, "
      "mean shift) and attaches them as metadata",
      "gst-pickdetect authors");
  gst_element_class_add_static_pad_template(element_class, &sink_template);
  gst_element_class_add_static_pad_template(element_class, &src_template);

  trans_class->start = GST_DEBUG_FUNCPTR(gst_pick_detect_start);
  trans_class->stop = GST_DEBUG_FUNCPTR(gst_pick_detect_stop);
  trans_class->transform_ip = GST_DEBUG_FUNCPTR(gst_pick_detect_transform_ip);
  trans_class->transform_meta = GST_DEBUG_FUNCPTR(gst_pick_detect_transform_meta);
  trans_class->generate_output = GST_DEBUG_FUNCPTR(gst_pick_detect_generate_output);
  trans_class->sink_event = GST_DEBUG_FUNCPTR(gst_pick_detect_sink_event);
  trans_class->query = GST_DEBUG_FUNCPTR(gst_pick_detect_query);
  trans_class->passthrough_on_same_caps = FALSE;
  filter_class->set_info = GST_DEBUG_FUNCPTR(gst_pick_detect_set_info);

  gst_type_mark_as_plugin_api(GST_TYPE_PICK_DETECT_METHOD, static_cast<GstPluginAPIFlags>(0));
  gst_type_mark_as_plugin_api(GST_TYPE_PICK_DETECT_FEATURES, static_cast<GstPluginAPIFlags>(0));
}
