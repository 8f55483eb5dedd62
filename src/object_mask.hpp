// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: which pixels of a model picture show the object, and the picture
// continued beyond them.
#pragma once

#include <opencv2/core.hpp>

namespace pickdetect::detail {

/// The pixels of a picture of `size` that show the object: `mask` (CV_8UC1, 255 on the
/// object), or the whole picture when there is none (a Model put together by a program rather
/// than loaded, whose mask was left empty).
inline cv::Mat object_mask(const cv::Mat& mask, const cv::Size& size) {
  return mask.empty() ? cv::Mat(size, CV_8UC1, cv::Scalar(255)) : mask;
}

/// `picture` (CV_8UC1) with the pixels outside the object (`mask` 0) taken from the nearest
/// pixel of the object, as the features see it. A transparent pixel's colour is no part of the
/// object, yet against it the outline makes an edge whose keypoints agree with any straight
/// edge of a frame of the same contrast (a pack whose transparent pixels are light placed along
/// a belt's light border); continued, the outline makes none, as a picture's own border makes
/// none (SIFT keeps off it, and the tilted views replicate it). `picture` itself when the mask
/// is empty or covers it all.
cv::Mat continue_object(const cv::Mat& picture, const cv::Mat& mask);

} // namespace pickdetect::detail
