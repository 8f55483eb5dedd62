// SPDX-License-Identifier: LGPL-2.1-or-later
// Faces seen far off their normal: the model's simulated tilted views find them, and their
// features land where the picture shows them.
#include "../support/box.hpp"
#include "../support/tilted_face.hpp"
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

TEST(TiltedViews, AFaceSeen68DegreesOffItsNormalIsFound) {
  cv::Matx33d h;
  const cv::Mat scene =
      test_scene::tilted_face(box_model().image, 68.0, 1.2, 700.0, cv::Size(640, 480), h);
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
