// SPDX-License-Identifier: LGPL-2.1-or-later
// Scenes for the tests and the benchmark, built from a real textured picture at known poses, so
// expectations are exact.
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <vector>

namespace pickdetect::test_scene {

/// Where a copy of the model picture is placed: its centre (w/2, h/2) goes to `center`, turned
/// by `angle` degrees clockwise on screen (image y axis down) and scaled by `scale`.
struct Pose {
  cv::Point2f center;
  double angle = 0.0;
  double scale = 1.0;
};

/// The 2x3 affine map that carries model pixels into the scene for `pose`.
inline cv::Matx23d model_to_scene(const cv::Size& model_size, const Pose& pose) {
  const double rad = pose.angle * CV_PI / 180.0;
  const double c = std::cos(rad) * pose.scale, s = std::sin(rad) * pose.scale;
  const double mx = model_size.width / 2.0, my = model_size.height / 2.0;
  return {c, -s, pose.center.x - (c * mx - s * my), s, c, pose.center.y - (s * mx + c * my)};
}

inline cv::Point2f apply(const cv::Matx23d& m, cv::Point2f p) {
  return {static_cast<float>(m(0, 0) * p.x + m(0, 1) * p.y + m(0, 2)),
          static_cast<float>(m(1, 0) * p.x + m(1, 1) * p.y + m(1, 2))};
}

/// A background of the given grey level with mild, seeded sensor noise.
inline cv::Mat plain_background(const cv::Size& size, int level = 110, int seed = 7) {
  cv::Mat noise(size, CV_8UC1);
  cv::RNG rng(static_cast<uint64>(seed));
  rng.fill(noise, cv::RNG::NORMAL, level, 4);
  return noise;
}

/// A background of smooth noise: uniform in [level, level + span), blurred by a Gaussian of
/// `sigma` pixels, seeded.
inline cv::Mat smooth_noise_background(const cv::Size& size, int seed = 1234, int level = 100,
                                       int span = 40, double sigma = 2.0) {
  cv::Mat noise(size, CV_8UC1);
  cv::RNG rng(static_cast<uint64>(seed));
  rng.fill(noise, cv::RNG::UNIFORM, 0, span);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), sigma);
  return noise + cv::Scalar(level);
}

/// Pastes the model picture (grey, CV_8UC1) onto `scene` at each pose, later poses on top.
inline void paste(cv::Mat& scene, const cv::Mat& model, const std::vector<Pose>& poses) {
  const cv::Mat ones(model.size(), CV_8UC1, cv::Scalar(255));
  for (const Pose& pose : poses) {
    const cv::Matx23d m = model_to_scene(model.size(), pose);
    cv::Mat warped, mask;
    cv::warpAffine(model, warped, cv::Mat(m), scene.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    cv::warpAffine(ones, mask, cv::Mat(m), scene.size(), cv::INTER_NEAREST, cv::BORDER_CONSTANT);
    warped.copyTo(scene, mask);
  }
}

} // namespace pickdetect::test_scene
