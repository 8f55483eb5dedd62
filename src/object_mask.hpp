// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: which pixels of a model picture show the object.
#pragma once

#include <opencv2/core.hpp>

namespace pickdetect::detail {

/// The pixels of a picture of `size` that show the object: `mask` (CV_8UC1, 255 on the
/// object), or the whole picture when there is none (a Model put together by a program rather
/// than loaded, whose mask was left empty).
inline cv::Mat object_mask(const cv::Mat& mask, const cv::Size& size) {
  return mask.empty() ? cv::Mat(size, CV_8UC1, cv::Scalar(255)) : mask;
}

} // namespace pickdetect::detail
