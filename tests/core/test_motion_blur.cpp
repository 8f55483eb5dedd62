// SPDX-License-Identifier: LGPL-2.1-or-later
// The belt's motion blur: its length measured on an instance against its model's picture, and
// undone along any direction.
#include "../support/box.hpp"
#include "common/scene.hpp"
#include "motion_blur.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <string>

using namespace pickdetect;
using pickdetect::test_scene::Pose;

namespace {

const cv::Size kSize(640, 480);

/// A smooth bright spot of `level` grey levels on `scene` around `at`: a highlight.
void add_highlight(cv::Mat& scene, const cv::Point& at, double level) {
  cv::Mat spot = cv::Mat::zeros(scene.size(), CV_32F), wide;
  cv::circle(spot, at, 30, cv::Scalar(level), cv::FILLED);
  cv::GaussianBlur(spot, spot, cv::Size(0, 0), 15);
  scene.convertTo(wide, CV_32F);
  cv::Mat(wide + spot).convertTo(scene, CV_8UC1);
}

/// Sensor noise: Gaussian, 2 grey levels, drawn from `seed`.
void add_sensor_noise(cv::Mat& scene, uint64 seed) {
  cv::Mat noise(scene.size(), CV_16SC1), wide;
  cv::RNG(seed).fill(noise, cv::RNG::NORMAL, 0, 2);
  scene.convertTo(wide, CV_16SC1);
  cv::Mat(wide + noise).convertTo(scene, CV_8UC1);
}

/// `picture` (the box's by default) at `pose` on a textured belt, with a highlight of
/// `highlight` grey levels left of its middle (none: 0), blurred by the lens (a Gaussian of
/// `lens` sigma) and along `step`'s direction by a box of `length` pixels (a line kernel sampled
/// finely), with sensor noise.
cv::Mat blurred_scene(const Pose& pose, const cv::Point2f& step, double length,
                      const cv::Mat& picture = test_scene::box_model().image,
                      double highlight = 0.0, double lens = 0.0) {
  cv::Mat scene = test_scene::smooth_noise_background(kSize, 5);
  test_scene::paste(scene, picture, {pose});
  if (highlight > 0.0)
    add_highlight(scene, cv::Point(cvRound(pose.center.x) - 60, cvRound(pose.center.y) - 40),
                  highlight);
  if (lens > 0.0)
    cv::GaussianBlur(scene, scene, cv::Size(0, 0), lens);
  if (length > 0.0) {
    const double n = std::hypot(step.x, step.y);
    const int r = static_cast<int>(std::ceil(length / 2)) + 1;
    cv::Mat kernel = cv::Mat::zeros(2 * r + 1, 2 * r + 1, CV_32F);
    const int samples = 400;
    for (int i = 0; i < samples; ++i) {
      const double t = (i + 0.5) / samples * length - length / 2;
      kernel.at<float>(cvRound(r + t * step.y / n), cvRound(r + t * step.x / n)) += 1.f / samples;
    }
    cv::filter2D(scene, scene, -1, kernel);
  }
  add_sensor_noise(scene, 7);
  return scene;
}

cv::Matx33d homography_of(const Pose& pose,
                          const cv::Size& picture = test_scene::box_model().image.size()) {
  const cv::Matx23d a = test_scene::model_to_scene(picture, pose);
  return {a(0, 0), a(0, 1), a(0, 2), a(1, 0), a(1, 1), a(1, 2), 0, 0, 1};
}

TEST(MotionBlur, LengthIsMeasuredAlongTheBeltWithinAPixel) {
  const Pose pose{{320.f, 240.f}, 25.0, 0.8};
  for (const cv::Point2f step :
       {cv::Point2f(25.f, 0.f), cv::Point2f(0.f, 20.f), cv::Point2f(14.f, -14.f)}) {
    const double longest = std::hypot(step.x, step.y);
    for (const double length : {0.0, 0.3 * longest, 0.5 * longest, 0.9 * longest}) {
      const std::optional<double> got = detail::measure_blur_length(
          blurred_scene(pose, step, length), test_scene::box_model(), homography_of(pose), step);
      ASSERT_TRUE(got.has_value()) << "step (" << step.x << ", " << step.y << "), " << length;
      EXPECT_NEAR(*got, length, 1.0) << "step (" << step.x << ", " << step.y << ")";
    }
  }
}

// A print of soft shapes and little fine detail (OpenCV's fruits.jpg) under a highlight, which
// its picture does not have. Measured by how much the frame streaks along the motion, the
// streaked highlight made the blur 8, 11.5 and 17 px for 5, 9 and 14 (on a synthetic belt of
// other products 15 px for 9, and the over-long blur undone lost an object for 29 frames).
TEST(MotionBlur, AHighlightOnSoftPrintDoesNotLengthenTheBlur) {
  const cv::Mat fruits =
      cv::imread(std::string(PICKDETECT_TEST_DATA) + "/fruits.jpg", cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(fruits.empty());
  Model soft;
  soft.image = fruits;
  soft.outline = {{0.f, 0.f},
                  {static_cast<float>(fruits.cols), 0.f},
                  {static_cast<float>(fruits.cols), static_cast<float>(fruits.rows)},
                  {0.f, static_cast<float>(fruits.rows)}};
  const Pose pose{{320.f, 240.f}, 8.0, 0.4};
  const cv::Point2f step(18.f, 0.f);
  for (const double length : {5.0, 9.0, 14.0}) {
    const std::optional<double> got =
        detail::measure_blur_length(blurred_scene(pose, step, length, fruits, 80.0, 0.65), soft,
                                    homography_of(pose, fruits.size()), step);
    ASSERT_TRUE(got.has_value()) << length;
    EXPECT_NEAR(*got, length, 1.0);
  }
}

TEST(MotionBlur, UndoingTheBlurBringsTheSharpPictureBack) {
  const Pose pose{{320.f, 240.f}, 25.0, 0.8};
  const cv::Mat sharp = blurred_scene(pose, cv::Point2f(1.f, 0.f), 0.0);
  const cv::Rect inside(120, 100, 400, 280);
  for (const cv::Point2f blur :
       {cv::Point2f(12.f, 0.f), cv::Point2f(0.f, 12.f), cv::Point2f(-8.5f, 8.5f)}) {
    const cv::Mat blurred = blurred_scene(pose, blur, std::hypot(blur.x, blur.y));
    const cv::Mat undone = detail::undo_motion_blur(blurred, blur);
    const double before = cv::norm(blurred(inside), sharp(inside), cv::NORM_L2);
    const double after = cv::norm(undone(inside), sharp(inside), cv::NORM_L2);
    EXPECT_LT(after, 0.75 * before) << "blur (" << blur.x << ", " << blur.y << ")";
  }
  // Shorter than SIFT's own smoothing: left as it is.
  const cv::Mat slight = blurred_scene(pose, cv::Point2f(1.f, 0.f), 1.5);
  EXPECT_EQ(
      cv::norm(detail::undo_motion_blur(slight, cv::Point2f(1.5f, 0.f)), slight, cv::NORM_INF),
      0.0);
}

/// SIFT keypoints (at a faint print's lowered contrast threshold) within 6 px of `outline`'s
/// edges and at least 20 px from its corners: blobs along a rim.
int keypoints_along_rim(const cv::Mat& grey, const std::vector<cv::Point2f>& outline) {
  std::vector<cv::KeyPoint> found;
  cv::SIFT::create(0, 3, 0.02)->detect(grey, found);
  int along = 0;
  for (const cv::KeyPoint& k : found) {
    const bool near_corner = std::any_of(outline.begin(), outline.end(), [&](const cv::Point2f& c) {
      return cv::norm(k.pt - c) < 20.0;
    });
    along += !near_corner && std::abs(cv::pointPolygonTest(outline, k.pt, true)) < 6.0;
  }
  return along;
}

TEST(MotionBlur, UndoingTheBlurRaisesNoRowsOfBlobsAlongALightBoxsRim) {
  // A plain white box turned 15 degrees on a dark belt, blurred 9 px along the rows: the
  // deconvolution must not ring along its rim, where SIFT would find rows of small blobs.
  const cv::Mat plain(140, 200, CV_8UC1, cv::Scalar(250));
  const Pose pose{{320.f, 240.f}, 15.0, 1.0};
  cv::Mat scene = test_scene::smooth_noise_background(kSize, 5, 50);
  test_scene::paste(scene, plain, {pose});
  cv::Mat kernel(1, 9, CV_32F, cv::Scalar(1.0 / 9.0));
  cv::filter2D(scene, scene, -1, kernel);
  add_sensor_noise(scene, 3);
  const cv::Matx23d to_scene = test_scene::model_to_scene(plain.size(), pose);
  std::vector<cv::Point2f> rim;
  for (const cv::Point2f corner :
       {cv::Point2f(0, 0), cv::Point2f(200, 0), cv::Point2f(200, 140), cv::Point2f(0, 140)})
    rim.push_back(test_scene::apply(to_scene, corner));
  const int blurred = keypoints_along_rim(scene, rim);
  const int undone = keypoints_along_rim(detail::undo_motion_blur(scene, {9.f, 0.f}), rim);
  // Deconvolved alike everywhere (noise-to-signal 0.01): 73 along the rim against 0; damped
  // beside strong edges: 5.
  EXPECT_LE(undone, blurred + 10) << "blurred frame " << blurred << ", undone " << undone;
}

} // namespace
