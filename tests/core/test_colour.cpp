// SPDX-License-Identifier: LGPL-2.1-or-later
// Look-alike products that differ only in colour, told apart by the frame's colour. Scenes
// built from a crop of OpenCV's fruits.jpg and its recoloured editions.
#include "../../src/colour_decision.hpp"
#include "../support/colour_print.hpp"
#include "../support/folder_test.hpp"
#include "common/scene.hpp"

#include <pickdetect/pickdetect.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

using namespace pickdetect;
using pickdetect::test_scene::Pose;

namespace {

const std::string kData = PICKDETECT_TEST_DATA;

/// The picture with its hue turned by `degrees` (one design, another colour).
cv::Mat turn_hue(const cv::Mat& bgr, int degrees) {
  cv::Mat hsv;
  cv::cvtColor(bgr, hsv, cv::COLOR_BGR2HSV);
  for (auto it = hsv.begin<cv::Vec3b>(); it != hsv.end<cv::Vec3b>(); ++it)
    (*it)[0] = static_cast<uchar>(((*it)[0] + degrees / 2) % 180);
  cv::Mat out;
  cv::cvtColor(hsv, out, cv::COLOR_HSV2BGR);
  return out;
}

/// Two editions of one design in a folder: "warm" (a 300x220 crop of fruits.jpg) and "cold"
/// (its red and blue channels swapped), and "green" (its hue turned by 120 degrees, no model).
class Colour : public test_scene::FolderTest {
protected:
  Colour() : FolderTest("pickdetect-colour-") {}
  void SetUp() override {
    FolderTest::SetUp();
    warm_ = test_scene::fruits_print(kData);
    ASSERT_FALSE(warm_.empty());
    cv::cvtColor(warm_, cold_, cv::COLOR_BGR2RGB);
    green_ = turn_hue(warm_, 120);
    cv::imwrite(path("warm.png"), warm_);
    cv::imwrite(path("cold.png"), cold_);
  }
  Detector detector() const {
    return Detector(load_models(path("warm.png") + "," + path("cold.png")));
  }
  cv::Mat warm_, cold_, green_;
};

/// A colour scene: smooth grey noise, the pictures pasted at their poses.
cv::Mat scene_of(const std::vector<std::pair<cv::Mat, Pose>>& objects,
                 cv::Size size = {1000, 600}) {
  cv::Mat grey = test_scene::smooth_noise_background(size, 3), scene;
  cv::cvtColor(grey, scene, cv::COLOR_GRAY2BGR);
  for (const auto& [picture, pose] : objects)
    test_scene::paste(scene, picture, {pose});
  return scene;
}

cv::Mat grey_of(const cv::Mat& bgr) {
  cv::Mat grey;
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  return grey;
}

double distance(cv::Point2f a, cv::Point2f b) {
  return std::hypot(a.x - b.x, a.y - b.y);
}

std::string describe(const std::vector<Instance>& found) {
  std::ostringstream out;
  for (const Instance& i : found)
    out << " " << i.model_name << " at (" << i.center.x << ", " << i.center.y << "), " << i.matches
        << " matches, " << i.distinct_matches << " distinct;";
  return found.empty() ? " none" : out.str();
}

/// The instance nearest to `at` within 5 pixels, or nullptr.
const Instance* at(const std::vector<Instance>& found, cv::Point2f where) {
  for (const Instance& i : found)
    if (distance(i.center, where) < 5.0)
      return &i;
  return nullptr;
}

/// The picture with the same grey (luma) and other colours: its two chroma planes swapped.
cv::Mat swap_chroma(const cv::Mat& bgr) {
  cv::Mat ycrcb, planes[3], out;
  cv::cvtColor(bgr, ycrcb, cv::COLOR_BGR2YCrCb);
  cv::split(ycrcb, planes);
  std::swap(planes[1], planes[2]);
  cv::merge(planes, 3, ycrcb);
  cv::cvtColor(ycrcb, out, cv::COLOR_YCrCb2BGR);
  return out;
}

const Pose kLeft{{270, 300}, 20.0, 1.0};
const Pose kRight{{720, 290}, 250.0, 0.9};

} // namespace

TEST_F(Colour, ModelsKeepTheirPicturesColour) {
  const Detector d = detector();
  ASSERT_EQ(d.models().size(), 2u);
  EXPECT_EQ(d.models()[0].colour.type(), CV_8UC3);
  EXPECT_EQ(d.models()[0].colour.size(), warm_.size());
  EXPECT_TRUE(d.has_colour_models());
  // A grey picture, also one stored as colour, has none.
  cv::Mat grey3;
  cv::cvtColor(grey_of(warm_), grey3, cv::COLOR_GRAY2BGR);
  cv::imwrite(path("grey3.png"), grey3);
  EXPECT_TRUE(load_model(path("grey3.png")).colour.empty());
  EXPECT_TRUE(load_model(kData + "/box.png").colour.empty());
}

TEST_F(Colour, EachEditionIsNamedByTheFramesColour) {
  const cv::Mat scene = scene_of({{warm_, kLeft}, {cold_, kRight}});
  const Detector d = detector();
  // The light's gain does not change the colour; a mild cast (blue / 1.15, red * 1.15) does
  // not hide it.
  const std::vector<std::pair<double, double>> lights = {{1.0, 1.0}, {0.6, 1.0}, {1.0, 1.15}};
  for (const auto& [gain, cast] : lights) {
    cv::Mat lit;
    cv::multiply(scene, cv::Scalar(gain / cast, gain, gain * cast), lit);
    const std::vector<Instance> found = d.detect(grey_of(lit), lit).instances;
    const Instance* left = at(found, kLeft.center);
    const Instance* right = at(found, kRight.center);
    const std::string light = "gain " + std::to_string(gain) + ", cast " + std::to_string(cast);
    ASSERT_TRUE(left && right) << light << ":" << describe(found);
    EXPECT_EQ(found.size(), 2u) << light << ":" << describe(found);
    EXPECT_EQ(left->model_name, "warm") << light << ":" << describe(found);
    EXPECT_EQ(right->model_name, "cold") << light << ":" << describe(found);
  }
}

/// The same instances: models, centres and matches.
void expect_same(const std::vector<Instance>& a, const std::vector<Instance>& b) {
  ASSERT_EQ(a.size(), b.size()) << describe(a) << " against" << describe(b);
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].model, b[i].model);
    EXPECT_EQ(a[i].center, b[i].center);
    EXPECT_EQ(a[i].matches, b[i].matches);
  }
}

TEST_F(Colour, GreyFramesOrGreyModelsKeepTodaysBehaviour) {
  // Swapping red and blue changes the grey picture too, so that in grey most matches are
  // distinct ones (drop_look_alikes): the colder edition, more contrasted in grey, is named at
  // both places, one of them wrong. That was the result before colour was used, and it stays
  // with grey frames or grey models.
  const cv::Mat scene = scene_of({{warm_, kLeft}, {cold_, kRight}});
  const Detector d = detector();
  const std::vector<Instance> grey = d.detect(grey_of(scene)).instances;
  const Instance* left = at(grey, kLeft.center);
  const Instance* right = at(grey, kRight.center);
  ASSERT_TRUE(left && right) << describe(grey);
  EXPECT_EQ(left->model_name, "cold") << describe(grey);
  EXPECT_EQ(right->model_name, "cold") << describe(grey);
  expect_same(d.detect(grey_of(scene), cv::Mat()).instances, grey);
  // Models without colour, a colour frame: the same.
  std::vector<Model> grey_models = d.models();
  for (Model& m : grey_models)
    m.colour.release();
  const Detector g(grey_models);
  EXPECT_FALSE(g.has_colour_models());
  expect_same(g.detect(grey_of(scene), scene).instances, grey);
}

TEST_F(Colour, EditionsOfOneGreyPictureAreToldApartByColourAlone) {
  // Two editions whose grey pictures are the same: every feature fits both models alike. In
  // grey, the instances of both models in one place compete for the same keypoints and the
  // first model's wins (explain_scene), its few distinct matches (chance) enough alone: the
  // first edition is named at both places. In colour each is named right.
  const cv::Mat twin = swap_chroma(warm_);
  cv::imwrite(path("twin.png"), twin);
  const Detector d(load_models(path("warm.png") + "," + path("twin.png")));
  const cv::Mat scene = scene_of({{warm_, kLeft}, {twin, kRight}});
  const std::vector<Instance> grey = d.detect(grey_of(scene)).instances;
  ASSERT_TRUE(at(grey, kLeft.center) && at(grey, kRight.center)) << describe(grey);
  EXPECT_EQ(at(grey, kLeft.center)->model_name, "warm") << describe(grey);
  EXPECT_EQ(at(grey, kRight.center)->model_name, "warm") << describe(grey);
  const std::vector<Instance> found = d.detect(grey_of(scene), scene).instances;
  const Instance* left = at(found, kLeft.center);
  const Instance* right = at(found, kRight.center);
  ASSERT_TRUE(left && right) << describe(found);
  EXPECT_EQ(found.size(), 2u) << describe(found);
  EXPECT_EQ(left->model_name, "warm") << describe(found);
  EXPECT_EQ(right->model_name, "twin") << describe(found);
}

TEST_F(Colour, AColourThatFitsNoModelIsNotForced) {
  const cv::Mat scene = scene_of({{green_, kLeft}, {warm_, kRight}});
  const std::vector<Instance> found = detector().detect(grey_of(scene), scene).instances;
  EXPECT_EQ(at(found, kLeft.center), nullptr) << describe(found);
  const Instance* right = at(found, kRight.center);
  ASSERT_NE(right, nullptr) << describe(found);
  EXPECT_EQ(right->model_name, "warm");
}

TEST_F(Colour, MisfitIsSmallForTheRightEditionOnly) {
  const cv::Mat scene = scene_of({{warm_, kLeft}});
  const Detector d = detector();
  Instance inst;
  inst.scale = 1.0;
  const cv::Matx23d m = test_scene::model_to_scene(warm_.size(), kLeft);
  inst.homography = cv::Matx33d(m(0, 0), m(0, 1), m(0, 2), m(1, 0), m(1, 1), m(1, 2), 0, 0, 1);
  const double right = detail::colour_misfit(inst, d.models()[0], scene);
  const double wrong = detail::colour_misfit(inst, d.models()[1], scene);
  EXPECT_LT(right, 0.05);
  EXPECT_GT(wrong, 3 * right + 0.05) << "right " << right;
  // No colour: no misfit.
  EXPECT_TRUE(std::isnan(detail::colour_misfit(inst, d.models()[0], cv::Mat())));
}
