// SPDX-License-Identifier: LGPL-2.1-or-later
#pragma once

#include <pickdetect/export.hpp>

#include <pickdetect/features.hpp>
#include <pickdetect/model.hpp>

#include <opencv2/core.hpp>

#include <memory>
#include <string>
#include <vector>

namespace pickdetect {

/// How instances are found from the matches.
enum class Method {
  Voting,          ///< The seed paper's method: centre votes, mean shift, principal points.
  RansacClustered, ///< Baseline: one RANSAC homography per mean-shift cluster of centre votes.
  RansacAll,       ///< Baseline: one RANSAC homography over all matches (one instance at most).
};

PICKDETECT_API const char* method_name(Method method);
/// Parses "voting", "ransac-clustered" or "ransac-all"; throws Error on anything else.
PICKDETECT_API Method parse_method(const std::string& name);

/// The 2NN ratio test's threshold when Settings::ratio is 0 (automatic): voting with refinement
/// checks every instance against the frame (scene explanation), so it takes the matches of
/// faint, washed-out or tilted print that a stricter test drops; the RANSAC baselines and plain
/// voting keep Lowe's 0.8, the paper's, since every extra false match is an outlier to them.
constexpr double kVotingRatio = 0.9;
constexpr double kBaselineRatio = 0.8;

/// The numbers that matter, with their units. Defaults are the element's property defaults.
struct Settings {
  Method method = Method::Voting;
  /// 2NN ratio test threshold (nearest / second nearest, 0 < ratio < 1); 0 = automatic:
  /// kVotingRatio for voting with refinement, kBaselineRatio otherwise.
  double ratio = 0.0;
  /// Fewest supporting matches an instance needs (the RANSAC baselines: at least 6, as four
  /// matches always fit a homography).
  int min_matches = 4;
  /// Mean-shift bandwidth in scene pixels; 0 = automatic: 0.15 of the model picture's smaller
  /// side, and for objects seen smaller than their picture the votes the instances found leave
  /// clustered again at that bandwidth narrowed by their scale.
  double bandwidth = 0.0;
  int max_instances = 0;   ///< At most this many instances per frame, best first; 0 = no limit.
  bool allow_scale = true; ///< Votes use the keypoints' scale ratio (else scale is fixed at 1).
  /// Voting: refit each instance's pose on its own inlier matches (robustly), and share the
  /// features of look-alike models (Ambiguity::Share). False: the paper's plain voting.
  bool refine = true;
  Search search = Search::KdTree;           ///< Nearest-neighbour search of the matching.
  FeatureKind features = FeatureKind::Sift; ///< SIFT (the paper's) or ORB (fast).
  /// Features are extracted from the frame shrunk by this factor (0 < f <= 1), then carried back
  /// to frame pixels: 0.5 costs SIFT about a quarter of its time, and the smallest details.
  double detection_scale = 1.0;
  /// SIFT's contrast threshold for the frames (OpenCV's scale: kSiftContrastThreshold, 0.04, is
  /// its default); 0 = automatic: 0.04 times exposure_contrast_share(frame), lower for dim or
  /// flat frames, halved for models with faint print (Detector::frame_contrast_threshold). Set it
  /// (e.g. 0.02) where the light changes across the frame (a spot light): more keypoints in the
  /// darker parts, at more cost everywhere.
  double contrast_threshold = 0.0;
  double ransac_reprojection_px = 5.0; ///< RANSAC baselines: inlier distance in scene pixels.
  /// Pickable only when the whole object is in view (no more than kCoverTolerance, occlusion.hpp,
  /// of its outline outside the frame): what lies on a part the camera does not see is not known.
  /// False: half of it in view is enough (kMinPickableVisibility), as for a box cut by the edge
  /// of a camera that sees the whole work area.
  bool pick_whole_in_view = false;
  /// The frame's motion blur, where it is known: its direction and length in frame pixels, x
  /// and y (a belt's travel in one frame times the share of the frame time the shutter is
  /// open). The checks of the frame's pixels (what lies on an instance, whether its print is
  /// seen) then compare each model's picture blurred the same way, so that the blur alone does
  /// not make a free box look covered. (0, 0): a sharp frame; a blur under 2 pixels counts as
  /// none. At most kMaxMotionBlurPx long. FeatureReuse (the element with tracking) measures it
  /// on a belt and sets it itself.
  double motion_blur_x = 0.0;
  double motion_blur_y = 0.0;
};

/// The longest motion blur (Settings::motion_blur_x, motion_blur_y) detect takes, in pixels.
constexpr double kMaxMotionBlurPx = 256.0;

/// Whether two settings agree in every field (a field added to Settings is added here too).
PICKDETECT_API bool operator==(const Settings& a, const Settings& b);
inline bool operator!=(const Settings& a, const Settings& b) {
  return !(a == b);
}

/// One object instance found in the frame, in scene pixels (y axis down).
struct Instance {
  int model = 0;          ///< Index of the model in the detector's list.
  std::string model_name; ///< The product's name (Model::name).
  std::string view;       ///< Which of the product's views it matched (Model::view; may be empty).
  std::vector<cv::Point2f> points;  ///< The model's principal points; [0] is the centre.
  std::vector<cv::Point2f> outline; ///< The model's outline carried into the scene.
  cv::Point2f center;
  double angle = 0.0; ///< Degrees in [0, 360), clockwise on screen (image y axis down).
  double scale = 1.0; ///< Scene size / model size.
  int matches = 0;    ///< Matches that support the instance.
  /// Of those, the matches whose scene feature fitted no other model about as well: the evidence
  /// for which product this is (look-alike products share parts of their design). All of them
  /// for the RANSAC baselines and plain voting, whose matching drops such features.
  int distinct_matches = 0;
  double score = 0.0;                          ///< Confidence in [0, 1].
  cv::Matx33d homography = cv::Matx33d::eye(); ///< Carries model pixels into the scene.
  std::vector<cv::Point2f> support;            ///< Scene positions of the supporting keypoints.
  /// Estimated share of the outline that is seen: inside the frame and under no other instance.
  double visibility = 1.0;
  /// Another detected instance lies on it (or which is on top is unclear), or, when the frame's
  /// pixels were given, something of no model does (see occlusion.hpp).
  bool covered = false;
  /// Not covered, enough of it seen, neither guided nor place_unsure (occlusion.hpp).
  bool pickable = false;
  int pick_order = 0;       ///< 1 = pick first among the pickable instances; 0 = not pickable.
  cv::Point2f grasp;        ///< The model's grasp point in the scene.
  double grasp_angle = 0.0; ///< Gripper angle in degrees (the instance's angle).
  /// Completed by guided matching from a hypothesis of two or three votes (a model of faint
  /// print): its support pairs keypoints by descriptor where its pose puts them, not by the
  /// ratio test. Never pickable: too little evidence to send a gripper to.
  bool guided = false;
  /// A model whose picture repeats a part (a bundle of identical packs), placed where the frame
  /// does not tell which of its copies lie where: its ends out of the frame or hidden, a place
  /// shifted by a copy explains what is seen as well. Never pickable: its grasp point may be a
  /// copy off.
  bool place_unsure = false;
};

/// Time spent in each stage of one detection, in milliseconds.
struct Timings {
  double features_ms = 0.0;
  double matching_ms = 0.0;
  double clustering_ms = 0.0; ///< Voting / RANSAC, mean shift, pose and occlusion.
};

struct Detection {
  std::vector<Instance> instances;
  Timings timings;
  int scene_keypoints = 0;
  int matches = 0;
};

/// Frames searched for a model whose picture has faint print (its features found at a lowered
/// threshold, Model::contrast_threshold) are searched at this share of the automatic threshold:
/// the same print, smaller and blurrier in the frame, is fainter there still.
constexpr double kFaintPrintFrameShare = 0.5;

/// SIFT's contrast threshold for `grey` with `settings`: Settings::contrast_threshold, else
/// kSiftContrastThreshold times exposure_contrast_share(grey) times `print_share` (1, or
/// kFaintPrintFrameShare for models with faint print), no less than kLeastFrameContrastShare
/// of it. Detector::frame_contrast_threshold gives the one detect uses.
PICKDETECT_API double frame_contrast_threshold(const cv::Mat& grey, const Settings& settings,
                                               double print_share = 1.0);

/// Finds every instance of its models in grey frames (and tells apart by the frame's colour,
/// when given, look-alike products that differ in colour). Immutable after construction, so one
/// detector may serve several threads; swapping models means building a new detector.
class PICKDETECT_API Detector {
public:
  explicit Detector(std::vector<Model> models);

  /// Detects in a grey frame (CV_8UC1, any stride; the data is only read).
  Detection detect(const cv::Mat& grey, const Settings& settings = Settings()) const;

  /// Detects in a grey frame, with the same frame in colour beside it (`colour`: CV_8UC3, BGR,
  /// the grey one's size; empty: none). Features come from the grey frame as above; the colour
  /// tells look-alike products that differ only in colour apart, where their models have
  /// colour (Model::colour) and the method is voting with refinement (docs/models.md). Without
  /// colour, or with grey models, the result is detect(grey, settings)'s.
  Detection detect(const cv::Mat& grey, const cv::Mat& colour,
                   const Settings& settings = Settings()) const;

  /// Whether any model has colour: only then is a colour frame worth giving.
  bool has_colour_models() const;

  /// SIFT's contrast threshold detect uses on `grey` with `settings`: the free function's,
  /// with kFaintPrintFrameShare when any model's picture has faint print.
  double frame_contrast_threshold(const cv::Mat& grey, const Settings& settings) const;

  /// Detects from features already extracted from the frame. Without the frame's pixels,
  /// which of two overlapping instances is on top is told from the features alone.
  Detection detect(const Features& scene, const cv::Size& frame_size,
                   const Settings& settings = Settings()) const;

  /// The matches of the scene features against every model (the first stage of detect). Each
  /// scene feature's matches depend on it alone, so the matches of a subset of the features are
  /// those of the whole restricted to it (FeatureReuse relies on it).
  std::vector<Match> match(const Features& scene, const Settings& settings = Settings()) const;

  /// detect(grey, colour, settings) from the frame's features and their matches
  /// (match(scene)), the frame's pixels still telling which instance is on top and, with
  /// `colour` (as for detect), which of look-alikes that differ in colour lies there.
  Detection detect(const cv::Mat& grey, const Features& scene, const std::vector<Match>& matches,
                   const Settings& settings = Settings(), const cv::Mat& colour = cv::Mat()) const;

  const std::vector<Model>& models() const { return models_; }

private:
  Detection detect_scene(const Features& scene, const cv::Size& frame_size,
                         const Settings& settings, const cv::Mat& grey,
                         const cv::Mat& colour) const;
  Detection detect_matched(const Features& scene, const std::vector<Match>& matches,
                           const cv::Size& frame_size, const Settings& settings,
                           const cv::Mat& grey, const cv::Mat& colour) const;

  struct Matchers; ///< The search indices over the models' features (src/, internal).

  std::vector<Model> models_;
  double print_share_ = 1.0; ///< frame_contrast_threshold's print_share for these models.
  std::shared_ptr<const Matchers> matchers_; ///< Shared by copies: a detector is immutable.
};

} // namespace pickdetect
