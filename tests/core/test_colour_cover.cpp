// SPDX-License-Identifier: LGPL-2.1-or-later
// Pick safety in colour: an object of another colour lying on a plain part of a colour print,
// as light as the print there (the grey comparison sees flat on flat), makes the instance
// covered when the frame has colour; a highlight and a coloured light do not. Scenes built
// from a crop of OpenCV's fruits.jpg beside a plain orange panel.
#include "../support/colour_print.hpp"
#include "../support/folder_test.hpp"
#include "common/scene.hpp"

#include <pickdetect/pickdetect.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <string>
#include <vector>

using namespace pickdetect;
using pickdetect::test_scene::Pose;

namespace {

const std::string kData = PICKDETECT_TEST_DATA;

/// The panel's orange (BGR) and where it lies in the picture.
const cv::Vec3b kOrange(40, 130, 230);
const cv::Rect kPanel(300, 0, 160, 220);
const Pose kPose{{480.f, 330.f}, 20.0, 0.9};

double grey_level(const cv::Vec3b& bgr) {
  return 0.114 * bgr[0] + 0.587 * bgr[1] + 0.299 * bgr[2];
}

/// A blue-green as light as the orange in grey.
cv::Vec3b teal_like_orange() {
  const double b = 200, r = 40;
  const double g = (grey_level(kOrange) - 0.114 * b - 0.299 * r) / 0.587;
  return cv::Vec3b(static_cast<uchar>(b), static_cast<uchar>(std::lround(g)),
                   static_cast<uchar>(r));
}

class ColourCover : public test_scene::FolderTest {
protected:
  ColourCover() : FolderTest("pickdetect-colour-cover-") {}
  void SetUp() override {
    FolderTest::SetUp();
    const cv::Mat fruits = test_scene::fruits_print(kData);
    ASSERT_FALSE(fruits.empty());
    picture_.create(220, 460, CV_8UC3);
    fruits.copyTo(picture_(cv::Rect(0, 0, fruits.cols, fruits.rows)));
    picture_(kPanel).setTo(kOrange);
    cv::imwrite(path("fruits_panel.png"), picture_);
    models_ = load_models(path("fruits_panel.png"));
  }

  /// A colour scene: smooth grey noise, the picture at kPose.
  cv::Mat scene() const {
    cv::Mat grey = test_scene::smooth_noise_background({1000, 700}, 5), out;
    cv::cvtColor(grey, out, cv::COLOR_GRAY2BGR);
    test_scene::paste(out, picture_, {kPose});
    return out;
  }

  /// Where a point of the picture lies in the scene.
  static cv::Point to_scene(cv::Point2f p, cv::Size picture) {
    const cv::Point2f q = test_scene::apply(test_scene::model_to_scene(picture, kPose), p);
    return {static_cast<int>(std::lround(q.x)), static_cast<int>(std::lround(q.y))};
  }

  /// The one instance found in `frame`, with the colour frame or in grey only.
  Instance detect_one(const cv::Mat& frame, bool in_colour) const {
    cv::Mat grey;
    cv::cvtColor(frame, grey, cv::COLOR_BGR2GRAY);
    const Detector detector(models_);
    const Detection d = in_colour ? detector.detect(grey, frame) : detector.detect(grey);
    EXPECT_EQ(d.instances.size(), 1u);
    return d.instances.empty() ? Instance() : d.instances.front();
  }

  cv::Mat picture_;
  std::vector<Model> models_;
};

} // namespace

TEST_F(ColourCover, AnObjectOfAnotherColourOnAPlainPartOfThePrintCoversIt) {
  cv::Mat frame = scene();
  // A plain card, as light as the orange in grey, over the middle of the panel.
  const cv::Point centre = to_scene({380.f, 110.f}, picture_.size());
  const cv::Vec3b teal = teal_like_orange();
  cv::ellipse(frame, centre, {34, 26}, kPose.angle, 0, 360, cv::Scalar(teal[0], teal[1], teal[2]),
              cv::FILLED, cv::LINE_AA);

  const Instance in_grey = detect_one(frame, false);
  EXPECT_FALSE(in_grey.covered) << "in grey the card is flat on flat: nothing tells it";
  const Instance in_colour = detect_one(frame, true);
  EXPECT_TRUE(in_colour.covered) << "the card's colour is not the print's";
  EXPECT_FALSE(in_colour.pickable);
}

TEST_F(ColourCover, AHighlightOrAColouredLightCoversNothing) {
  // A white highlight over the panel: lighter and greyer than the print, as glare is.
  cv::Mat glare = scene();
  cv::Mat spot = cv::Mat::zeros(glare.size(), CV_32F);
  cv::circle(spot, to_scene({380.f, 110.f}, picture_.size()), 30, cv::Scalar(1.0), cv::FILLED);
  cv::GaussianBlur(spot, spot, cv::Size(0, 0), 8.0);
  for (int y = 0; y < glare.rows; ++y)
    for (int x = 0; x < glare.cols; ++x) {
      const float a = spot.at<float>(y, x);
      cv::Vec3b& p = glare.at<cv::Vec3b>(y, x);
      for (int c = 0; c < 3; ++c)
        p[c] = cv::saturate_cast<uchar>(p[c] * (1.0f - a) + 245.0f * a);
    }
  const Instance under_glare = detect_one(glare, true);
  EXPECT_FALSE(under_glare.covered) << "a highlight is not an object";
  EXPECT_TRUE(under_glare.pickable);

  // A warm light over the whole frame: red up, blue down.
  cv::Mat warm = scene();
  std::vector<cv::Mat> channels;
  cv::split(warm, channels);
  channels[0] *= 0.8;
  channels[2] *= 1.15;
  cv::merge(channels, warm);
  const Instance in_warm_light = detect_one(warm, true);
  EXPECT_FALSE(in_warm_light.covered) << "the light's colour is the same all over the instance";
  EXPECT_TRUE(in_warm_light.pickable);
}
