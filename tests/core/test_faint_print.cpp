// SPDX-License-Identifier: LGPL-2.1-or-later
// Faint print (a white glossy carton with pale print): the model picture is searched at a
// lowered SIFT threshold, the frames searched for it keep their weaker extrema, and the
// threshold travels with a model file's feature cache.
#include "../support/box.hpp"
#include "../support/folder_test.hpp"
#include "common/scene.hpp"

#include <pickdetect/pickdetect.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <fstream>
#include <iterator>
#include <string>
#include <vector>

using namespace pickdetect;
using pickdetect::test_scene::box_model;
using pickdetect::test_scene::faint_box_model;
using pickdetect::test_scene::Pose;

namespace {

const std::vector<Pose> kPoses = {
    {{170.f, 150.f}, 20.0, 0.6}, {{460.f, 160.f}, 110.0, 0.6}, {{320.f, 350.f}, 200.0, 0.6}};

/// Three washed-out boxes on a dark tote floor, a little blurred, with sensor noise.
cv::Mat faint_scene(const Model& model) {
  cv::Mat scene = test_scene::plain_background(cv::Size(640, 480), 70, 5);
  test_scene::paste(scene, model.image, kPoses);
  cv::GaussianBlur(scene, scene, cv::Size(0, 0), 0.8);
  cv::Mat noise(scene.size(), CV_16SC1);
  cv::RNG rng(11);
  rng.fill(noise, cv::RNG::NORMAL, 0, 2);
  cv::Mat noisy;
  scene.convertTo(noisy, CV_16SC1);
  noisy += noise;
  noisy.convertTo(scene, CV_8UC1);
  return scene;
}

int found_at_poses(const Detection& d, double tolerance_px) {
  int found = 0;
  for (const Pose& pose : kPoses)
    for (const Instance& inst : d.instances)
      if (cv::norm(inst.center - pose.center) < tolerance_px) {
        ++found;
        break;
      }
  return found;
}

class FaintPrintFiles : public test_scene::FolderTest {
protected:
  FaintPrintFiles() : FolderTest("pickdetect-faint-") {}
};

} // namespace

TEST(FaintPrint, APictureWithLittlePrintIsSearchedAtALowerThreshold) {
  EXPECT_DOUBLE_EQ(box_model().contrast_threshold, kSiftContrastThreshold)
      << "a picture with plenty of print keeps SIFT's usual threshold";
  const Model faint = faint_box_model();
  EXPECT_LT(faint.contrast_threshold, kSiftContrastThreshold);
  EXPECT_GE(faint.contrast_threshold, kLeastModelContrastThreshold);
  const Features usual =
      extract_features(faint.image, faint.mask, FeatureKind::Sift, kSiftContrastThreshold);
  ASSERT_LT(static_cast<int>(usual.keypoints.size()), kModelKeypointTarget)
      << "the premise: the washed-out picture yields few keypoints at the usual threshold";
  const Features own =
      extract_features(faint.image, faint.mask, FeatureKind::Sift, faint.contrast_threshold);
  EXPECT_GT(own.keypoints.size(), 2 * usual.keypoints.size())
      << "the lowered threshold finds the pale print's weaker extrema";
  EXPECT_GE(faint.sift.keypoints.size(), own.keypoints.size())
      << "the model's features are the picture's at that threshold, and its tilted views'";
}

TEST(FaintPrint, FramesSearchedForAFaintModelKeepTheirWeakerExtrema) {
  const cv::Mat scene = faint_scene(faint_box_model());
  const Settings automatic;
  const double usual = frame_contrast_threshold(scene, automatic);
  EXPECT_DOUBLE_EQ(Detector({box_model()}).frame_contrast_threshold(scene, automatic), usual);
  EXPECT_DOUBLE_EQ(
      Detector({box_model(), faint_box_model()}).frame_contrast_threshold(scene, automatic),
      usual * kFaintPrintFrameShare)
      << "one faint model among others lowers the frames' threshold";
  Settings fixed;
  fixed.contrast_threshold = 0.03;
  EXPECT_DOUBLE_EQ(Detector({faint_box_model()}).frame_contrast_threshold(scene, fixed), 0.03)
      << "a threshold set by hand is kept";
  EXPECT_GE(frame_contrast_threshold(scene, automatic, 0.01),
            kSiftContrastThreshold * kLeastFrameContrastShare * (1 - 1e-12))
      << "never below the sensor's noise";
}

TEST(FaintPrint, WashedOutCartonsAreFound) {
  const Model faint = faint_box_model();
  const cv::Mat scene = faint_scene(faint);
  // Without the step: the picture's features and the frame's at SIFT's usual threshold.
  Model usual = faint;
  usual.contrast_threshold = kSiftContrastThreshold;
  usual.max_tilt_deg = 0.0;
  usual.sift = extract_features(usual.image, usual.mask, FeatureKind::Sift, kSiftContrastThreshold);
  Settings at_usual;
  at_usual.contrast_threshold = kSiftContrastThreshold;
  EXPECT_LT(found_at_poses(Detector({usual}).detect(scene, at_usual), 3.0), 3)
      << "the premise: at the usual threshold some of the washed-out boxes are missed";

  const Detection d = Detector({faint}).detect(scene);
  EXPECT_EQ(found_at_poses(d, 3.0), 3) << "every washed-out box is found, centre within 3 px";
  EXPECT_EQ(d.instances.size(), kPoses.size()) << "and nothing else";
}

TEST_F(FaintPrintFiles, AModelFilesCacheKeepsTheThreshold) {
  const Model faint = faint_box_model();
  ASSERT_TRUE(cv::imwrite(path("faint.png"), faint.image));
  Model on_disk = faint;
  on_disk.image_path = path("faint.png");
  save_model(on_disk, path("faint.yml"));
  const Model back = load_model(path("faint.yml"));
  EXPECT_DOUBLE_EQ(back.contrast_threshold, faint.contrast_threshold);
  EXPECT_EQ(back.sift.keypoints.size(), faint.sift.keypoints.size());

  // A cache from before the key existed was found at the usual threshold.
  std::ifstream in(path("faint.yml"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string key = "contrast_threshold: ";
  const size_t at = text.find(key);
  ASSERT_NE(at, std::string::npos);
  const size_t end = text.find('\n', at);
  write("old.yml", text.substr(0, at) + text.substr(end + 1));
  EXPECT_DOUBLE_EQ(load_model(path("old.yml")).contrast_threshold, kSiftContrastThreshold);

  for (const std::string& bad : {std::string("zero"), std::string("0"), std::string("2")}) {
    write("bad.yml", text.substr(0, at) + key + bad + text.substr(end));
    try {
      load_model(path("bad.yml"));
      ADD_FAILURE() << "contrast_threshold " << bad << " should be refused";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("contrast_threshold"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad.yml"), std::string::npos) << e.what();
    }
  }
}
