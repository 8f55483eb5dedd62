// SPDX-License-Identifier: LGPL-2.1-or-later
// Features: where keypoints sit, the contrast threshold that follows the exposure, ORB and
// reduced pictures in frame pixels.
#include "common/scene.hpp"

#include <pickdetect/pickdetect.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <vector>

using namespace pickdetect;

TEST(Features, KeypointsSitWhereTheBlobIs) {
  // A dark Gaussian blob centred exactly on (80, 90), pixel centres on integers.
  cv::Mat grey(180, 160, CV_8UC1);
  for (int y = 0; y < grey.rows; ++y)
    for (int x = 0; x < grey.cols; ++x)
      grey.at<uchar>(y, x) = cv::saturate_cast<uchar>(
          200.0 - 150.0 * std::exp(-((x - 80.0) * (x - 80.0) + (y - 90.0) * (y - 90.0)) / 50.0));
  const Features f = extract_features(grey);
  ASSERT_FALSE(f.keypoints.empty());
  const cv::KeyPoint* best = &f.keypoints[0];
  for (const cv::KeyPoint& k : f.keypoints)
    if (k.response > best->response)
      best = &k;
  EXPECT_NEAR(best->pt.x, 80.f, 0.1f);
  EXPECT_NEAR(best->pt.y, 90.f, 0.1f);
}

TEST(Features, TheContrastThresholdFollowsTheFramesExposure) {
  // A ramp over every grey level spans about 250 of them: well lit. Dimmed or flattened to 30 %
  // of that span, 76 of them: 76 / 200 of the threshold. Uniform grey: the least share.
  cv::Mat ramp(64, 256, CV_8UC1);
  for (int x = 0; x < ramp.cols; ++x)
    ramp.col(x).setTo(x);
  cv::Mat dim, flat;
  ramp.convertTo(dim, CV_8UC1, 0.3);
  ramp.convertTo(flat, CV_8UC1, 0.3, 120.0);
  EXPECT_DOUBLE_EQ(exposure_contrast_share(ramp), 1.0);
  EXPECT_NEAR(exposure_contrast_share(dim), 76.0 / 200, 0.02);
  EXPECT_NEAR(exposure_contrast_share(flat), exposure_contrast_share(dim), 0.01);
  EXPECT_DOUBLE_EQ(exposure_contrast_share(cv::Mat(64, 64, CV_8UC1, cv::Scalar(90))), 0.25);
  // A plain, noisy belt with one small printed object (1 % of the frame) is well lit: the
  // object's print sets the span, not the belt.
  cv::Mat belt(400, 400, CV_8UC1);
  cv::randn(belt, 110, 4);
  cv::Mat object = belt(cv::Rect(180, 180, 40, 40));
  for (int y = 0; y < object.rows; ++y)
    for (int x = 0; x < object.cols; ++x)
      object.at<uchar>(y, x) = ((x / 5 + y / 5) % 2) ? 230 : 15;
  EXPECT_DOUBLE_EQ(exposure_contrast_share(belt), 1.0);
  // The lower threshold keeps many more of a dim picture's keypoints.
  const cv::Mat graf =
      cv::imread(std::string(PICKDETECT_TEST_DATA) + "/graf1.png", cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(graf.empty());
  cv::Mat dim_graf;
  graf.convertTo(dim_graf, CV_8UC1, 0.25);
  const Features fixed = extract_features(dim_graf);
  const Features followed =
      extract_features(dim_graf, cv::Mat(), FeatureKind::Sift,
                       kSiftContrastThreshold * exposure_contrast_share(dim_graf));
  EXPECT_GT(followed.keypoints.size(), fixed.keypoints.size() * 3 / 2)
      << followed.keypoints.size() << " against " << fixed.keypoints.size();
}

TEST(Features, OrbAndReducedPicturesKeepPositionsInFramePixels) {
  // The same blob as above, found by ORB and by SIFT on a picture shrunk by 0.5.
  cv::Mat grey(240, 320, CV_8UC1);
  for (int y = 0; y < grey.rows; ++y)
    for (int x = 0; x < grey.cols; ++x)
      grey.at<uchar>(y, x) = cv::saturate_cast<uchar>(
          200.0 -
          150.0 * std::exp(-((x - 160.0) * (x - 160.0) + (y - 120.0) * (y - 120.0)) / 200.0));
  const Features half = extract_features_scaled(grey, 0.5);
  ASSERT_FALSE(half.keypoints.empty());
  const cv::KeyPoint* best = &half.keypoints[0];
  for (const cv::KeyPoint& k : half.keypoints)
    if (k.response > best->response)
      best = &k;
  EXPECT_NEAR(best->pt.x, 160.f, 0.25f);
  EXPECT_NEAR(best->pt.y, 120.f, 0.25f);
  EXPECT_EQ(parse_features("orb"), FeatureKind::Orb);
  EXPECT_THROW(parse_features("surf"), Error);
}
