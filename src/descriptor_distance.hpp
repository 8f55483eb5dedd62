// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: whether two descriptors lie within a distance of each other.
#pragma once

#include <pickdetect/features.hpp>

#include <opencv2/core.hpp>
#include <opencv2/core/hal/hal.hpp>

#include <algorithm>

namespace pickdetect::detail {

/// Greatest distance at which a scene keypoint's descriptor agrees with a model keypoint's
/// where a pose already says they should meet: L2 for SIFT, whose descriptors OpenCV scales to a
/// norm of 512 (on the real tote, 300-400 explained the same keypoints, 250 lost blurred true
/// ones), Hamming for ORB's 256 bits.
constexpr double kAgreeSiftDistance = 300.0;
constexpr double kAgreeOrbDistance = 64.0;

inline double agree_distance(FeatureKind kind) {
  return kind == FeatureKind::Orb ? kAgreeOrbDistance : kAgreeSiftDistance;
}

/// Squared L2 distance between SIFT descriptor rows, or Hamming distance between ORB rows, when
/// within `limit`; a negative value when not (the sum stops as soon as it passes the limit:
/// most pairs differ early).
inline double distance_within(const cv::Mat& as, int a, const cv::Mat& bs, int b, double limit,
                              FeatureKind kind) {
  if (kind == FeatureKind::Orb) {
    const int d = cv::hal::normHamming(as.ptr<uchar>(a), bs.ptr<uchar>(b), as.cols);
    return d <= limit ? d : -1.0;
  }
  const float* x = as.ptr<float>(a);
  const float* y = bs.ptr<float>(b);
  const double bound = limit * limit;
  double sum = 0.0;
  for (int i = 0; i < as.cols; i += 16) {
    const int end = std::min(as.cols, i + 16);
    for (int j = i; j < end; ++j) {
      const double d = static_cast<double>(x[j]) - y[j];
      sum += d * d;
    }
    if (sum > bound)
      return -1.0;
  }
  return sum;
}

} // namespace pickdetect::detail
