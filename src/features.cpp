// SPDX-License-Identifier: LGPL-2.1-or-later
// Feature extraction: SIFT keypoints and descriptors.
#include <pickdetect/features.hpp>

#include <opencv2/features2d.hpp>

namespace pickdetect {

Features extract_features(const cv::Mat& grey, const cv::Mat& mask) {
  CV_Assert(grey.type() == CV_8UC1);
  Features f;
  if (grey.empty())
    return f;
  // One detector per call: cv::SIFT keeps no state between calls, and per-call objects keep
  // concurrent callers apart. Its keypoints come out sorted, so the order is deterministic.
  cv::Ptr<cv::SIFT> sift = cv::SIFT::create();
  sift->detectAndCompute(grey, mask, f.keypoints, f.descriptors);
  return f;
}

} // namespace pickdetect
