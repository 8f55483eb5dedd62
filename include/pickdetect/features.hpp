// SPDX-License-Identifier: LGPL-2.1-or-later
#pragma once

#include <pickdetect/export.hpp>

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace pickdetect {

/// Which local features describe pictures.
enum class FeatureKind {
  Sift, ///< SIFT (the paper's): the most distinctive, the most costly.
  Orb,  ///< ORB: oriented FAST corners with binary descriptors, ten times cheaper or more.
};

PICKDETECT_API const char* feature_name(FeatureKind kind);
/// Parses "sift" or "orb"; throws Error on anything else.
PICKDETECT_API FeatureKind parse_features(const std::string& name);

/// Keypoints and their descriptors, one row per keypoint: CV_32F for SIFT, CV_8U for ORB.
struct Features {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
};

/// OpenCV's SIFT contrast threshold: extrema of the difference of Gaussians weaker than this
/// (in grey levels / 255, over the 3 layers of an octave) are left out as noise.
constexpr double kSiftContrastThreshold = 0.04;

/// Features of a grey picture (CV_8UC1, any stride); an optional mask limits where keypoints
/// lie. Positions are in the picture's pixels with pixel centres on integers.
/// `contrast_threshold`: SIFT's (lower keeps weaker extrema too; see exposure_contrast_share;
/// negative or NaN: kSiftContrastThreshold); ORB ignores it.
PICKDETECT_API Features extract_features(const cv::Mat& grey, const cv::Mat& mask = cv::Mat(),
                                         FeatureKind kind = FeatureKind::Sift,
                                         double contrast_threshold = kSiftContrastThreshold);

/// Features of `grey` shrunk by `scale` (0 < scale <= 1, area interpolation), with positions and
/// sizes carried back to `grey`'s pixels.
PICKDETECT_API Features extract_features_scaled(const cv::Mat& grey, double scale,
                                                FeatureKind kind = FeatureKind::Sift,
                                                double contrast_threshold = kSiftContrastThreshold);

/// How much of SIFT's contrast threshold (kSiftContrastThreshold) suits a frame of this
/// exposure (CV_8UC1; the detector's default, Settings::contrast_threshold 0): 1 for a
/// frame whose grey spans 200 levels or more (between the 0.1 and 99.9 percentiles, so
/// that a few small objects on a plain belt set it), that span / 200 for a dimmer or flatter
/// one, 0.25 at the least. In a frame taken with a quarter of the light every contrast is a
/// quarter as strong, the objects' too: with OpenCV's fixed threshold SIFT would find few of
/// their keypoints. Model pictures keep the full threshold.
PICKDETECT_API double exposure_contrast_share(const cv::Mat& grey);

/// The least share of kSiftContrastThreshold a frame is searched at, whatever lowers it (a dim
/// frame, models with faint print): below it the extra extrema are the sensor's noise.
constexpr double kLeastFrameContrastShare = 0.25;

/// How the matching searches the two nearest model descriptors of each scene descriptor.
enum class Search {
  KdTree,     ///< FLANN's randomised kd-trees, built with a fixed seed: fast, deterministic.
  BruteForce, ///< Every pair compared: exact, several times slower on large frames.
};

/// One simulated view of a model picture (ASIFT's view simulation): the face turned by `phi`
/// degrees in the picture plane, then tilted away from the camera so that it looks `tilt` times
/// narrower across (tilt = 1 / cos of the angle off its normal).
struct TiltedView {
  double tilt = 1.0;
  double phi = 0.0;
};

/// The views that cover faces seen up to `max_tilt_deg` off their normal (ASIFT's sampling:
/// tilts in steps of sqrt(2), turns in steps of 72 / tilt degrees over half a turn); none
/// below 45 degrees, which the picture's own SIFT features already survive.
PICKDETECT_API std::vector<TiltedView> tilted_views(double max_tilt_deg);

/// SIFT features of `grey` (CV_8UC1; `mask` as for extract_features) seen in `view`, with
/// their positions, orientations and sizes carried back into the picture's pixels.
PICKDETECT_API Features features_of_view(const cv::Mat& grey, const cv::Mat& mask,
                                         const TiltedView& view,
                                         double contrast_threshold = kSiftContrastThreshold);

/// A correspondence between a model keypoint and a scene keypoint that passed the 2NN test.
struct Match {
  int model = 0;        ///< Index of the model (in the detector's model list).
  int model_point = 0;  ///< Keypoint index in that model.
  int scene_point = 0;  ///< Keypoint index in the scene.
  float distance = 0.f; ///< Descriptor distance to the nearest neighbour.
  float ratio = 0.f;    ///< Nearest / second nearest distance (lower is more distinctive).
  /// The scene feature fits other models about as well (Ambiguity::Share), or its model
  /// keypoint lies on a part of the picture another product shares (a family's panel).
  bool shared = false;
};

} // namespace pickdetect
