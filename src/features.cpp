// SPDX-License-Identifier: LGPL-2.1-or-later
// Feature extraction: SIFT keypoints and descriptors.
#include <pickdetect/features.hpp>

#include <pickdetect/error.hpp>

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace pickdetect {
namespace {

/// OpenCV's SIFT finds its first octave on the picture doubled in size and reports positions
/// as doubled-picture pixel / 2; with pixel centres on integers, doubled pixel x lies at
/// x / 2 - 0.25 in the picture. Every keypoint (all octaves descend from the doubled picture
/// by dropping every other pixel) therefore sits a quarter pixel right of and below where it
/// was found; this takes it back.
constexpr float kSiftPositionBias = 0.25f;

/// ORB: at most this many keypoints per picture, on this many pyramid levels this far apart.
/// The levels reach down to a third of the picture's size, so a model meets its instances from
/// about 0.35 to 2.8 times its size.
constexpr int kOrbFeatures = 3000;
constexpr int kOrbLevels = 8;
constexpr float kOrbLevelStep = 1.2f;
/// FAST threshold: low enough for dark, low-contrast objects (the default, 20, misses them).
constexpr int kOrbFastThreshold = 10;

Features orb_features(const cv::Mat& grey, const cv::Mat& mask) {
  Features f;
  cv::Ptr<cv::ORB> orb = cv::ORB::create(kOrbFeatures, kOrbLevelStep, kOrbLevels, 31, 0, 2,
                                         cv::ORB::HARRIS_SCORE, 31, kOrbFastThreshold);
  orb->detectAndCompute(grey, mask, f.keypoints, f.descriptors);
  // ORB finds level-L keypoints on the picture shrunk by s = 1.2^L (pixel centres aligned, as
  // cv::resize does) and reports them as position * s; pixel x of the level lies at
  // (x + 0.5) * s - 0.5 in the picture.
  for (cv::KeyPoint& k : f.keypoints) {
    const float s = std::pow(kOrbLevelStep, static_cast<float>(k.octave));
    k.pt += cv::Point2f(0.5f * (s - 1.f), 0.5f * (s - 1.f));
  }
  return f;
}

/// Every fourth row and column is enough for the percentiles of a frame's grey.
constexpr int kExposureStride = 4;
/// The frame's grey span runs from this share of its (sampled) pixels to the same share from
/// the top: few enough that a few small objects on a plain conveyor set it, not the belt.
constexpr double kSpanTail = 0.001;
/// A frame whose grey spans less than this is taken as exposed darker or flatter than a
/// well-lit one: every contrast in it, the objects' too, is that much weaker.
constexpr double kWellLitSpan = 200.0;

} // namespace

double exposure_contrast_share(const cv::Mat& grey) {
  CV_Assert(grey.type() == CV_8UC1);
  long hist[256] = {0};
  long n = 0;
  for (int y = 0; y < grey.rows; y += kExposureStride) {
    const uchar* g = grey.ptr<uchar>(y);
    for (int x = 0; x < grey.cols; x += kExposureStride)
      ++hist[g[x]];
    n += (grey.cols + kExposureStride - 1) / kExposureStride;
  }
  if (n == 0)
    return 1.0;
  auto percentile = [&](double q) {
    long seen = 0;
    for (int v = 0; v < 256; ++v)
      if ((seen += hist[v]) >= q * n)
        return v;
    return 255;
  };
  const double span = percentile(1.0 - kSpanTail) - percentile(kSpanTail);
  return std::clamp(span / kWellLitSpan, kLeastFrameContrastShare, 1.0);
}

const char* feature_name(FeatureKind kind) {
  return kind == FeatureKind::Orb ? "orb" : "sift";
}

FeatureKind parse_features(const std::string& name) {
  for (FeatureKind k : {FeatureKind::Sift, FeatureKind::Orb})
    if (name == feature_name(k))
      return k;
  throw Error("unknown features '" + name + "' (expected sift or orb)");
}

Features extract_features(const cv::Mat& grey, const cv::Mat& mask, FeatureKind kind,
                          double contrast_threshold) {
  CV_Assert(grey.type() == CV_8UC1);
  Features f;
  if (grey.empty())
    return f;
  if (kind == FeatureKind::Orb)
    return orb_features(grey, mask);
  // One detector per call: cv::SIFT keeps no state between calls, and per-call objects keep
  // concurrent callers apart. Its keypoints come out sorted, so the order is deterministic.
  const double threshold = contrast_threshold >= 0.0 ? contrast_threshold : kSiftContrastThreshold;
  cv::Ptr<cv::SIFT> sift = cv::SIFT::create(0, 3, threshold);
  sift->detectAndCompute(grey, mask, f.keypoints, f.descriptors);
  for (cv::KeyPoint& k : f.keypoints)
    k.pt -= cv::Point2f(kSiftPositionBias, kSiftPositionBias);
  return f;
}

Features extract_features_scaled(const cv::Mat& grey, double scale, FeatureKind kind,
                                 double contrast_threshold) {
  if (!(scale > 0.0) || scale >= 1.0)
    return extract_features(grey, cv::Mat(), kind, contrast_threshold);
  cv::Mat small;
  cv::resize(grey, small, cv::Size(), scale, scale, cv::INTER_AREA);
  Features f = extract_features(small, cv::Mat(), kind, contrast_threshold);
  // cv::resize aligns pixel centres: small pixel x covers grey's (x + 0.5) / fx - 0.5.
  const double fx = static_cast<double>(small.cols) / grey.cols;
  const double fy = static_cast<double>(small.rows) / grey.rows;
  for (cv::KeyPoint& k : f.keypoints) {
    k.pt = cv::Point2f(static_cast<float>((k.pt.x + 0.5) / fx - 0.5),
                       static_cast<float>((k.pt.y + 0.5) / fy - 0.5));
    k.size = static_cast<float>(k.size / scale);
  }
  return f;
}

} // namespace pickdetect
