// SPDX-License-Identifier: LGPL-2.1-or-later
// Feature extraction: SIFT keypoints and descriptors.
#include <pickdetect/features.hpp>

#include <opencv2/features2d.hpp>

namespace pickdetect {
namespace {

/// OpenCV's SIFT finds its first octave on the picture doubled in size and reports positions
/// as doubled-picture pixel / 2; with pixel centres on integers, doubled pixel x lies at
/// x / 2 - 0.25 in the picture. Every keypoint (all octaves descend from the doubled picture
/// by dropping every other pixel) therefore sits a quarter pixel right of and below where it
/// was found; this takes it back.
constexpr float kSiftPositionBias = 0.25f;

} // namespace

Features extract_features(const cv::Mat& grey, const cv::Mat& mask) {
  CV_Assert(grey.type() == CV_8UC1);
  Features f;
  if (grey.empty())
    return f;
  // One detector per call: cv::SIFT keeps no state between calls, and per-call objects keep
  // concurrent callers apart. Its keypoints come out sorted, so the order is deterministic.
  cv::Ptr<cv::SIFT> sift = cv::SIFT::create();
  sift->detectAndCompute(grey, mask, f.keypoints, f.descriptors);
  for (cv::KeyPoint& k : f.keypoints)
    k.pt -= cv::Point2f(kSiftPositionBias, kSiftPositionBias);
  return f;
}

} // namespace pickdetect
