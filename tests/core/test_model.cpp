// SPDX-License-Identifier: LGPL-2.1-or-later
// Models: pictures, alpha outlines, default principal points, model files and their errors.
#include "../support/folder_test.hpp"

#include <pickdetect/pickdetect.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <fstream>

using namespace pickdetect;
namespace fs = std::filesystem;

namespace {

const std::string kData = PICKDETECT_TEST_DATA;

/// A fresh folder per test, removed afterwards.
class ModelFiles : public test_scene::FolderTest {
protected:
  ModelFiles() : FolderTest("pickdetect-model-") {}
  /// Expects load_model to throw an Error whose message contains every fragment.
  static void expect_refused(const std::string& file,
                             std::initializer_list<std::string> fragments) {
    try {
      load_model(file);
      ADD_FAILURE() << "loading " << file << " should have failed";
    } catch (const Error& e) {
      for (const std::string& f : fragments)
        EXPECT_NE(std::string(e.what()).find(f), std::string::npos)
            << "message '" << e.what() << "' should mention '" << f << "'";
    }
  }
};

} // namespace

TEST(Model, PlainPictureGetsTheCentreAndCornersAndItsRectangle) {
  const Model m = load_model(kData + "/box.png");
  EXPECT_EQ(m.name, "box");
  ASSERT_EQ(m.principal_points.size(), 5u);
  EXPECT_EQ(m.principal_points[0], cv::Point2f(162.f, 111.5f));
  EXPECT_EQ(m.principal_points[1], cv::Point2f(0.f, 0.f));
  EXPECT_EQ(m.principal_points[3], cv::Point2f(324.f, 223.f));
  ASSERT_EQ(m.outline.size(), 4u);
  EXPECT_EQ(m.outline[2], cv::Point2f(324.f, 223.f));
  EXPECT_GE(static_cast<int>(m.sift.keypoints.size()), kMinModelKeypoints);
  EXPECT_EQ(m.sift.descriptors.rows, static_cast<int>(m.sift.keypoints.size()));
}

TEST_F(ModelFiles, AlphaMarksTheObjectAndGivesItsOutline) {
  // The box picture inside a larger transparent canvas, as a disc-cornered shape.
  const cv::Mat box = cv::imread(kData + "/box.png", cv::IMREAD_COLOR);
  cv::Mat rgba(box.rows + 40, box.cols + 60, CV_8UC4, cv::Scalar(0, 0, 0, 0));
  cv::Mat inner;
  cv::cvtColor(box, inner, cv::COLOR_BGR2BGRA);
  inner.copyTo(rgba(cv::Rect(30, 20, box.cols, box.rows)));
  cv::imwrite(path("boxed.png"), rgba);

  const Model m = load_model(path("boxed.png"));
  EXPECT_EQ(m.principal_points[0], cv::Point2f(30.f + box.cols / 2.f, 20.f + box.rows / 2.f));
  EXPECT_EQ(m.principal_points[1], cv::Point2f(30.f, 20.f));
  const cv::Rect outline_box = cv::boundingRect(m.outline);
  EXPECT_NEAR(outline_box.x, 30, 1);
  EXPECT_NEAR(outline_box.y, 20, 1);
  EXPECT_NEAR(outline_box.width, box.cols, 2);
  EXPECT_EQ(cv::countNonZero(m.mask), box.cols * box.rows);
  for (const cv::KeyPoint& k : m.sift.keypoints)
    EXPECT_TRUE(cv::Rect(28, 18, box.cols + 4, box.rows + 4).contains(k.pt))
        << "keypoint outside the object at (" << k.pt.x << ", " << k.pt.y << ")";
}

TEST_F(ModelFiles, TheColourOfTransparentPixelsChangesNoFeature) {
  // The same object on canvases whose transparent pixels are black, light and white: that
  // colour is no part of the object, so the features (keypoints on the outline among them, and
  // the descriptors beside it) must not depend on it. Light transparent pixels around a dark
  // print made an edge whose keypoints agreed with a belt's light border (docs/tracking.md).
  const cv::Mat box = cv::imread(kData + "/box.png", cv::IMREAD_COLOR);
  std::vector<Model> models;
  for (const cv::Scalar& fill :
       {cv::Scalar(0, 0, 0, 0), cv::Scalar(151, 200, 180, 0), cv::Scalar(255, 255, 255, 0)}) {
    cv::Mat rgba(box.rows + 40, box.cols + 60, CV_8UC4, fill);
    cv::Mat inner;
    cv::cvtColor(box, inner, cv::COLOR_BGR2BGRA);
    inner.copyTo(rgba(cv::Rect(30, 20, box.cols, box.rows)));
    const std::string file = path("boxed" + std::to_string(models.size()) + ".png");
    cv::imwrite(file, rgba);
    models.push_back(load_model(file));
  }
  for (size_t i = 1; i < models.size(); ++i) {
    for (const auto& [a, b] :
         {std::pair(&models[0].sift, &models[i].sift), std::pair(&models[0].orb, &models[i].orb)}) {
      ASSERT_EQ(a->keypoints.size(), b->keypoints.size()) << "fill " << i;
      for (size_t k = 0; k < a->keypoints.size(); ++k)
        EXPECT_EQ(a->keypoints[k].pt, b->keypoints[k].pt) << "fill " << i << ", keypoint " << k;
      EXPECT_EQ(cv::norm(a->descriptors, b->descriptors, cv::NORM_INF), 0.0) << "fill " << i;
    }
  }
}

TEST_F(ModelFiles, TexturelessPictureIsRefusedWithTheCount) {
  cv::imwrite(path("flat.png"), cv::Mat(200, 300, CV_8UC1, cv::Scalar(90)));
  expect_refused(path("flat.png"), {path("flat.png"), "yields only 0", "keypoints"});
}

TEST_F(ModelFiles, ModelFileRoundTripsWithCachedFeatures) {
  Model m = load_model(kData + "/box.png");
  m.name = "cereal";
  m.principal_points = {{162.f, 111.5f}, {40.f, 50.f}, {280.f, 170.f}};
  m.grasp_point = 2;
  save_model(m, path("cereal.yml"), true);
  const Model back = load_model(path("cereal.yml"));
  EXPECT_EQ(back.name, "cereal");
  EXPECT_EQ(back.principal_points, m.principal_points);
  EXPECT_EQ(back.outline, m.outline);
  EXPECT_EQ(back.grasp_point, 2);
  ASSERT_EQ(back.sift.keypoints.size(), m.sift.keypoints.size());
  EXPECT_EQ(cv::norm(back.sift.descriptors, m.sift.descriptors, cv::NORM_INF), 0.0);
  EXPECT_EQ(back.sift.keypoints[5].pt, m.sift.keypoints[5].pt);
}

TEST_F(ModelFiles, ModelFileWithoutCacheComputesFeatures) {
  const std::string file = write("plain.yml", "%YAML:1.0\nimage: \"" + kData + "/box.png\"\n");
  const Model m = load_model(file);
  EXPECT_EQ(m.name, "plain");
  EXPECT_EQ(m.principal_points.size(), 5u);
  EXPECT_GE(static_cast<int>(m.sift.keypoints.size()), kMinModelKeypoints);
}

TEST_F(ModelFiles, ErrorsNameTheFileAndTheReason) {
  expect_refused(path("missing.yml"), {path("missing.yml"), "No such file"});
  expect_refused(path("missing.png"), {path("missing.png"), "No such file"});
  expect_refused(write("broken.yml", "%YAML:1.0\nimage: [unclosed\n  - {\n"), {path("broken.yml")});
  expect_refused(write("noimage.yml", "%YAML:1.0\nname: x\n"), {path("noimage.yml"), "'image'"});
  expect_refused(write("gone.yml", "%YAML:1.0\nimage: nowhere.png\n"),
                 {path("gone.yml"), path("nowhere.png"), "No such file"});
  expect_refused(write("notpic.png", "this is not a picture"), {path("notpic.png"), "decoded"});
  expect_refused(write("outside.yml", "%YAML:1.0\nimage: \"" + kData +
                                          "/box.png\"\nprincipal_points: [[10, 10], [900, 5]]\n"),
                 {path("outside.yml"), "principal point 1", "outside"});
  expect_refused(write("flatline.yml", "%YAML:1.0\nimage: \"" + kData +
                                           "/box.png\"\noutline: [[0, 0], [10, 0], [20, 0]]\n"),
                 {path("flatline.yml"), "outline"});
  expect_refused(
      write("badgrasp.yml", "%YAML:1.0\nimage: \"" + kData + "/box.png\"\ngrasp_point: 9\n"),
      {path("badgrasp.yml"), "grasp_point"});
  expect_refused(kData, {kData, "directory"});
}

TEST_F(ModelFiles, HugePictureIsRefusedWithItsSize) {
  cv::imwrite(path("huge.png"), cv::Mat(5000, 4200, CV_8UC1, cv::Scalar(0)));
  expect_refused(path("huge.png"), {path("huge.png"), "4200x5000"});
}

// Found by fuzz-model: a cached matrix whose header claims more rows than the file holds made
// OpenCV allocate them all (16 GiB for rows: 2147483647) before it read the data.
TEST_F(ModelFiles, CachedDescriptorsWithAFalseSizeAreRefusedBeforeReading) {
  Model m = load_model(kData + "/box.png");
  save_model(m, path("cached.yml"), true);
  std::ifstream in(path("cached.yml"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string rows = "rows: " + std::to_string(m.sift.keypoints.size());
  const size_t at = text.find(rows, text.find("\ndescriptors:"));
  ASSERT_NE(at, std::string::npos) << "no '" << rows << "' in the saved descriptors";
  text.replace(at, rows.size(), "rows: 2147483647");
  expect_refused(
      write("liar.yml", text),
      {path("liar.yml"), "'descriptors'", std::to_string(m.sift.keypoints.size()) + "x128 matrix"});
}

// Only the header: the picture is refused for the size it declares, before any decoding (which
// would fail on the missing data, or take gigabytes for a real 30000 x 30000 picture).
TEST_F(ModelFiles, HugePictureIsRefusedFromItsHeaderBeforeDecoding) {
  const std::string png_header(
      "\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\0\x75\x30\0\0\x75\x30\x08\0\0\0\0", 29);
  expect_refused(write("huge-header.png", png_header), {path("huge-header.png"), "30000x30000"});
  // A JPEG with a comment segment, one fill byte, then a start of frame (SOF2) of 20000 x 30000.
  const std::string jpeg_header(
      "\xFF\xD8\xFF\xFE\0\x05hi!\xFF\xFF\xC2\0\x11\x08\x75\x30\x4E\x20\x03", 20);
  expect_refused(write("huge-header.jpg", jpeg_header), {path("huge-header.jpg"), "20000x30000"});
}

TEST_F(ModelFiles, MaxTiltChoosesTheSimulatedViewsAndTheCacheKeepsThem) {
  const std::string picture = kData + "/box.png";
  const Model plain =
      load_model(write("plain.yml", "%YAML:1.0\nimage: \"" + picture + "\"\nmax_tilt: 0\n"));
  const Model tilted = load_model(write("tilted.yml", "%YAML:1.0\nimage: \"" + picture + "\"\n"));
  EXPECT_EQ(plain.max_tilt_deg, 0.0);
  EXPECT_EQ(tilted.max_tilt_deg, kDefaultMaxTiltDeg);
  EXPECT_GT(tilted.sift.keypoints.size(), 2 * plain.sift.keypoints.size())
      << "the tilted views add features to the picture's own";
  // Written with its features and read back: the same features, not computed again.
  save_model(tilted, path("cached.yml"));
  const Model cached = load_model(path("cached.yml"));
  EXPECT_EQ(cached.max_tilt_deg, kDefaultMaxTiltDeg);
  EXPECT_EQ(cached.sift.keypoints.size(), tilted.sift.keypoints.size());
  // A cache written before max_tilt existed holds the picture's own features: the views are
  // added to it.
  cv::FileStorage old(path("old.yml"), cv::FileStorage::WRITE);
  old << "image" << picture;
  cv::write(old, "keypoints", plain.sift.keypoints);
  old << "descriptors" << plain.sift.descriptors;
  old.release();
  EXPECT_EQ(load_model(path("old.yml")).sift.keypoints.size(), tilted.sift.keypoints.size());
}

TEST_F(ModelFiles, AMaxTiltOutOfRangeIsRefusedByName) {
  expect_refused(write("m.yml", "%YAML:1.0\nimage: \"" + kData + "/box.png\"\nmax_tilt: 85\n"),
                 {"m.yml", "'max_tilt' must lie between 0 and 80"});
  expect_refused(write("n.yml", "%YAML:1.0\nimage: \"" + kData + "/box.png\"\nmax_tilt: steep\n"),
                 {"n.yml", "'max_tilt' must be a number"});
}

// A model list: commas, model sets relative to their folder; its errors say which file and why.
TEST_F(ModelFiles, ModelListReadsSetsRelativeToThemAndClassifiesItsErrors) {
  fs::copy_file(kData + "/box.png", path("crate.png"));
  const std::string set = write("set.yml", "%YAML:1.0\nmodels: [crate.png]\n");
  const std::vector<Model> models = load_models(" " + kData + "/box.png ,\t" + set);
  ASSERT_EQ(models.size(), 2u);
  EXPECT_EQ(models[0].name, "box");
  EXPECT_EQ(models[1].name, "crate");

  auto refusal = [](const std::string& list) -> Error {
    try {
      load_models(list);
    } catch (const Error& e) {
      return e;
    }
    ADD_FAILURE() << "loading '" << list << "' should have failed";
    return Error("");
  };
  const Error missing = refusal(write("missing.yml", "%YAML:1.0\nmodels: [gone.png]\n"));
  EXPECT_EQ(missing.kind(), ErrorKind::NotFound) << missing.what();
  EXPECT_EQ(missing.path(), path("gone.png"));
  const Error folder = refusal(dir_.string());
  EXPECT_EQ(folder.kind(), ErrorKind::CannotRead) << folder.what();
  const Error nested = refusal(write("nested.yml", "%YAML:1.0\nmodels: [set.yml]\n"));
  EXPECT_EQ(nested.kind(), ErrorKind::Invalid) << nested.what();
  EXPECT_NE(std::string(nested.what()).find("lists another model set"), std::string::npos);
  const Error twice = refusal(set + "," + path("crate.png"));
  EXPECT_EQ(twice.path(), "") << twice.what();
  EXPECT_NE(std::string(twice.what()).find("two models are named \"crate\""), std::string::npos);
  const Error empty = refusal(kData + "/box.png,,");
  EXPECT_EQ(empty.path(), "") << empty.what();
  EXPECT_NE(std::string(empty.what()).find("empty entry"), std::string::npos);
}
