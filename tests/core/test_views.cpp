// SPDX-License-Identifier: LGPL-2.1-or-later
// Views: a model file listing several pictures of one product; each instance names the product
// and the view it matched. Scenes built from OpenCV's box.png and a crop of graf1.png.
#include "../support/folder_test.hpp"
#include "common/scene.hpp"

#include <pickdetect/pickdetect.hpp>

#include <gtest/gtest.h>
#include <opencv2/core/persistence.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <fstream>
#include <sstream>

using namespace pickdetect;
using pickdetect::test_scene::Pose;

namespace {

const std::string kData = PICKDETECT_TEST_DATA;

/// A fresh folder per test holding the two faces of a carton: front.png (OpenCV's box.png) and
/// back.png (a 320x220 crop of graf1.png, another design), removed afterwards.
class Views : public test_scene::FolderTest {
protected:
  Views() : FolderTest("pickdetect-views-") {}
  void SetUp() override {
    FolderTest::SetUp();
    front_ = cv::imread(kData + "/box.png", cv::IMREAD_GRAYSCALE);
    const cv::Mat graf = cv::imread(kData + "/graf1.png", cv::IMREAD_GRAYSCALE);
    back_ = graf(cv::Rect(200, 150, 320, 220)).clone();
    ASSERT_FALSE(front_.empty());
    ASSERT_FALSE(back_.empty());
    cv::imwrite(path("front.png"), front_);
    cv::imwrite(path("back.png"), back_);
  }
  /// The carton's model file: two views, the back's name left to its picture's.
  std::string carton() const {
    return write("carton.yml", "%YAML:1.0\n"
                               "name: carton\n"
                               "height: 30\n"
                               "views:\n"
                               "  - name: front\n"
                               "    image: front.png\n"
                               "    grasp_point: 1\n"
                               "  - image: back.png\n"
                               "    principal_points: [[160, 110], [0, 0], [320, 220]]\n");
  }
  /// Expects load_views (and load_models) to throw an Error whose message holds each fragment.
  static void expect_refused(const std::string& file,
                             std::initializer_list<std::string> fragments) {
    for (int list = 0; list < 2; ++list) {
      try {
        if (list)
          load_models(file);
        else
          load_views(file);
        ADD_FAILURE() << "loading " << file << " should have failed";
      } catch (const Error& e) {
        for (const std::string& f : fragments)
          EXPECT_NE(std::string(e.what()).find(f), std::string::npos)
              << "message '" << e.what() << "' should mention '" << f << "'";
      }
    }
  }
  cv::Mat front_, back_;
};

double distance(cv::Point2f a, cv::Point2f b) {
  return std::hypot(a.x - b.x, a.y - b.y);
}

std::string describe(const std::vector<Instance>& found) {
  std::ostringstream out;
  for (const Instance& i : found)
    out << " " << i.model_name << "/" << i.view << " at (" << i.center.x << ", " << i.center.y
        << "), " << i.matches << " matches;";
  return found.empty() ? " none" : out.str();
}

} // namespace

TEST_F(Views, AModelFileListsTheViewsOfOneProduct) {
  const std::vector<Model> views = load_views(carton());
  ASSERT_EQ(views.size(), 2u);
  EXPECT_EQ(views[0].name, "carton");
  EXPECT_EQ(views[1].name, "carton");
  EXPECT_EQ(views[0].view, "front");
  EXPECT_EQ(views[1].view, "back"); // the picture's file name
  EXPECT_EQ(views[0].grasp_point, 1);
  EXPECT_EQ(views[0].principal_points.size(), 5u); // the default: centre and corners
  EXPECT_EQ(views[1].principal_points.size(), 3u);
  EXPECT_EQ(views[1].principal_points[0], cv::Point2f(160, 110));
  EXPECT_EQ(views[0].image.size(), front_.size());
  EXPECT_EQ(views[1].image.size(), back_.size());
  EXPECT_DOUBLE_EQ(views[1].height_mm, 30.0); // the product's, for every view
  // A picture, or a model file of one picture, is one model with no view.
  const std::vector<Model> plain = load_views(path("front.png"));
  ASSERT_EQ(plain.size(), 1u);
  EXPECT_EQ(plain[0].name, "front");
  EXPECT_EQ(plain[0].view, "");
  // load_model takes one model only.
  EXPECT_THROW(load_model(path("carton.yml")), Error);
}

TEST_F(Views, BothFacesInOneSceneAreFoundWithTheirView) {
  cv::Mat scene = test_scene::smooth_noise_background({1100, 700}, 5);
  const Pose front_pose{{300, 330}, 25.0, 0.9};
  const Pose back_pose{{780, 360}, 300.0, 1.0};
  test_scene::paste(scene, front_, {front_pose});
  test_scene::paste(scene, back_, {back_pose});
  // The carton and another product (OpenCV's box.png again would be the same as the front).
  const Detector detector(load_models(carton()));
  const std::vector<Instance> found = detector.detect(scene).instances;
  ASSERT_EQ(found.size(), 2u) << describe(found);
  const Instance& a = distance(found[0].center, front_pose.center) < 20 ? found[0] : found[1];
  const Instance& b = &a == &found[0] ? found[1] : found[0];
  EXPECT_LT(distance(a.center, front_pose.center), 3.0) << describe(found);
  EXPECT_LT(distance(b.center, back_pose.center), 3.0) << describe(found);
  EXPECT_EQ(a.model_name, "carton");
  EXPECT_EQ(a.view, "front") << describe(found);
  EXPECT_EQ(b.model_name, "carton");
  EXPECT_EQ(b.view, "back") << describe(found);
  // The front's grasp point is its own (index 1, the top-left corner).
  const cv::Matx23d m = test_scene::model_to_scene(front_.size(), front_pose);
  EXPECT_LT(distance(a.grasp, test_scene::apply(m, {0, 0})), 4.0);
}

TEST_F(Views, OneFaceSeenIsOneInstanceOfItsView) {
  cv::Mat scene = test_scene::smooth_noise_background({800, 600}, 9);
  const Pose pose{{400, 300}, 140.0, 1.1};
  test_scene::paste(scene, back_, {pose});
  const Detector detector(load_models(carton()));
  const std::vector<Instance> found = detector.detect(scene).instances;
  ASSERT_EQ(found.size(), 1u) << describe(found);
  EXPECT_EQ(found[0].view, "back");
  EXPECT_LT(distance(found[0].center, pose.center), 3.0) << describe(found);
}

TEST_F(Views, SavedViewsLoadBackWithTheirCachedFeatures) {
  const std::vector<Model> views = load_views(carton());
  save_views(views, path("saved.yml"));
  // The cache is written per view.
  cv::FileStorage stored(path("saved.yml"), cv::FileStorage::READ);
  ASSERT_TRUE(stored.isOpened());
  ASSERT_EQ(stored["views"].size(), 2u);
  EXPECT_EQ(static_cast<std::string>(stored["name"]), "carton");
  EXPECT_EQ(static_cast<std::string>(stored["views"][1]["name"]), "back");
  EXPECT_EQ(stored["views"][1]["keypoints"].size(), views[1].sift.keypoints.size());
  stored.release();

  const std::vector<Model> back = load_views(path("saved.yml"));
  ASSERT_EQ(back.size(), 2u);
  for (size_t v = 0; v < 2; ++v) {
    EXPECT_EQ(back[v].name, "carton");
    EXPECT_EQ(back[v].view, views[v].view);
    EXPECT_EQ(back[v].image_path, views[v].image_path);
    EXPECT_EQ(back[v].principal_points, views[v].principal_points);
    EXPECT_EQ(back[v].outline, views[v].outline);
    EXPECT_EQ(back[v].grasp_point, views[v].grasp_point);
    EXPECT_DOUBLE_EQ(back[v].height_mm, 30.0);
    ASSERT_EQ(back[v].sift.keypoints.size(), views[v].sift.keypoints.size());
    EXPECT_EQ(cv::norm(back[v].sift.descriptors, views[v].sift.descriptors, cv::NORM_INF), 0.0);
    EXPECT_EQ(back[v].orb.keypoints.size(), views[v].orb.keypoints.size());
  }
  // The features come from the cache: a cache that disagrees is refused.
  std::ifstream in(path("saved.yml"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t at = text.find("descriptors: !!opencv-matrix", text.find("name: back"));
  ASSERT_NE(at, std::string::npos);
  const size_t rows = text.find("rows: ", at);
  text.replace(rows, text.find('\n', rows) - rows, "rows: 3");
  expect_refused(write("broken.yml", text), {"broken.yml", "views[1] ('back')", "descriptors"});
  // Views of two products are not one model file.
  std::vector<Model> mixed = views;
  mixed[1].name = "other";
  EXPECT_THROW(save_views(mixed, path("mixed.yml")), Error);
  EXPECT_THROW(save_views({}, path("none.yml")), Error);
}

TEST_F(Views, BadViewsAreRefusedNamingTheFileAndTheView) {
  expect_refused(write("empty.yml", "%YAML:1.0\nname: carton\nviews: []\n"),
                 {"empty.yml", "'views' must be a non-empty list"});
  expect_refused(write("noimage.yml", "%YAML:1.0\nviews:\n  - image: front.png\n  - name: side\n"),
                 {"noimage.yml", "views[1] ('side')", "'image'"});
  expect_refused(write("missing.yml", "%YAML:1.0\nviews:\n  - image: front.png\n"
                                      "  - name: side\n    image: nowhere.png\n"),
                 {"missing.yml", "views[1] ('side')", "nowhere.png"});
  expect_refused(write("outside.yml", "%YAML:1.0\nviews:\n  - image: front.png\n"
                                      "  - image: back.png\n"
                                      "    principal_points: [[160, 110], [400, 10]]\n"),
                 {"outside.yml", "views[1]", "principal point 1", "outside the 320x220"});
  expect_refused(write("twice.yml", "%YAML:1.0\nviews:\n  - image: front.png\n"
                                    "  - name: front\n    image: back.png\n"),
                 {"twice.yml", "views[0] and views[1] are both named 'front'"});
  expect_refused(write("both.yml", "%YAML:1.0\nimage: front.png\nviews:\n  - image: back.png\n"),
                 {"both.yml", "not both"});
}

TEST_F(Views, AModelListKeepsTheViewsOfAProductAndRefusesTwoProductsOfOneName) {
  const std::vector<Model> models = load_models(carton() + "," + kData + "/box.png");
  ASSERT_EQ(models.size(), 3u);
  EXPECT_EQ(models[0].view, "front");
  EXPECT_EQ(models[1].view, "back");
  EXPECT_EQ(models[2].name, "box");
  // Another file naming its product "carton" is refused, as is the same file twice.
  const std::string other = write("other.yml", "%YAML:1.0\nname: carton\nimage: back.png\n");
  EXPECT_THROW(load_models(carton() + "," + other), Error);
  EXPECT_THROW(load_models(carton() + "," + carton()), Error);
}
