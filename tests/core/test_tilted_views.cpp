// SPDX-License-Identifier: LGPL-2.1-or-later
// Faces seen far off their normal: the model's simulated tilted views find them, and their
// features land where the picture shows them.
#include "../support/box.hpp"
#include "common/scene.hpp"

#include <pickdetect/pickdetect.hpp>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <vector>

using namespace pickdetect;
using pickdetect::test_scene::box_model;

namespace {

/// box.png turned `tilt_deg` about its horizontal axis, seen from 700 px away, centred in a
/// 640x480 frame; `h` carries model pixels into the frame.
cv::Mat tilted_box(double tilt_deg, cv::Matx33d& h) {
  const cv::Mat& box = box_model().image;
  const double tilt = tilt_deg * CV_PI / 180.0, f = 700.0, scale = 1.2;
  const cv::Size frame(640, 480);
  const std::vector<cv::Point2f> corners = {
      {0.f, 0.f},
      {static_cast<float>(box.cols), 0.f},
      {static_cast<float>(box.cols), static_cast<float>(box.rows)},
      {0.f, static_cast<float>(box.rows)}};
  std::vector<cv::Point2f> seen;
  for (const cv::Point2f& p : corners) {
    const double x = (p.x - box.cols / 2.0) * scale, y = (p.y - box.rows / 2.0) * scale;
    const double zc = f + y * std::sin(tilt);
    seen.emplace_back(static_cast<float>(frame.width / 2.0 + f * x / zc),
                      static_cast<float>(frame.height / 2.0 + f * y * std::cos(tilt) / zc));
  }
  h = cv::Matx33d(cv::getPerspectiveTransform(corners, seen));
  cv::Mat scene = test_scene::plain_background(frame, 100), warped, mask;
  cv::warpPerspective(box, warped, cv::Mat(h), frame, cv::INTER_AREA);
  cv::warpPerspective(cv::Mat(box.size(), CV_8UC1, cv::Scalar(255)), mask, cv::Mat(h), frame,
                      cv::INTER_NEAREST);
  warped.copyTo(scene, mask);
  return scene;
}

TEST(TiltedViews, AFaceSeen68DegreesOffItsNormalIsFound) {
  cv::Matx33d h;
  const cv::Mat scene = tilted_box(68.0, h);
  Model plain = box_model();
  plain.max_tilt_deg = 0.0;
  compute_model_features(plain);
  const Detector without({plain});
  EXPECT_TRUE(without.detect(scene).instances.empty())
      << "the premise: the picture's own features do not find a face this steep";
  Model tilted = box_model();
  tilted.max_tilt_deg = 70.0;
  compute_model_features(tilted);
  const Detection d = Detector({tilted}).detect(scene);
  ASSERT_EQ(d.instances.size(), 1u) << "the tilted views find the box";
  std::vector<cv::Point2f> truth;
  cv::perspectiveTransform(box_model().principal_points, truth, cv::Mat(h));
  EXPECT_LT(cv::norm(d.instances[0].center - truth[0]), 3.0)
      << "expected the centre at (" << truth[0].x << ", " << truth[0].y << "), got ("
      << d.instances[0].center.x << ", " << d.instances[0].center.y << ")";
}

TEST(TiltedViews, EachViewsKeypointsLandWhereThePictureShowsThem) {
  // A view's keypoint carried back into the picture must describe the picture there: the
  // view's descriptor matches the one SIFT computes on the picture itself at that place, size
  // and orientation far better than a random keypoint's does.
  const cv::Mat& picture = box_model().image;
  for (const TiltedView& view : tilted_views(60.0)) {
    const Features f = features_of_view(picture, cv::Mat(), view);
    ASSERT_GE(f.keypoints.size(), 10u) << "tilt " << view.tilt << ", turn " << view.phi;
    for (const cv::KeyPoint& k : f.keypoints) {
      ASSERT_GE(k.pt.x, 0.f);
      ASSERT_GE(k.pt.y, 0.f);
      ASSERT_LE(k.pt.x, picture.cols - 1.f);
      ASSERT_LE(k.pt.y, picture.rows - 1.f);
    }
  }
  const std::vector<TiltedView> views = tilted_views(60.0);
  EXPECT_EQ(views.size(), 9u) << "tilts sqrt(2) and 2, turns of 72 / tilt degrees over half a turn";
  EXPECT_TRUE(tilted_views(40.0).empty()) << "below 45 degrees the picture's own features serve";
}

} // namespace
