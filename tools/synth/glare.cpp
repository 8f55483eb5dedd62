// SPDX-License-Identifier: LGPL-2.1-or-later
// Glare: specular reflections of the lights on glossy print or stretch film, bright patches
// that clip to white and wipe out the texture under them. They change no ground truth (the
// object is still there, nothing lies on it).
#include "synth.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>

namespace synth {

void add_glare(cv::Mat& frame, const std::vector<ModelPicture>& models,
               const std::vector<Placed>& placed, int count, Random& rng) {
  if (placed.empty())
    return;
  for (int k = 0; k < count; ++k) {
    // A streak on a random instance, a tenth to a third of its shorter side long.
    const Placed& target =
        placed[static_cast<size_t>(rng.integer(0, static_cast<int>(placed.size()) - 1))];
    const ModelPicture& m = models[static_cast<size_t>(target.model)];
    const cv::Point2d model_at(rng.uniform(0.15, 0.85) * m.bgr.cols,
                               rng.uniform(0.15, 0.85) * m.bgr.rows);
    const std::vector<cv::Point2d> at = apply(
        target.homography, {model_at, model_at + cv::Point2d(std::min(m.bgr.cols, m.bgr.rows), 0)});
    const double side = cv::norm(at[1] - at[0]); // the shorter side, as seen in the frame
    const double length = rng.uniform(0.12, 0.35) * side;
    const double width = length * rng.uniform(0.25, 0.7);
    const double angle = rng.uniform(0, 180);
    const double strength = rng.uniform(220, 380);
    const double soft = std::max(1.0, 0.25 * width);
    const int reach = static_cast<int>(std::ceil(length + 4 * soft)) + 2;
    const cv::Rect roi =
        cv::Rect(cvRound(at[0].x) - reach, cvRound(at[0].y) - reach, 2 * reach, 2 * reach) &
        cv::Rect(0, 0, frame.cols, frame.rows);
    if (roi.empty())
      continue;
    cv::Mat spot(roi.size(), CV_32FC1, cv::Scalar(0));
    cv::ellipse(spot,
                cv::RotatedRect(cv::Point2f(static_cast<float>(at[0].x - roi.x),
                                            static_cast<float>(at[0].y - roi.y)),
                                cv::Size2f(static_cast<float>(length), static_cast<float>(width)),
                                static_cast<float>(angle)),
                cv::Scalar(1.0), cv::FILLED, cv::LINE_AA);
    cv::GaussianBlur(spot, spot, cv::Size(0, 0), soft);
    cv::Mat spot3;
    cv::merge(std::vector<cv::Mat>{spot, spot, spot}, spot3);
    cv::Mat region = frame(roi);
    region += spot3 * strength; // clipped to 255 when the frame is written
  }
}

} // namespace synth
