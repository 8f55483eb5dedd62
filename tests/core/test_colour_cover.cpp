// SPDX-License-Identifier: LGPL-2.1-or-later
// Pick safety in colour: an object of another colour lying on a plain part of a colour print,
// as light as the print there (the grey comparison sees flat on flat), makes the instance
// covered when the frame has colour, and so does a card of another colour too small for the grey
// comparison's groups; a highlight and a coloured light do not. Scenes built
// from a crop of OpenCV's fruits.jpg beside a plain orange panel. On a grey picture (box.png),
// a disc of clear colour lighter than the print, its rim fading as a highlight's does, covers
// it in colour only; a highlight does not.
#include "../support/box.hpp"
#include "../support/colour_print.hpp"
#include "../support/folder_test.hpp"
#include "../support/soft_disc.hpp"
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

/// The one instance of `models` found in `frame` (BGR), with the colour frame or in grey only.
Instance detect_one(const std::vector<Model>& models, const cv::Mat& frame, bool in_colour) {
  cv::Mat grey;
  cv::cvtColor(frame, grey, cv::COLOR_BGR2GRAY);
  const Detector detector(models);
  const Detection d = in_colour ? detector.detect(grey, frame) : detector.detect(grey);
  EXPECT_EQ(d.instances.size(), 1u);
  return d.instances.empty() ? Instance() : d.instances.front();
}

/// Expects the one instance of `models` in `frame` to be found covered with the frame's colour
/// (`why`) and not in grey (`why_not_in_grey`).
void expect_covered_in_colour_only(const std::vector<Model>& models, const cv::Mat& frame,
                                   const char* why_not_in_grey, const char* why) {
  const Instance in_grey = detect_one(models, frame, false);
  EXPECT_FALSE(in_grey.covered) << why_not_in_grey;
  const Instance in_colour = detect_one(models, frame, true);
  EXPECT_TRUE(in_colour.covered) << why;
  EXPECT_FALSE(in_colour.pickable);
}

/// A white highlight on `frame` (BGR): a soft disc towards level 245 (lighter and greyer than a
/// print, as glare is).
void add_highlight(cv::Mat& frame, cv::Point centre, int radius) {
  test_scene::add_soft_disc(frame, centre, {radius, radius}, 0.0, cv::Vec3b(245, 245, 245));
}

/// A blue-green as light as the orange in grey.
cv::Vec3b teal_like_orange() {
  const double b = 200, r = 40;
  const double g = (grey_level(kOrange) - 0.114 * b - 0.299 * r) / 0.587;
  return cv::Vec3b(static_cast<uchar>(b), static_cast<uchar>(std::lround(g)),
                   static_cast<uchar>(r));
}

/// A frame in colour holding OpenCV's box.png (a grey picture) at kPose.
cv::Mat box_frame() {
  cv::Mat frame, picture;
  cv::cvtColor(test_scene::smooth_noise_background({1000, 700}, 5), frame, cv::COLOR_GRAY2BGR);
  cv::cvtColor(test_scene::box_model().image, picture, cv::COLOR_GRAY2BGR);
  test_scene::paste(frame, picture, {kPose});
  return frame;
}

/// Where box.png's point (200, 150) lies in box_frame(): on its print, whose grey level there
/// is about 113.
cv::Point on_box_print() {
  const cv::Point2f at = test_scene::apply(
      test_scene::model_to_scene(test_scene::box_model().image.size(), kPose), {200.f, 150.f});
  return {cvRound(at.x), cvRound(at.y)};
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

  expect_covered_in_colour_only(models_, frame,
                                "in grey the card is flat on flat: nothing tells it",
                                "the card's colour is not the print's");
}

TEST_F(ColourCover, ACardOfAnotherColourTwoCellsAcrossCoversIt) {
  // A plain blue card 28 x 20 px, about two comparison cells (kCoverCell) across: on the
  // fruits' print, flat where the print has detail, too few cells for a group in grey; in
  // colour two cells side by side show a colour the print does not have there. Each place was
  // missed in colour too before such a pair counted.
  const cv::Vec3b blue(200, 80, 40);
  for (const cv::Point2f at : {cv::Point2f(60.f, 60.f), cv::Point2f(60.f, 110.f),
                               cv::Point2f(100.f, 60.f), cv::Point2f(140.f, 110.f)}) {
    SCOPED_TRACE(testing::Message() << "card at (" << at.x << ", " << at.y << ") of the picture");
    cv::Mat frame = scene();
    cv::ellipse(frame, to_scene(at, picture_.size()), {14, 10}, kPose.angle, 0, 360,
                cv::Scalar(blue[0], blue[1], blue[2]), cv::FILLED, cv::LINE_AA);
    expect_covered_in_colour_only(models_, frame, "in grey the card hides too few cells",
                                  "two cells side by side show another colour than the print's");
  }
}

TEST_F(ColourCover, AHighlightOrAColouredLightCoversNothing) {
  // A white highlight over the panel.
  cv::Mat glare = scene();
  add_highlight(glare, to_scene({380.f, 110.f}, picture_.size()), 30);
  const Instance under_glare = detect_one(models_, glare, true);
  EXPECT_FALSE(under_glare.covered) << "a highlight is not an object";
  EXPECT_TRUE(under_glare.pickable);

  // A warm light over the whole frame: red up, blue down.
  cv::Mat warm = scene();
  std::vector<cv::Mat> channels;
  cv::split(warm, channels);
  channels[0] *= 0.8;
  channels[2] *= 1.15;
  cv::merge(channels, warm);
  const Instance in_warm_light = detect_one(models_, warm, true);
  EXPECT_FALSE(in_warm_light.covered) << "the light's colour is the same all over the instance";
  EXPECT_TRUE(in_warm_light.pickable);
}

// A model picture without colour tells nothing of the product's colours, but a highlight takes
// the light's colour, near white: a plain disc of clear colour, lighter than the print under it
// (which in grey cannot be told from glare washing the print out), lies on the box.
TEST(ColourCoverOnAGreyPicture, APlainDiscOfClearColourLighterThanThePrintCoversIt) {
  const cv::Vec3b light_green(120, 240, 120); // grey level about 191
  ASSERT_GT(grey_level(light_green), 113 + 30 + 30)
      << "the disc must be lighter than glare's limit";
  cv::Mat frame = box_frame();
  // Its rim fades into the print as a highlight's does (a sharp rim would tell a lid in grey
  // too: Occlusion.ALightPlainLidWithEdgesOfItsOwnCoversIt).
  test_scene::add_soft_disc(frame, on_box_print(), {28, 28}, 0.0, light_green);

  expect_covered_in_colour_only({test_scene::box_model()}, frame,
                                "in grey a lighter plain patch may be glare: nothing tells it",
                                "glare is not green");
}

TEST(ColourCoverOnAGreyPicture, AHighlightCoversNothing) {
  cv::Mat frame = box_frame();
  add_highlight(frame, on_box_print(), 28);
  const Instance under_glare = detect_one({test_scene::box_model()}, frame, true);
  EXPECT_FALSE(under_glare.covered) << "a highlight is not an object";
  EXPECT_TRUE(under_glare.pickable);
}
