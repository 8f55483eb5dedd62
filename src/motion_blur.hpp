// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: the motion blur of a moving belt, measured on an instance, undone
// before SIFT (FeatureReuse) and laid on model pictures compared with the frame.
#pragma once

#include <pickdetect/model.hpp>

#include <opencv2/core.hpp>

#include <optional>

namespace pickdetect::detail {

/// Blur shorter than this many pixels is left as it is: SIFT's own smoothing (sigma 1.6)
/// covers it.
constexpr double kLeastBlurPx = 2.0;

/// How long the motion blur along `step` (the instance's motion in one frame, frame pixels) is
/// on `grey`, in pixels: the model's picture carried into the frame by `homography`, blurred
/// along the motion by a box of 0 to |step| pixels (a shutter open for none to all of the
/// frame time), against the frame's pixels under the instance (normalised correlation on the
/// picture's mask, its rim left out). The length that correlates best, when its correlation
/// reaches `least_correlation`; nullopt when the instance is not in the frame or matches no
/// length that well.
std::optional<double> measure_blur_length(const cv::Mat& grey, const Model& model,
                                          const cv::Matx33d& homography, const cv::Point2f& step,
                                          double least_correlation = 0.8);

/// `grey` (CV_8UC1) with a motion blur of `blur` (its direction and length, frame pixels: a box
/// kernel along it, centred) undone by Wiener deconvolution, row by row along the motion. A
/// blur shorter than kLeastBlurPx: `grey` as it is.
cv::Mat undo_motion_blur(const cv::Mat& grey, const cv::Point2f& blur);

/// `picture` (any depth and channels) with a motion blur of `blur` (its direction and length,
/// pixels: a box kernel along it, centred), its border replicated; a blur shorter than a pixel
/// leaves it as it is.
cv::Mat motion_blurred(const cv::Mat& picture, const cv::Point2f& blur);

} // namespace pickdetect::detail
