// SPDX-License-Identifier: LGPL-2.1-or-later
#pragma once

#include <pickdetect/export.hpp>

#include <pickdetect/features.hpp>

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace pickdetect {

/// The object to look for: one model picture, its principal points and its outline, plus the
/// SIFT features of the picture (computed, or read back from a model file's cache).
/// Default Model::max_tilt_deg: a face seen up to 60 degrees off its normal, as a carton lying
/// in a heap or the far side of a tote under a camera 40 degrees off vertical shows it.
constexpr double kDefaultMaxTiltDeg = 60.0;
/// Largest Model::max_tilt_deg accepted (ASIFT's views stop near 80 degrees).
constexpr double kMaxTiltDeg = 80.0;

struct Model {
  /// The product's name, shown as the instance's model name (ROI type, overlay label). The views
  /// of one product (a model file's `views`) are models of one name.
  std::string name;
  /// Which picture of the product this is: a view's name (its `name` key, else its picture's
  /// file name without extension) for a model file with `views`; empty for a product of one
  /// picture.
  std::string view;
  std::string image_path; ///< The model picture the features come from.
  cv::Mat image;          ///< Grey picture, CV_8UC1.
  /// The picture in colour (CV_8UC3, BGR), for telling look-alike products apart by the frame's
  /// colour; empty when the picture is grey (one channel, or no pixel with chroma).
  cv::Mat colour;
  cv::Mat mask; ///< CV_8UC1, 255 where the picture shows the object.
  /// Principal points in model pixels; [0] is the object centre, the rest grasping / delimiting
  /// points.
  std::vector<cv::Point2f> principal_points;
  std::vector<cv::Point2f> outline; ///< Outline polygon in model pixels.
  int grasp_point = 0;              ///< Index into principal_points of the grasp point.
  /// Millimetres from the work plane up to the object's top face (the model file's `height`),
  /// for positions on the plane (calibration.hpp); 0 = flat on the plane.
  double height_mm = 0.0;
  /// Faces seen up to this many degrees off their normal are matched through views of the
  /// picture simulated at those tilts (the model file's `max_tilt`; see tilted_views); 0 =
  /// the picture's own SIFT features only. The simulated views' features are part of `sift`.
  double max_tilt_deg = kDefaultMaxTiltDeg;
  /// SIFT's contrast threshold the picture's features were found at: kSiftContrastThreshold,
  /// lower for a picture with little print (compute_model_features); a model file's feature
  /// cache records it (`contrast_threshold`). Frames searched for such a model keep their
  /// weaker extrema too (Detector::frame_contrast_threshold).
  double contrast_threshold = kSiftContrastThreshold;
  Features sift; ///< SIFT features of the picture (the paper's), and of its tilted views.
  Features orb;  ///< ORB features of the picture (the fast configuration).

  const Features& features(FeatureKind kind) const { return kind == FeatureKind::Orb ? orb : sift; }
  /// Whether the picture has faint print: its features were found below SIFT's usual threshold.
  bool faint_print() const { return contrast_threshold < kSiftContrastThreshold * (1.0 - 1e-9); }
};

/// Fewest keypoints a model picture must yield to be usable.
constexpr int kMinModelKeypoints = 12;
/// A model picture yielding fewer SIFT keypoints than this at SIFT's usual contrast threshold
/// (kSiftContrastThreshold) is searched again at half the threshold, and so on down to
/// kLeastModelContrastThreshold (compute_model_features); its tilted views use the same.
constexpr int kModelKeypointTarget = 250;
constexpr double kLeastModelContrastThreshold = 0.005;

/// Builds a model from a picture. A picture with an alpha channel marks the object by its alpha;
/// otherwise the whole picture is the object. Principal points default to the centre and the
/// four corners of the object's bounding box, the outline to the alpha contour or the picture's
/// rectangle. Throws Error naming the file when it cannot be read or yields too few keypoints.
PICKDETECT_API Model model_from_picture(const std::string& picture_path,
                                        const std::string& name = {});

/// Loads a model file (YAML, see docs/models.md) or, for any other file, a plain picture with
/// default points. Throws Error naming the file and the reason; also for a model file listing
/// several `views` (load_views takes those).
PICKDETECT_API Model load_model(const std::string& path);

/// Loads every view of a product: one model per entry of a model file's `views` list (each with
/// the product's name and its own Model::view), or the one model of any other model file or
/// picture. Throws Error naming the file, the view and the reason.
PICKDETECT_API std::vector<Model> load_views(const std::string& path);

/// Writes a model file. The picture path is stored relative to the file's folder when it lies
/// below it. With cache_features the keypoints and descriptors are stored too, so that loading
/// does not recompute them.
PICKDETECT_API void save_model(const Model& model, const std::string& path,
                               bool cache_features = true);

/// Writes a model file listing the views of one product (models of one name, each with its own
/// Model::view; `height` and `max_tilt` are those of the first), which load_views reads back.
/// Throws Error when `views` is empty or its models name different products.
PICKDETECT_API void save_views(const std::vector<Model>& views, const std::string& path,
                               bool cache_features = true);

/// Computes the model's SIFT and ORB features from its picture and mask (used by the loaders).
PICKDETECT_API void compute_model_features(Model& model);

/// Whether load_model reads `path` as a model file (YAML, JSON or XML by its extension, also
/// gzipped) rather than as a picture.
PICKDETECT_API bool is_model_file(const std::string& path);

/// Loads every model a model list names: model files, pictures and model-set files (a model
/// file with a `models` list of model files or pictures and no `image`; relative entries are
/// relative to the set's folder), separated by commas, blanks around each entry ignored. Throws
/// Error when any cannot be loaded (its path() the file being read and its kind() why), when an
/// entry is empty, when a set lists another set, or when two entries name the same product
/// (path() empty for the list as a whole). A model file with `views` gives one model per view.
PICKDETECT_API std::vector<Model> load_models(const std::string& list);

} // namespace pickdetect
