// SPDX-License-Identifier: LGPL-2.1-or-later
// Guided matching: a face of faint print of which only two matches pass the ratio test (glare, a
// steep tilt: the rest come out as near another part of the picture as their own) is completed
// from the keypoints its pose predicts.
#include "../support/box.hpp"
#include "../support/model_keypoints.hpp"

#include <pickdetect/pickdetect.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

using namespace pickdetect;
using pickdetect::test_scene::box_model;
using pickdetect::test_scene::faint_box_model;
using pickdetect::test_scene::own_keypoints;
using pickdetect::test_scene::strongest_own_keypoint;

namespace {

/// The face: turned 30 degrees, scaled by 0.7 and foreshortened to 0.8 of its height (a face
/// tilted about 37 degrees off the picture plane), its centre at (320, 240).
constexpr double kTurnDeg = 30.0, kScale = 0.7, kSqueeze = 0.8;
const cv::Point2f kAt(320.f, 240.f);

cv::Matx22d face_map() {
  const double r = kTurnDeg * CV_PI / 180.0;
  return cv::Matx22d(std::cos(r), -std::sin(r), std::sin(r), std::cos(r)) *
         cv::Matx22d(kScale, 0.0, 0.0, kScale * kSqueeze);
}

/// Where the face centred at `at` puts model point `p`.
cv::Point2f on_face(const Model& model, cv::Point2f p, cv::Point2f at = kAt) {
  const cv::Point2f c = model.principal_points[0];
  const cv::Vec2d q = face_map() * cv::Vec2d(p.x - c.x, p.y - c.y);
  return at + cv::Point2f(static_cast<float>(q[0]), static_cast<float>(q[1]));
}

/// The strongest of the picture's own keypoints in each cell of a 4 x 3 grid.
std::vector<int> grid_keypoints(const Model& model) {
  const size_t own = own_keypoints(model);
  std::vector<int> chosen;
  for (int row = 0; row < 3; ++row)
    for (int column = 0; column < 4; ++column) {
      const float x0 = model.image.cols * column / 4.f, x1 = model.image.cols * (column + 1) / 4.f;
      const float y0 = model.image.rows * row / 3.f, y1 = model.image.rows * (row + 1) / 3.f;
      const int best = strongest_own_keypoint(model, own, [&](int, const cv::KeyPoint& k) {
        return k.pt.x >= x0 && k.pt.x < x1 && k.pt.y >= y0 && k.pt.y < y1;
      });
      if (best >= 0)
        chosen.push_back(best);
    }
  return chosen;
}

/// The frame's keypoints: model keypoints `chosen` placed on the face centred at `at`. Those in
/// `exact` keep their own descriptors (they pass the ratio test); the others' descriptors lie
/// halfway between their own and that of the nearest model keypoint elsewhere on the picture,
/// as far from one as from the other (the ratio test rejects them, as it rejects a washed-out
/// carton's).
Features placed_keypoints(const Model& model, const std::vector<int>& chosen,
                          const std::vector<int>& exact, cv::Point2f at) {
  Features scene;
  for (int i : chosen) {
    const bool is_exact = std::find(exact.begin(), exact.end(), i) != exact.end();
    const cv::KeyPoint& km = model.sift.keypoints[static_cast<size_t>(i)];
    cv::Mat descriptor = model.sift.descriptors.row(i).clone();
    if (!is_exact) {
      int rival = -1;
      double nearest = 0.0;
      for (int j = 0; j < model.sift.descriptors.rows; ++j) {
        if (cv::norm(model.sift.keypoints[static_cast<size_t>(j)].pt - km.pt) < 30.0)
          continue;
        const double d = cv::norm(model.sift.descriptors.row(j), model.sift.descriptors.row(i));
        if (rival < 0 || d < nearest) {
          rival = j;
          nearest = d;
        }
      }
      descriptor = 0.5 * (descriptor + model.sift.descriptors.row(rival));
    }
    cv::KeyPoint ks = km;
    ks.pt = on_face(model, km.pt, at);
    ks.angle = std::fmod(km.angle + static_cast<float>(kTurnDeg), 360.f);
    ks.size = km.size * static_cast<float>(kScale);
    scene.keypoints.push_back(ks);
    scene.descriptors.push_back(descriptor);
  }
  return scene;
}

/// The `count` keypoints of `chosen` nearest the picture's middle row (the two nearest: their
/// votes for the centre agree within 3 px).
std::vector<int> nearest_middle_row(const Model& model, std::vector<int> chosen, size_t count) {
  const cv::Point2f c = model.principal_points[0];
  std::sort(chosen.begin(), chosen.end(), [&](int a, int b) {
    return std::abs(model.sift.keypoints[a].pt.y - c.y) <
           std::abs(model.sift.keypoints[b].pt.y - c.y);
  });
  chosen.resize(std::min(count, chosen.size()));
  return chosen;
}

/// The frame's keypoints of the grid (grid_keypoints) on the face centred at `at`: the
/// `exact_count` nearest the middle row (nearest_middle_row) keep their own descriptors. With
/// `only_exact` the others are left out.
Features face_keypoints(const Model& model, bool only_exact, cv::Point2f at = kAt,
                        size_t exact_count = 2) {
  std::vector<int> chosen = grid_keypoints(model);
  const std::vector<int> exact = nearest_middle_row(model, chosen, exact_count);
  if (only_exact)
    chosen = exact;
  return placed_keypoints(model, chosen, exact, at);
}

/// Every principal point of `inst` within 1 px of where the face puts it.
void expect_on_face(const Model& model, const Instance& inst) {
  for (size_t k = 0; k < model.principal_points.size(); ++k) {
    const cv::Point2f truth = on_face(model, model.principal_points[k]);
    EXPECT_LT(cv::norm(inst.points[k] - truth), 1.0)
        << "principal point " << k << ": expected (" << truth.x << ", " << truth.y << "), got ("
        << inst.points[k].x << ", " << inst.points[k].y << ")";
  }
}

/// Detects `scene` with `model` alone: `ratio_matches` matches pass the ratio test (the
/// premise), and the one instance found is the face, completed by guided matching from at least
/// `least_pairs` pairs, and not pickable.
void expect_one_guided_face(const Model& model, const Features& scene, int ratio_matches,
                            int least_pairs) {
  const Detection d = Detector({model}).detect(scene, cv::Size(640, 480), Settings());
  EXPECT_EQ(d.matches, ratio_matches) << "the premise: so many matches pass the ratio test";
  ASSERT_EQ(d.instances.size(), 1u) << "the face is completed from its keypoints' descriptors";
  const Instance& inst = d.instances[0];
  EXPECT_GE(inst.matches, least_pairs) << "the rest of the face supports it";
  EXPECT_TRUE(inst.guided);
  EXPECT_FALSE(inst.pickable);
  expect_on_face(model, inst);
}

} // namespace

TEST(GuidedMatching, AFaintFaceOfTwoRatioTestMatchesIsCompleted) {
  const Model model = faint_box_model();
  ASSERT_LT(model.contrast_threshold, kSiftContrastThreshold) << "the premise: faint print";
  const Features scene = face_keypoints(model, false);
  ASSERT_EQ(scene.keypoints.size(), 12u);
  const Detection d = Detector({model}).detect(scene, cv::Size(640, 480), Settings());
  EXPECT_EQ(d.matches, 2) << "the premise: two matches pass the ratio test";
  ASSERT_EQ(d.instances.size(), 1u) << "the face is found from its keypoints' descriptors";
  const Instance& inst = d.instances[0];
  EXPECT_EQ(inst.matches, 12) << "every keypoint of the face supports it";
  EXPECT_TRUE(inst.guided);
  EXPECT_FALSE(inst.pickable) << "a pose of a few pairs without the ratio test: uncertain, so "
                                 "not pickable, though nothing lies on it";
  expect_on_face(model, inst);
}

TEST(GuidedMatching, TwoMatchesAloneMakeNoInstance) {
  const Model model = faint_box_model();
  const Features scene = face_keypoints(model, true);
  ASSERT_EQ(scene.keypoints.size(), 2u);
  EXPECT_TRUE(Detector({model}).detect(scene, cv::Size(640, 480), Settings()).instances.empty())
      << "nothing in the frame bears the two votes out";
}

TEST(GuidedMatching, ARichPrintModelKeepsTheRatioTestsWord) {
  // The same face and keypoints, the model's features the same, but its picture not marked as
  // of faint print: there the ratio test decides (in a frame of clutter, pairing descriptors
  // near a pose built ghosts).
  Model model = faint_box_model();
  const Features scene = face_keypoints(model, false);
  model.contrast_threshold = kSiftContrastThreshold;
  ASSERT_FALSE(model.faint_print());
  const Detection d = Detector({model}).detect(scene, cv::Size(640, 480), Settings());
  EXPECT_EQ(d.matches, 2) << "the premise: two matches pass the ratio test";
  EXPECT_TRUE(d.instances.empty());
}

TEST(GuidedMatching, AFaintFaceBesideOneFoundInAPackedRowIsCompleted) {
  // Two faces side by side in a row, touching: the first has twelve keypoints that pass the
  // ratio test, the second none (no vote starts a search there); its place is the first's
  // shifted by one face along the row.
  const Model model = faint_box_model();
  const float width = static_cast<float>(cv::boundingRect(model.outline).width);
  const cv::Vec2d step = face_map() * cv::Vec2d(width, 0.0);
  const cv::Point2f next =
      kAt + cv::Point2f(static_cast<float>(step[0]), static_cast<float>(step[1]));
  Features scene = face_keypoints(model, false, kAt, 12);
  const Features beside = face_keypoints(model, false, next, 0);
  scene.keypoints.insert(scene.keypoints.end(), beside.keypoints.begin(), beside.keypoints.end());
  cv::vconcat(scene.descriptors, beside.descriptors, scene.descriptors);
  const Detection d = Detector({model}).detect(scene, cv::Size(1000, 800), Settings());
  ASSERT_EQ(d.instances.size(), 2u) << "both faces of the row";
  for (const cv::Point2f at : {kAt, next}) {
    const auto it = std::find_if(d.instances.begin(), d.instances.end(),
                                 [&](const Instance& i) { return cv::norm(i.center - at) < 1.0; });
    ASSERT_NE(it, d.instances.end()) << "no face within 1 px of (" << at.x << ", " << at.y << ")";
    EXPECT_EQ(it->guided, at == next) << "only the second needs guided matching";
  }
}

TEST(GuidedMatching, AFaintFaceFoundOnABunchOfMatchesIsCompleted) {
  // Only the keypoints on one small part of the face pass the ratio test (a logo on a washed-out
  // carton): four of them, bunched, enough to find the face but too little spread over it for
  // the scene explanation to keep it, and its pose, fitted on them, is off at the far ends.
  // Guided matching from that pose pairs the rest of the face.
  const Model model = faint_box_model();
  const size_t own = own_keypoints(model);
  const int strongest =
      strongest_own_keypoint(model, own, [](int, const cv::KeyPoint&) { return true; });
  const cv::Point2f anchor = model.sift.keypoints[static_cast<size_t>(strongest)].pt;
  std::vector<int> bunch(own);
  std::iota(bunch.begin(), bunch.end(), 0);
  std::sort(bunch.begin(), bunch.end(), [&](int a, int b) {
    return cv::norm(model.sift.keypoints[a].pt - anchor) <
           cv::norm(model.sift.keypoints[b].pt - anchor);
  });
  bunch.resize(4);
  std::vector<int> chosen = grid_keypoints(model);
  for (int i : bunch)
    if (std::find(chosen.begin(), chosen.end(), i) == chosen.end())
      chosen.push_back(i);
  const Features scene = placed_keypoints(model, chosen, bunch, kAt);
  std::vector<cv::Point2f> bunched;
  for (int i : bunch)
    bunched.push_back(model.sift.keypoints[static_cast<size_t>(i)].pt);
  std::vector<cv::Point2f> hull;
  cv::convexHull(bunched, hull);
  ASSERT_LT(cv::contourArea(hull), 0.03 * cv::contourArea(model.outline))
      << "the premise: the four are bunched on a small part of the face";
  expect_one_guided_face(model, scene, 4, 8);
}

TEST(GuidedMatching, AFaintFaceOfThreeMatchesAndAStrayVoteIsCompleted) {
  // Three matches pass the ratio test on the face, and a fourth scene keypoint with a picture
  // keypoint's own descriptor lies 12 px off that keypoint's place (a match on something else
  // whose vote for the centre lands near theirs): four votes, as many as min_matches, that no
  // pose fits. Without the stray vote the three are completed by guided matching; with it, so
  // they are still.
  const Model model = faint_box_model();
  const std::vector<int> chosen = grid_keypoints(model);
  const std::vector<int> exact = nearest_middle_row(model, chosen, 4);
  ASSERT_EQ(exact.size(), 4u);
  Features scene = placed_keypoints(model, chosen, exact, kAt);
  const size_t stray =
      static_cast<size_t>(std::find(chosen.begin(), chosen.end(), exact[3]) - chosen.begin());
  scene.keypoints[stray].pt += cv::Point2f(0.f, 12.f);
  expect_one_guided_face(model, scene, 4, 10); // the face's keypoints, the stray one aside
}

namespace {

/// A 640 x 480 frame of mid-grey with the model's picture on the face (where face_keypoints puts
/// its keypoints), left of `seen_to` (frame x): right of it a plain grey card lies on it. A dark
/// and a white object in two corners give the frame a well-lit frame's span of grey.
cv::Mat frame_of(const Model& model, float seen_to) {
  cv::Mat frame(480, 640, CV_8UC1, cv::Scalar(128));
  const float w = static_cast<float>(model.image.cols), h = static_cast<float>(model.image.rows);
  const std::vector<cv::Point2f> corners = {{0.f, 0.f}, {w, 0.f}, {0.f, h}};
  std::vector<cv::Point2f> placed;
  for (const cv::Point2f& p : corners)
    placed.push_back(on_face(model, p));
  cv::warpAffine(model.image, frame, cv::getAffineTransform(corners, placed), frame.size(),
                 cv::INTER_LINEAR, cv::BORDER_TRANSPARENT);
  const int from = std::clamp(static_cast<int>(seen_to), 0, frame.cols);
  frame(cv::Rect(from, 0, frame.cols - from, frame.rows)).setTo(cv::Scalar(128));
  frame(cv::Rect(0, 0, 60, 60)).setTo(cv::Scalar(10));
  frame(cv::Rect(580, 420, 60, 60)).setTo(cv::Scalar(250));
  return frame;
}

/// The faint face of AFaintFaceOfTwoRatioTestMatchesIsCompleted, its keypoints in the frame as
/// they are there, detected with the frame's pixels.
Detection detect_on(const Model& model, const cv::Mat& frame) {
  const Features scene = face_keypoints(model, false);
  const Detector detector({model});
  return detector.detect(frame, scene, detector.match(scene), Settings());
}

} // namespace

TEST(GuidedMatching, AFaceWhoseFrameShowsItsPrintStands) {
  const Model model = faint_box_model();
  const Detection d = detect_on(model, frame_of(model, 640.f));
  ASSERT_EQ(d.instances.size(), 1u) << "the print in the frame bears the pairs out";
  EXPECT_TRUE(d.instances[0].guided);
  expect_on_face(model, d.instances[0]);
}

TEST(GuidedMatching, AFacePartlyUnderACardStands) {
  // A plain card hides the face's right part (a third of it): what is seen of the print still
  // bears it out.
  const Model model = faint_box_model();
  const Detection d = detect_on(model, frame_of(model, kAt.x + 40.f));
  ASSERT_EQ(d.instances.size(), 1u) << "two thirds of the print are seen";
  EXPECT_TRUE(d.instances[0].guided);
  EXPECT_FALSE(d.instances[0].pickable);
}

TEST(GuidedMatching, PairsWhereTheFrameShowsNoneOfThePrintMakeNoInstance) {
  // The same keypoints, but the frame shows none of the face's print where they lie: pairs on
  // something else (a line drawing's strokes paired along a striped card or a bin's rim). The
  // face is washed out to 30 % of its contrast (still faint print: searched at a lowered
  // threshold), not 25 % as above: there its print has the texture the frame is compared in
  // (kMinCellTexture) in only 3 or 4 of its cells, too few to tell anything by, and a face
  // whose print cannot be told stands on its pairs.
  const Model model = faint_box_model(0.3);
  ASSERT_LT(model.contrast_threshold, kSiftContrastThreshold) << "the premise: faint print";
  ASSERT_EQ(detect_on(model, frame_of(model, 640.f)).instances.size(), 1u)
      << "the premise: where the frame shows the print, the pairs make the face";
  const Detection d = detect_on(model, frame_of(model, 0.f));
  EXPECT_TRUE(d.instances.empty()) << "the frame does not show the face the pairs stand for";
}

TEST(GuidedMatching, AFaceInADimFrameStands) {
  // The frame of AFaceWhoseFrameShowsItsPrintStands at 30 % of its light: the faint print keeps
  // too little detail to be told from flat ground, so flat cells do not count against it.
  const Model model = faint_box_model();
  cv::Mat dim;
  frame_of(model, 640.f).convertTo(dim, CV_8U, 0.3);
  ASSERT_LT(exposure_contrast_share(dim), 0.5) << "the premise: a dim frame";
  const Detection d = detect_on(model, dim);
  ASSERT_EQ(d.instances.size(), 1u) << "the face stands on its pairs";
  EXPECT_TRUE(d.instances[0].guided);
}
