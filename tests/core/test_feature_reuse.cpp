// SPDX-License-Identifier: LGPL-2.1-or-later
// FeatureReuse (the element's full-detection-interval): a still scene costs no extraction, a
// moving box is found where whole-frame detection finds it, a box coming into view is found
// without a whole frame, a belt's motion blur is undone, a box leaving the frame is followed out.
#include "../support/belt_blur.hpp"
#include "../support/box.hpp"
#include "common/scene.hpp"

#include <pickdetect/pickdetect.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

using namespace pickdetect;
using pickdetect::test_scene::blurred_along_x;
using pickdetect::test_scene::Pose;

namespace {

const cv::Size kSize(960, 720);

const cv::Mat& box_picture() {
  static const cv::Mat picture = cv::imread(test_scene::kData + "/box.png", cv::IMREAD_GRAYSCALE);
  return picture;
}

/// A still textured belt with boxes at `poses`, and sensor noise of its own (seed) when
/// `noise_seed` is not 0. Black and white marks in a corner keep the frame's grey span, so the
/// exposure's contrast threshold, the same whatever boxes are in view.
cv::Mat scene_with(const std::vector<Pose>& poses, int noise_seed = 0, int belt_seed = 77) {
  cv::Mat scene = test_scene::smooth_noise_background(kSize, belt_seed);
  scene(cv::Rect(0, 0, 40, 40)).setTo(0);
  scene(cv::Rect(40, 0, 40, 40)).setTo(255);
  test_scene::paste(scene, box_picture(), poses);
  if (noise_seed != 0) {
    cv::Mat noise(kSize, CV_16SC1);
    cv::RNG rng(static_cast<uint64>(noise_seed));
    rng.fill(noise, cv::RNG::NORMAL, 0, 2);
    cv::Mat wide;
    scene.convertTo(wide, CV_16SC1);
    cv::Mat(wide + noise).convertTo(scene, CV_8UC1);
  }
  return scene;
}

/// Instances of both detections pair by centre (nearest); each pair's centre, outline and
/// grasp point within `px`, the same covered and pickable.
void expect_same_instances(const Detection& got, const Detection& want, double px) {
  ASSERT_EQ(got.instances.size(), want.instances.size());
  for (const Instance& w : want.instances) {
    const Instance* best = nullptr;
    for (const Instance& g : got.instances)
      if (!best || cv::norm(g.center - w.center) < cv::norm(best->center - w.center))
        best = &g;
    ASSERT_NE(best, nullptr);
    EXPECT_LE(cv::norm(best->center - w.center), px)
        << "instance at (" << w.center.x << ", " << w.center.y << ") found at (" << best->center.x
        << ", " << best->center.y << ")";
    ASSERT_EQ(best->outline.size(), w.outline.size());
    for (size_t k = 0; k < w.outline.size(); ++k)
      EXPECT_LE(cv::norm(best->outline[k] - w.outline[k]), px) << "outline corner " << k;
    EXPECT_LE(cv::norm(best->grasp - w.grasp), px);
    EXPECT_EQ(best->covered, w.covered);
    EXPECT_EQ(best->pickable, w.pickable);
  }
}

TEST(FeatureReuse, StillSceneExtractsNoFeaturesAfterTheFirstFrame) {
  const Detector& detector = test_scene::box_detector();
  const std::vector<Pose> poses = {Pose{{300.f, 250.f}, 15.0, 0.6},
                                   Pose{{650.f, 450.f}, 200.0, 0.6}};
  FeatureReuse reuse(30);
  const Detection first = reuse.detect(detector, scene_with(poses, 1), Settings());
  ASSERT_TRUE(reuse.last().whole);
  ASSERT_EQ(first.instances.size(), 2u);
  const int whole = reuse.last().extracted;
  EXPECT_GT(whole, 500);
  for (int frame = 2; frame <= 4; ++frame) {
    // New sensor noise in every frame, nothing else.
    const Detection d = reuse.detect(detector, scene_with(poses, frame), Settings());
    EXPECT_EQ(reuse.last().extracted, 0)
        << "frame " << frame << " (the first extracted " << whole << ")";
    EXPECT_TRUE(reuse.last().unchanged) << "frame " << frame;
    EXPECT_EQ(reuse.last().extracted_share, 0.0);
    expect_same_instances(d, first, 1e-6);
  }
}

TEST(FeatureReuse, MovingBoxIsFoundWhereWholeFrameDetectionFindsIt) {
  const Detector& detector = test_scene::box_detector();
  FeatureReuse reuse(30);
  const Pose still{{720.f, 200.f}, 100.0, 0.55};
  for (int frame = 0; frame < 6; ++frame) {
    // One box rides right 12 px a frame beside one that lies still.
    const cv::Mat grey = scene_with({Pose{{200.f + 12.f * frame, 450.f}, 30.0, 0.55}, still});
    const Detection got = reuse.detect(detector, grey, Settings());
    const ReuseStats stats = reuse.last();
    const Detection want = detector.detect(grey, Settings());
    ASSERT_EQ(want.instances.size(), 2u) << "frame " << frame;
    expect_same_instances(got, want, 0.1);
    if (frame > 0) {
      // The moving box is found again by its motion: no SIFT at all.
      EXPECT_FALSE(stats.whole) << "frame " << frame;
      EXPECT_EQ(stats.extracted_share, 0.0) << "frame " << frame;
      EXPECT_GT(stats.reused, 0) << "frame " << frame;
    }
  }
}

TEST(FeatureReuse, BoxComingIntoViewIsFoundWithoutAWholeFrame) {
  const Detector& detector = test_scene::box_detector();
  FeatureReuse reuse(30);
  const Pose first{{250.f, 250.f}, 0.0, 0.55};
  ASSERT_EQ(reuse.detect(detector, scene_with({first}), Settings()).instances.size(), 1u);
  const cv::Mat grey = scene_with({first, Pose{{700.f, 480.f}, 60.0, 0.55}});
  const Detection got = reuse.detect(detector, grey, Settings());
  EXPECT_FALSE(reuse.last().whole);
  EXPECT_LT(reuse.last().extracted_share, 0.6);
  expect_same_instances(got, detector.detect(grey, Settings()), 0.1);
}

TEST(FeatureReuse, BeltMotionBlurIsUndoneSoThatBlurredBoxesAreFound) {
  const Detector& detector = test_scene::box_detector();
  FeatureReuse reuse(30);
  // Boxes ride right 25 px a frame, blurred by 13 px (the shutter open half the frame time);
  // the small ones are lost in the blur, or placed pixels off, frame by frame.
  auto poses_at = [](int frame) {
    const float x = 25.f * static_cast<float>(frame);
    return std::vector<Pose>{
        Pose{{150.f + x, 200.f}, 20.0, 0.7}, Pose{{160.f + x, 520.f}, 290.0, 0.7},
        Pose{{520.f + x, 230.f}, 60.0, 0.32}, Pose{{560.f + x, 530.f}, 150.0, 0.32}};
  };
  int missed_frame_by_frame = 0;
  for (int frame = 0; frame < 6; ++frame) {
    const std::vector<Pose> poses = poses_at(frame);
    const cv::Mat grey = blurred_along_x(scene_with(poses, frame + 1), 13);
    const Detection got = reuse.detect(detector, grey, Settings());
    if (detector.detect(grey, Settings()).instances.size() < poses.size())
      ++missed_frame_by_frame;
    if (frame < 2)
      continue; // The blur is measured on the boxes the belt carried into frame 1.
    // From there on, every box is found where it lies, as on a sharp frame.
    ASSERT_EQ(got.instances.size(), poses.size()) << "frame " << frame;
    for (const Pose& p : poses) {
      double nearest = 1e9;
      for (const Instance& i : got.instances)
        nearest = std::min(nearest, cv::norm(i.center - p.center));
      EXPECT_LE(nearest, 0.3) << "frame " << frame << ": box at (" << p.center.x << ", "
                              << p.center.y << ")";
    }
  }
  EXPECT_GT(missed_frame_by_frame, 0) << "the blur hides no box from frame-by-frame detection";
}

TEST(FeatureReuse, FreeBoxesOnABlurredBeltArePickableOnceTheBlurIsMeasured) {
  const Detector& detector = test_scene::box_detector();
  FeatureReuse reuse(30);
  // Two boxes apart, nothing on them, riding right 25 px a frame and blurred by 20 px (the
  // shutter open most of the frame time): compared with its sharp picture, the smeared print
  // looks like something lying on a box.
  auto poses_at = [](int frame) {
    const float x = 25.f * static_cast<float>(frame);
    return std::vector<Pose>{Pose{{200.f + x, 220.f}, 20.0, 0.8},
                             Pose{{220.f + x, 500.f}, 290.0, 0.8}};
  };
  for (int frame = 0; frame < 6; ++frame) {
    const std::vector<Pose> poses = poses_at(frame);
    const cv::Mat grey = blurred_along_x(scene_with(poses, frame + 1), 20);
    const Detection got = reuse.detect(detector, grey, Settings());
    if (frame < 2)
      continue; // The blur is measured on the boxes the belt carried into frame 1.
    ASSERT_EQ(got.instances.size(), poses.size()) << "frame " << frame;
    for (const Instance& i : got.instances) {
      EXPECT_FALSE(i.covered) << "frame " << frame << ": box at (" << i.center.x << ", "
                              << i.center.y << ")";
      EXPECT_TRUE(i.pickable) << "frame " << frame;
    }
  }
}

TEST(FeatureReuse, AnotherPictureIsDetectedWhole) {
  const Detector& detector = test_scene::box_detector();
  FeatureReuse reuse(30);
  reuse.detect(detector, scene_with({Pose{{300.f, 300.f}, 0.0, 0.55}}), Settings());
  // Another belt under another box, and more light: the whole frame changed (its grey span,
  // so the contrast threshold, is the same).
  const cv::Mat other = scene_with({Pose{{600.f, 400.f}, 90.0, 0.6}}, 0, 78) + cv::Scalar(30);
  const Detection got = reuse.detect(detector, other, Settings());
  EXPECT_TRUE(reuse.last().whole);
  expect_same_instances(got, detector.detect(other, Settings()), 0.0);
}

TEST(FeatureReuse, IntervalOneDetectsEveryFrameWhole) {
  const Detector& detector = test_scene::box_detector();
  FeatureReuse reuse(1);
  const cv::Mat grey = scene_with({Pose{{400.f, 300.f}, 0.0, 0.6}});
  for (int frame = 0; frame < 2; ++frame) {
    const Detection got = reuse.detect(detector, grey, Settings());
    EXPECT_TRUE(reuse.last().whole);
    expect_same_instances(got, detector.detect(grey, Settings()), 0.0);
  }
}

} // namespace

TEST(FeatureReuse, BoxEnteringFromTheEdgeIsFollowedFromWhereItWasFoundAgain) {
  // A box rides in from the left edge, 10 px a frame. The whole frame finds it with a fifth of
  // it in view; while less than kLeastInFrame of it is in view its blocks are extracted again
  // and it is found again from those keypoints; once it is followed, its motion must be
  // measured from the frame they came from, not from the whole frame where it lay farther left
  // (before: found 20 px ahead of where it is).
  const Detector& detector = test_scene::box_detector();
  FeatureReuse reuse(30);
  const Pose still{{700.f, 250.f}, 100.0, 0.55};
  for (int frame = 0; frame < 16; ++frame) {
    const Pose riding{{-100.f + 10.f * frame, 480.f}, 10.0, 1.2};
    const cv::Mat grey = scene_with({riding, still}, frame + 1);
    const Detection got = reuse.detect(detector, grey, Settings());
    const Detection want = detector.detect(grey, Settings());
    for (const Instance& w : want.instances) {
      const auto near = std::min_element(
          got.instances.begin(), got.instances.end(), [&](const Instance& a, const Instance& b) {
            return cv::norm(a.center - w.center) < cv::norm(b.center - w.center);
          });
      ASSERT_NE(near, got.instances.end()) << "frame " << frame;
      EXPECT_LE(cv::norm(near->center - w.center), 1.0)
          << "frame " << frame << ": instance at (" << w.center.x << ", " << w.center.y
          << ") found at (" << near->center.x << ", " << near->center.y << ")";
    }
  }
}

/// A box (box.png at scale 1.2: 389 x 268 px) rides from `start` by `step` a frame beside a
/// still one, first found with a third of it in view. From frame `wholly` on it is wholly in
/// view: there, reusing the frames before, it must rest on most of the matches the whole frame
/// gives and lie where the whole frame puts it.
void expect_extracted_as_it_comes_in(const cv::Point2f& start, const cv::Point2f& step,
                                     int wholly) {
  const Detector& detector = test_scene::box_detector();
  FeatureReuse reuse(60);
  const Pose still{{700.f, 250.f}, 100.0, 0.55};
  int whole_frames = 0;
  for (int frame = 0; frame < wholly + 4; ++frame) {
    const Pose riding{start + step * static_cast<float>(frame), 0.0, 1.2};
    const cv::Mat grey = scene_with({riding, still}, frame + 1);
    const Detection got = reuse.detect(detector, grey, Settings());
    whole_frames += reuse.last().whole ? 1 : 0;
    if (frame < wholly)
      continue;
    const Detection want = detector.detect(grey, Settings());
    auto nearest = [&](const Detection& d) {
      return std::min_element(
          d.instances.begin(), d.instances.end(), [&](const Instance& a, const Instance& b) {
            return cv::norm(a.center - riding.center) < cv::norm(b.center - riding.center);
          });
    };
    const auto w = nearest(want), g = nearest(got);
    ASSERT_NE(w, want.instances.end()) << "frame " << frame;
    ASSERT_NE(g, got.instances.end()) << "frame " << frame;
    ASSERT_LE(cv::norm(w->center - riding.center), 2.0) << "frame " << frame;
    EXPECT_LE(cv::norm(g->center - w->center), 0.3)
        << "frame " << frame << ": the whole frame finds the box at (" << w->center.x << ", "
        << w->center.y << "), reuse at (" << g->center.x << ", " << g->center.y << ")";
    EXPECT_GE(g->matches, 0.6 * w->matches)
        << "frame " << frame << ": " << g->matches << " matches, the whole frame " << w->matches;
  }
  EXPECT_EQ(whole_frames, 1); // The first: every other frame reused the ones before.
}

TEST(FeatureReuse, BoxComingIntoViewIsExtractedAsItComesIn) {
  // While a box rides in across the frame's edge, what came into view since its keypoints there
  // were extracted (and those whose windows the edge cut) must be extracted each time
  // kMoreInView (0.4) more of it is in view: once wholly in view it rests on most of the matches
  // the whole frame gives (from the left, 415 of 557: its last 40 % waits for the next whole
  // frame; before: the keypoints of its first third alone, 158 matches, till the next whole
  // frame). Across the left edge, 12 px a frame; across the bottom one, going up and left.
  expect_extracted_as_it_comes_in({-60.f, 480.f}, {12.f, 0.f}, 22);
  expect_extracted_as_it_comes_in({520.f, 760.f}, {-4.f, -12.f}, 15);
}

/// A box (box.png at 0.55: 178 x 123 px) riding out across the right edge, 12 px a frame from
/// x = 880, beside a still one, over 16 frames detected with a whole frame every `interval`:
/// check(frame, what was detected, the reuse's stats, the frame) for each.
template <typename Check> void ride_out(int interval, Check&& check) {
  FeatureReuse reuse(interval);
  const Pose still{{300.f, 250.f}, 100.0, 0.55};
  for (int frame = 0; frame < 16; ++frame) {
    const Pose riding{{880.f + 12.f * frame, 480.f}, 0.0, 0.55};
    const cv::Mat grey = scene_with({riding, still}, frame + 1);
    const Detection got = reuse.detect(test_scene::box_detector(), grey, Settings());
    check(frame, got, reuse.last(), grey);
  }
}

TEST(FeatureReuse, BoxLeavingAcrossTheEdgeIsFollowedOutNotExtractedAgain) {
  // Once less than kLeastInFrame (0.3) of the box riding out is in view it is no longer found,
  // but what is left of it in view still moves with the belt: it is followed out by its
  // motion, and no frame needs SIFT (before: the blocks it changed were extracted again in
  // every frame till it was gone, for nothing: too little of it to find).
  ride_out(60, [](int frame, const Detection& got, const ReuseStats& stats, const cv::Mat& grey) {
    if (frame == 0)
      return;
    EXPECT_FALSE(stats.whole) << "frame " << frame;
    EXPECT_EQ(stats.extracted_share, 0.0) << "frame " << frame;
    // Found while half of it is in view, where the whole frame finds it; gone once out of view.
    const float in_view = std::clamp((960.f - (880.f + 12.f * frame - 89.f)) / 178.f, 0.f, 1.f);
    if (in_view >= 0.5f) {
      const Detection want = test_scene::box_detector().detect(grey, Settings());
      ASSERT_EQ(got.instances.size(), want.instances.size()) << "frame " << frame;
      for (const Instance& w : want.instances)
        EXPECT_TRUE(
            std::any_of(got.instances.begin(), got.instances.end(),
                        [&](const Instance& g) { return cv::norm(g.center - w.center) <= 1.0; }))
            << "frame " << frame << ": nothing found at (" << w.center.x << ", " << w.center.y
            << ")";
    }
    if (in_view == 0.f) {
      EXPECT_EQ(got.instances.size(), 1u) << "frame " << frame;
    }
  });
}

TEST(FeatureReuse, WhatIsLeftOfABoxLeavingRidesOutThroughAWholeFrame) {
  // The box riding out, with a whole frame every 11: frame 11 is detected whole while a fifth of
  // the box is in view (the whole frame finds it; its own step is not known there). What is left
  // of it rides out with the belt after that frame, by the belt's step: the frames after it
  // need no SIFT (before: its blocks were extracted again in every frame till it was gone).
  ride_out(11, [](int frame, const Detection& got, const ReuseStats& stats, const cv::Mat&) {
    EXPECT_EQ(stats.whole, frame % 11 == 0) << "frame " << frame;
    if (frame == 11) {
      EXPECT_EQ(got.instances.size(), 2u) << "frame 11, whole: both boxes";
    }
    if (frame > 11) {
      EXPECT_EQ(stats.extracted_share, 0.0) << "frame " << frame;
    }
    if (frame == 15) {
      EXPECT_EQ(got.instances.size(), 1u) << "frame 15: the box has left";
    }
  });
}
