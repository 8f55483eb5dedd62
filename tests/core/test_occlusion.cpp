// SPDX-License-Identifier: LGPL-2.1-or-later
// Which one to pick: stacks in both orders, three levels, touching neighbours, the frame edge.
#include "../support/belt_blur.hpp"
#include "../support/box.hpp"
#include "common/scene.hpp"

#include <pickdetect/matching.hpp>
#include <pickdetect/meanshift.hpp>
#include <pickdetect/occlusion.hpp>
#include <pickdetect/pickdetect.hpp>
#include <pickdetect/pose.hpp>
#include <pickdetect/ransac.hpp>
#include <pickdetect/voting.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <string>

using namespace pickdetect;
using pickdetect::test_scene::box_detector;
using pickdetect::test_scene::box_model;
using pickdetect::test_scene::box_picture;
using pickdetect::test_scene::Pose;

namespace {

/// Detects in a scene with boxes pasted in the given order (the last lies on top) and returns
/// the instance found nearest each pose, in the same order.
std::vector<Instance> detect_stack(const std::vector<Pose>& poses, cv::Size frame = {900, 700},
                                   bool with_pixels = true) {
  const cv::Mat picture = box_picture();
  cv::Mat scene = test_scene::plain_background(frame);
  test_scene::paste(scene, picture, poses);
  const Detection d = with_pixels ? box_detector().detect(scene)
                                  : box_detector().detect(extract_features(scene), scene.size());
  std::vector<Instance> ordered;
  for (const Pose& p : poses) {
    const Instance* best = nullptr;
    for (const Instance& i : d.instances)
      if (std::hypot(i.center.x - p.center.x, i.center.y - p.center.y) < 3.0)
        best = &i;
    EXPECT_NE(best, nullptr) << "no instance found at (" << p.center.x << ", " << p.center.y << ")";
    ordered.push_back(best ? *best : Instance());
  }
  EXPECT_EQ(d.instances.size(), poses.size());
  return ordered;
}

} // namespace

TEST(Occlusion, TwoBoxStackOnlyTheUpperOneIsPickable) {
  const Pose lower{{330.f, 300.f}, 15.0, 1.0}, upper{{470.f, 380.f}, 100.0, 1.0};
  for (bool with_pixels : {true, false}) {
    const std::vector<Instance> found = detect_stack({lower, upper}, {900, 700}, with_pixels);
    ASSERT_EQ(found.size(), 2u);
    EXPECT_TRUE(found[0].covered) << "the lower box must be covered (pixels: " << with_pixels
                                  << ")";
    EXPECT_FALSE(found[0].pickable);
    EXPECT_EQ(found[0].pick_order, 0);
    EXPECT_FALSE(found[1].covered) << "the upper box lies free (pixels: " << with_pixels << ")";
    EXPECT_TRUE(found[1].pickable);
    EXPECT_EQ(found[1].pick_order, 1);
    EXPECT_LT(found[0].visibility, 0.9);
    EXPECT_GT(found[1].visibility, 0.99);
  }
}

TEST(Occlusion, TwoBoxStackTheOtherWayRound) {
  const Pose lower{{470.f, 380.f}, 100.0, 1.0}, upper{{330.f, 300.f}, 15.0, 1.0};
  const std::vector<Instance> found = detect_stack({lower, upper});
  ASSERT_EQ(found.size(), 2u);
  EXPECT_FALSE(found[0].pickable) << "the lower box must not be pickable";
  EXPECT_TRUE(found[1].pickable) << "the upper box must be pickable";
  EXPECT_EQ(found[1].pick_order, 1);
}

TEST(Occlusion, ThreeLevelStackOnlyTheTopIsPickable) {
  const std::vector<Pose> stack = {
      {{300.f, 300.f}, 0.0, 1.0}, {{430.f, 360.f}, 60.0, 1.0}, {{560.f, 420.f}, 140.0, 1.0}};
  const std::vector<Instance> found = detect_stack(stack, {1000, 750});
  ASSERT_EQ(found.size(), 3u);
  EXPECT_TRUE(found[0].covered);
  EXPECT_TRUE(found[1].covered);
  EXPECT_FALSE(found[2].covered);
  EXPECT_FALSE(found[0].pickable);
  EXPECT_FALSE(found[1].pickable);
  EXPECT_TRUE(found[2].pickable);
}

TEST(Occlusion, SideBySideBoxesThatTouchAreBothPickable) {
  // Two upright boxes whose long edges meet: 224 px apart, the box's height (223 px) plus one.
  const std::vector<Pose> row = {
      {{300.f, 250.f}, 0.0, 1.0}, {{300.f, 474.f}, 0.0, 1.0}, {{625.f, 250.f}, 0.0, 1.0}};
  const std::vector<Instance> found = detect_stack(row, {900, 700});
  ASSERT_EQ(found.size(), 3u);
  for (const Instance& i : found) {
    EXPECT_FALSE(i.covered) << "at (" << i.center.x << ", " << i.center.y << ")";
    EXPECT_TRUE(i.pickable) << "at (" << i.center.x << ", " << i.center.y << ")";
  }
  std::vector<int> orders = {found[0].pick_order, found[1].pick_order, found[2].pick_order};
  std::sort(orders.begin(), orders.end());
  EXPECT_EQ(orders, (std::vector<int>{1, 2, 3}));
}

TEST(Occlusion, VisibilityCountsWhatLiesOutsideTheFrame) {
  // A box whose left half lies beyond the frame's edge.
  const std::vector<Instance> found = detect_stack({{{0.f, 300.f}, 0.0, 1.0}}, {700, 600});
  ASSERT_EQ(found.size(), 1u);
  EXPECT_NEAR(found[0].visibility, 0.5, 0.02);
  EXPECT_FALSE(found[0].covered);
  EXPECT_FALSE(found[0].pickable) << "its grasp point (the centre) lies on the frame's edge";
}

TEST(Occlusion, WithPickWholeInViewABoxPartlyBeyondTheFrameIsNotPickable) {
  // A fifth of the box (324 px wide) lies beyond the left edge; its grasp point and most of it
  // are in view. By default it is pickable; with pick_whole_in_view it is not (what lies on the
  // part the camera does not see is not known), while the same box wholly in view (its left
  // edge 4 px inside) still is.
  const cv::Mat picture = box_picture();
  auto detect = [&](float x, bool whole_in_view) {
    cv::Mat scene = test_scene::plain_background({700, 600});
    test_scene::paste(scene, picture, {{{x, 300.f}, 0.0, 1.0}});
    Settings settings;
    settings.pick_whole_in_view = whole_in_view;
    const Detection d = box_detector().detect(scene, settings);
    EXPECT_EQ(d.instances.size(), 1u);
    return d.instances.empty() ? Instance() : d.instances[0];
  };
  const Instance partly = detect(100.f, false);
  EXPECT_NEAR(partly.visibility, 0.81, 0.02);
  EXPECT_FALSE(partly.covered);
  EXPECT_TRUE(partly.pickable) << "by default four fifths in view are enough";
  const Instance unsure = detect(100.f, true);
  EXPECT_FALSE(unsure.covered);
  EXPECT_FALSE(unsure.pickable) << "a fifth of it lies outside the frame";
  EXPECT_EQ(unsure.pick_order, 0);
  const Instance whole = detect(166.f, true);
  EXPECT_TRUE(whole.pickable) << "wholly in view, visibility " << whole.visibility;
  EXPECT_EQ(whole.pick_order, 1);
}

TEST(Occlusion, PickOrderFollowsTheScore) {
  std::vector<Instance> inst(3);
  const std::vector<std::vector<cv::Point2f>> outlines = {
      {{0, 0}, {100, 0}, {100, 100}, {0, 100}},
      {{150, 0}, {250, 0}, {250, 100}, {150, 100}},
      {{300, 0}, {400, 0}, {400, 100}, {300, 100}}};
  const double scores[] = {0.5, 0.9, 0.7};
  for (size_t i = 0; i < 3; ++i) {
    inst[i].outline = outlines[i];
    inst[i].score = scores[i];
    inst[i].grasp = outlines[i][0] + cv::Point2f(50, 50);
  }
  assess_occlusion(inst, {box_model()}, {500, 200});
  EXPECT_EQ(inst[0].pick_order, 3);
  EXPECT_EQ(inst[1].pick_order, 1);
  EXPECT_EQ(inst[2].pick_order, 2);
}

TEST(Occlusion, ASmallBoxLyingInsideABigOneIsKept) {
  // The small box's evidence lies wholly within the big box's outline, but where it lies the big
  // box shows no features: it is on top, not a few of the big box's features matching wrongly.
  const Pose lower{{450.f, 350.f}, 10.0, 1.2}, upper{{470.f, 360.f}, 70.0, 0.45};
  const std::vector<Instance> found = detect_stack({lower, upper});
  ASSERT_EQ(found.size(), 2u);
  EXPECT_TRUE(found[0].covered);
  EXPECT_TRUE(found[1].pickable);
}

namespace {

/// One box at `pose`, then `draw` over the frame; the instance found nearest the pose.
template <typename Draw>
Instance detect_one(const Pose& pose, Draw&& draw, const Settings& settings = Settings()) {
  const cv::Mat picture = box_picture();
  cv::Mat scene = test_scene::plain_background({800, 600});
  test_scene::paste(scene, picture, {pose});
  draw(scene);
  const Detection d = box_detector().detect(scene, settings);
  EXPECT_EQ(d.instances.size(), 1u);
  return d.instances.empty() ? Instance() : d.instances[0];
}

/// A striped card (a package of another kind) `side` pixels wide, centred at `at`: grey level
/// `ground`, stripes of `stripe`.
void striped_card(cv::Mat& scene, cv::Point at, int side, int ground = 200, int stripe = 60) {
  const cv::Rect card(at.x - side / 2, at.y - side / 2, side, side);
  scene(card).setTo(cv::Scalar(ground));
  for (int x = card.x + 4; x < card.x + card.width; x += 9)
    cv::line(scene, {x, card.y}, {x + side / 3, card.y + card.height - 1}, cv::Scalar(stripe), 2);
}

/// Where `inst` carries the point `p` of its model picture.
cv::Point in_frame(const Instance& inst, cv::Point2d p) {
  const cv::Vec3d at = inst.homography * cv::Vec3d(p.x, p.y, 1.0);
  return {cvRound(at[0] / at[2]), cvRound(at[1] / at[2])};
}

/// The pose of the lone box the tests below lay things on.
const Pose kLonePose{{400.f, 300.f}, 20.0, 1.0};

/// Expects the box found under something (`what`: what lies on it) with most of its features
/// still, covered and not pickable.
void expect_covered(const Instance& under, const char* what) {
  EXPECT_GE(under.matches, 20);
  EXPECT_TRUE(under.covered) << what;
  EXPECT_FALSE(under.pickable);
}

} // namespace

TEST(Occlusion, AnObjectOfNoModelLyingOnABoxCoversIt) {
  const Instance free = detect_one(kLonePose, [](cv::Mat&) {});
  EXPECT_FALSE(free.covered);
  EXPECT_TRUE(free.pickable);
  // A card over one end of the box: a fifth of its width, far from its grasp point (the
  // centre), most of the box's features still seen.
  const Instance under = detect_one(kLonePose, [](cv::Mat& s) { striped_card(s, {510, 330}, 60); });
  expect_covered(under, "a card lies on the box");
  EXPECT_EQ(under.pick_order, 0);
}

TEST(Occlusion, APlainObjectLyingOnABoxCoversIt) {
  // A plain grey lid, no texture of its own, over the box's printed lower end.
  const Instance under = detect_one(kLonePose, [](cv::Mat& s) {
    cv::ellipse(s, {480, 340}, {32, 24}, 30.0, 0.0, 360.0, cv::Scalar(90), cv::FILLED);
  });
  expect_covered(under, "a plain lid lies on the box");
}

TEST(Occlusion, ALightPlainLidWithEdgesOfItsOwnCoversIt) {
  // A plain lid lighter than the print: flat and light inside, as a highlight washing the print
  // out would be, but with a sharp rim that shows something else all round it, where a
  // highlight fades into the print.
  for (const int level : {170, 210}) {
    const Instance under = detect_one(kLonePose, [&](cv::Mat& s) {
      cv::ellipse(s, {470, 330}, {38, 30}, 30.0, 0.0, 360.0, cv::Scalar(level), cv::FILLED);
    });
    expect_covered(under, ("a light plain lid (grey " + std::to_string(level) + ")").c_str());
  }
}

TEST(Occlusion, ATexturedObjectOnAnUnprintedPartOfABoxCoversIt) {
  const Instance free = detect_one(kLonePose, [](cv::Mat&) {});
  ASSERT_FALSE(free.covered);
  // box.png's upper left (about x 36-130, y 12-48 of the picture) is plain card: no print to
  // compare with. A striped card lying there shows texture the print cannot have.
  const cv::Point centre = in_frame(free, {80.0, 32.0});
  const Instance under = detect_one(kLonePose, [&](cv::Mat& s) { striped_card(s, centre, 40); });
  expect_covered(under, "a card lies on the box's plain corner");
}

TEST(Occlusion, ACardBlurredByTheBeltCoversTheBoxItLiesOn) {
  const Instance free = detect_one(kLonePose, [](cv::Mat&) {});
  ASSERT_FALSE(free.covered);
  // A dim card with faint stripes over the box's print, the whole frame then blurred by a belt
  // moving 11 pixels while the shutter was open: part of the card is flat, part shows smeared
  // stripes, and no part of it shows the print.
  const cv::Point centre = in_frame(free, {200.0, 100.0});
  const Instance under = detect_one(kLonePose, [&](cv::Mat& s) {
    striped_card(s, centre, 48, 100, 80);
    cv::blur(s, s, cv::Size(11, 1));
  });
  expect_covered(under, "a card lies on the box");
}

TEST(Occlusion, MotionBlurOnABoxDoesNotCoverIt) {
  // The conveyor moved 11 pixels while the shutter was open: the finest print is gone.
  const Instance blurred =
      detect_one(kLonePose, [](cv::Mat& s) { cv::blur(s, s, cv::Size(11, 1)); });
  EXPECT_FALSE(blurred.covered);
  EXPECT_TRUE(blurred.pickable);
}

/// The settings that know a belt's blur of `length` pixels along the frame's rows.
Settings knowing_blur(double length) {
  Settings s;
  s.motion_blur_x = length;
  return s;
}

TEST(Occlusion, ABoxUnderALongBlurTheDetectorKnowsIsNotCovered) {
  // 25 pixels of blur (a fast belt, the shutter open most of the frame): the print's detail is
  // smeared along the rows. Compared with the sharp picture, the smear looks like something
  // else lying on the box; compared with the picture blurred as the frame is, it is the print.
  const auto blur = [](cv::Mat& s) { s = test_scene::blurred_along_x(s, 25); };
  const Instance unknown = detect_one(kLonePose, blur);
  ASSERT_GE(unknown.matches, 10);
  EXPECT_TRUE(unknown.covered) << "the sharp picture no longer tells a blurred box from a cover";
  const Instance known = detect_one(kLonePose, blur, knowing_blur(25.0));
  EXPECT_FALSE(known.covered);
  EXPECT_TRUE(known.pickable);
}

TEST(Occlusion, ACardOnABoxIsSeenThroughALongBlurTheDetectorKnows) {
  const Instance free = detect_one(kLonePose, [](cv::Mat&) {});
  ASSERT_FALSE(free.covered);
  // A striped card and a plain lid over the box's print, then the same 25 pixels of blur: the
  // print blurred as the frame is still shows neither.
  const cv::Point centre = in_frame(free, {200.0, 100.0});
  const Instance carded = detect_one(
      kLonePose,
      [&](cv::Mat& s) {
        striped_card(s, centre, 60);
        s = test_scene::blurred_along_x(s, 25);
      },
      knowing_blur(25.0));
  EXPECT_TRUE(carded.covered) << "a striped card lies on the box";
  EXPECT_FALSE(carded.pickable);
  const Instance lidded = detect_one(
      kLonePose,
      [](cv::Mat& s) {
        cv::ellipse(s, {480, 340}, {36, 28}, 30.0, 0.0, 360.0, cv::Scalar(90), cv::FILLED);
        s = test_scene::blurred_along_x(s, 25);
      },
      knowing_blur(25.0));
  EXPECT_TRUE(lidded.covered) << "a plain lid lies on the box";
  EXPECT_FALSE(lidded.pickable);
}

TEST(Occlusion, AMotionBlurThatIsNoLengthIsRefusedByName) {
  const cv::Mat picture = box_picture();
  cv::Mat scene = test_scene::plain_background({800, 600});
  test_scene::paste(scene, picture, {kLonePose});
  for (const cv::Point2d blur : {cv::Point2d(std::nan(""), 0.0), cv::Point2d(0.0, 300.0)}) {
    Settings s;
    s.motion_blur_x = blur.x;
    s.motion_blur_y = blur.y;
    try {
      box_detector().detect(scene, s);
      FAIL() << "a motion blur of (" << blur.x << ", " << blur.y << ") was taken";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("motion_blur_x"), std::string::npos) << e.what();
    }
  }
}

TEST(Occlusion, GlareAndSpeckleOnABoxDoNotCoverIt) {
  // A washed-out highlight (flat, brightest there) and sensor noise over the whole frame.
  const Instance glare = detect_one(kLonePose, [](cv::Mat& s) {
    cv::Mat spot = cv::Mat::zeros(s.size(), CV_8UC1);
    cv::circle(spot, {430, 290}, 35, cv::Scalar(255), cv::FILLED);
    cv::GaussianBlur(spot, spot, cv::Size(0, 0), 6.0);
    cv::add(s, spot, s);
    cv::Mat noise(s.size(), CV_8UC1);
    cv::randn(noise, 0, 4);
    cv::add(s, noise, s);
  });
  EXPECT_FALSE(glare.covered);
  EXPECT_TRUE(glare.pickable);
  // A broad sheen that washes the print out to a flat light grey, short of clipping.
  const Instance sheen = detect_one(kLonePose, [](cv::Mat& s) {
    cv::Mat alpha = cv::Mat::zeros(s.size(), CV_32FC1);
    cv::circle(alpha, {470, 330}, 30, cv::Scalar(1.0), cv::FILLED);
    cv::GaussianBlur(alpha, alpha, cv::Size(0, 0), 8.0);
    cv::Mat grey;
    s.convertTo(grey, CV_32F);
    grey = grey.mul(1.0 - alpha) + 235.0 * alpha;
    grey.convertTo(s, CV_8U);
  });
  EXPECT_FALSE(sheen.covered);
  EXPECT_TRUE(sheen.pickable);
}

TEST(Occlusion, AFrameThatIsNotGreyIsRefusedByName) {
  std::vector<Instance> found = {detect_one(kLonePose, [](cv::Mat&) {})};
  const cv::Mat colour(600, 800, CV_8UC3, cv::Scalar(90, 90, 90));
  try {
    assess_occlusion(found, box_detector().models(), {800, 600}, colour);
    FAIL() << "a colour frame was taken";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("8-bit grey"), std::string::npos) << e.what();
  }
  const cv::Mat small(300, 400, CV_8UC1, cv::Scalar(90));
  EXPECT_THROW(assess_occlusion(found, box_detector().models(), {800, 600}, small), Error);
}

TEST(Occlusion, OverlapAreaOfCrossingAndTouchingOutlines) {
  const std::vector<cv::Point2f> a = {{0, 0}, {100, 0}, {100, 100}, {0, 100}};
  const std::vector<cv::Point2f> b = {{50, 50}, {150, 50}, {150, 150}, {50, 150}};
  const std::vector<cv::Point2f> touching = {{100, 0}, {200, 0}, {200, 100}, {100, 100}};
  EXPECT_NEAR(overlap_area(a, b), 2500.0, 1e-3);
  EXPECT_NEAR(overlap_area(a, touching), 0.0, 1e-3);
}

TEST(Occlusion, AFreeBoxWithAPlainRimTurnedOnADarkGroundIsNotCovered) {
  // box.png with a plain light margin along its lower side, lying a few degrees off the frame's
  // axes on a dark ground: the cells along that side hold the ground's edge near them, which
  // the comparison's blurs would spread into the plain margin as detail the print cannot have.
  cv::Mat picture;
  cv::copyMakeBorder(box_picture(), picture, 0, 24, 0, 0, cv::BORDER_CONSTANT, cv::Scalar(240));
  const Detector detector({test_scene::picture_model("box_with_margin", picture)});
  const auto detect = [&](const Pose& pose, bool card) {
    cv::Mat scene = test_scene::plain_background({800, 600}, 15);
    test_scene::paste(scene, picture, {pose});
    if (card)
      striped_card(scene, {365, 425}, 50, 15, 200);
    const Detection d = detector.detect(scene);
    EXPECT_EQ(d.instances.size(), 1u);
    return d.instances.empty() ? Instance() : d.instances[0];
  };
  for (const double angle : {2.0, 3.0, 176.0, 184.0}) {
    const Instance free = detect({{400.f, 300.f}, angle, 1.0}, false);
    EXPECT_FALSE(free.covered) << "turned " << angle << " degrees";
    EXPECT_TRUE(free.pickable) << "turned " << angle << " degrees";
  }
  // A striped card of the ground's own grey lying across that rim still covers the box.
  const Instance under = detect({{400.f, 300.f}, 2.0, 1.0}, true);
  expect_covered(under, "a card lies across the box's plain rim");
}
