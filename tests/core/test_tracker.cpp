// SPDX-License-Identifier: LGPL-2.1-or-later
// The tracker on synthetic instance streams: fast belts, arrivals, hiding, picks, counting.
#include <pickdetect/error.hpp>
#include <pickdetect/tracker.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

using namespace pickdetect;

namespace {

constexpr std::int64_t kFrameNs = 33'333'333; // 30 frames per second.
const cv::Size kFrame(1280, 960);

/// An instance of `model` at `center`, a w x h rectangle turned by `angle` degrees.
Instance box(cv::Point2f center, const std::string& model = "box", float w = 100.f, float h = 60.f,
             double angle = 0.0) {
  Instance i;
  i.model_name = model;
  i.center = center;
  i.angle = angle;
  i.grasp = center;
  i.points = {center};
  const double r = angle * CV_PI / 180.0;
  const cv::Point2f u(static_cast<float>(std::cos(r)), static_cast<float>(std::sin(r)));
  const cv::Point2f v(-u.y, u.x);
  for (const auto& [a, b] : {std::pair{-1.f, -1.f}, {1.f, -1.f}, {1.f, 1.f}, {-1.f, 1.f}})
    i.outline.push_back(center + u * (a * w / 2) + v * (b * h / 2));
  i.pickable = true;
  i.pick_order = 1;
  return i;
}

std::uint64_t id_near(const TrackedFrame& f, cv::Point2f c, float tolerance = 2.f) {
  for (const TrackedInstance& t : f.instances)
    if (!t.tracked && cv::norm(t.instance.center - c) < tolerance)
      return t.track_id;
  return 0;
}

int ended_with(const TrackedFrame& f, TrackEnd reason) {
  int n = 0;
  for (const TrackEvent& e : f.events)
    n += !e.started && e.reason == reason;
  return n;
}

} // namespace

TEST(Tracker, FastBeltWithoutOverlapKeepsEveryId) {
  // 120 px per frame: more than a box's width, so no box overlaps itself between frames.
  Tracker tracker;
  std::map<int, std::uint64_t> ids;
  for (int f = 0; f < 8; f++) {
    std::vector<Instance> frame;
    for (int k = 0; k < 3; k++)
      frame.push_back(box({100.f + 120.f * f + 180.f * k, 300.f + 150.f * k}));
    const TrackedFrame out = tracker.update(frame, f * kFrameNs, kFrame);
    ASSERT_EQ(out.instances.size(), 3u) << "frame " << f;
    for (int k = 0; k < 3; k++) {
      const std::uint64_t id = out.instances[static_cast<size_t>(k)].track_id;
      if (f == 0)
        ids[k] = id;
      EXPECT_EQ(id, ids[k]) << "box " << k << " changed id at frame " << f;
    }
    if (f >= 3) {
      ASSERT_TRUE(out.motion.found) << "frame " << f;
      EXPECT_NEAR(out.motion.velocity.x, 120.0 * 30.0, 5.0);
      EXPECT_NEAR(out.motion.velocity.y, 0.0, 5.0);
      EXPECT_EQ(out.motion.tracks, 3);
      EXPECT_NEAR(out.instances[0].velocity.x, 3600.0, 5.0);
    }
  }
  EXPECT_EQ(std::set<std::uint64_t>({ids[0], ids[1], ids[2]}).size(), 3u);
}

TEST(Tracker, SameModelNeighboursOnAFastBeltDoNotSwap) {
  // A row of boxes 110 px apart moving 45 px a frame: the nearest box of the last frame is
  // often the wrong one, the predicted centre is not.
  Tracker tracker;
  std::vector<std::uint64_t> first;
  for (int f = 0; f < 10; f++) {
    std::vector<Instance> frame;
    for (int k = 0; k < 5; k++)
      frame.push_back(box({150.f + 45.f * f + 110.f * k, 400.f}));
    const TrackedFrame out = tracker.update(frame, f * kFrameNs, kFrame);
    for (int k = 0; k < 5; k++) {
      if (f == 0)
        first.push_back(out.instances[static_cast<size_t>(k)].track_id);
      else
        EXPECT_EQ(out.instances[static_cast<size_t>(k)].track_id, first[static_cast<size_t>(k)])
            << "box " << k << " frame " << f;
    }
  }
}

TEST(Tracker, ArrivalsGetNewIdsAndIdsAreNeverReused) {
  Tracker tracker;
  std::set<std::uint64_t> seen;
  std::uint64_t last_id = 0;
  for (int f = 0; f < 60; f++) {
    // A box arrives at x = 60 every 10 frames and rides at 20 px a frame.
    std::vector<Instance> frame;
    for (int k = 0; k <= f / 10; k++) {
      const float x = 60.f + 20.f * static_cast<float>(f - 10 * k);
      if (x < kFrame.width)
        frame.push_back(box({x, 480.f}));
    }
    const TrackedFrame out = tracker.update(frame, f * kFrameNs, kFrame);
    for (const TrackEvent& e : out.events) {
      if (e.started) {
        EXPECT_TRUE(seen.insert(e.track_id).second) << "id " << e.track_id << " reused";
        EXPECT_GT(e.track_id, last_id);
        last_id = e.track_id;
      }
    }
  }
  EXPECT_EQ(seen.size(), 6u) << "one track per box";
}

TEST(Tracker, BoxRidingOnAnotherKeepsItsOwnId) {
  Tracker tracker;
  std::uint64_t lower = 0, upper = 0;
  for (int f = 0; f < 12; f++) {
    const float x = 200.f + 25.f * f;
    // The upper box lies half on the lower one, turned, and rides with it.
    const TrackedFrame out = tracker.update(
        {box({x, 400.f}), box({x + 50.f, 420.f}, "box", 100.f, 60.f, 30.0)}, f * kFrameNs, kFrame);
    if (f == 0) {
      lower = out.instances[0].track_id;
      upper = out.instances[1].track_id;
      EXPECT_NE(lower, upper);
    }
    EXPECT_EQ(out.instances[0].track_id, lower) << "frame " << f;
    EXPECT_EQ(out.instances[1].track_id, upper) << "frame " << f;
  }
}

TEST(Tracker, HiddenBrieflyKeepsItsIdWhereItsMotionSaysAndIsCarriedForward) {
  Tracker tracker;
  std::uint64_t id = 0;
  for (int f = 0; f < 20; f++) {
    const cv::Point2f c(100.f + 25.f * f, 500.f);
    const bool hidden = f >= 8 && f < 20 - 8; // 4 frames, 133 ms: under the 500 ms timeout.
    const TrackedFrame out = tracker.update(
        hidden ? std::vector<Instance>{} : std::vector<Instance>{box(c)}, f * kFrameNs, kFrame);
    EXPECT_EQ(ended_with(out, TrackEnd::Timeout), 0);
    if (f == 0)
      id = out.instances.at(0).track_id;
    if (!hidden) {
      ASSERT_EQ(out.instances.size(), 1u);
      EXPECT_EQ(out.instances[0].track_id, id) << "frame " << f;
      EXPECT_FALSE(out.instances[0].tracked);
    } else if (f <= 9) { // Carried forward for 70 ms: two frames.
      ASSERT_EQ(out.instances.size(), 1u) << "frame " << f;
      EXPECT_TRUE(out.instances[0].tracked);
      EXPECT_FALSE(out.instances[0].instance.pickable);
      EXPECT_NEAR(out.instances[0].instance.center.x, c.x, 1.0) << "predicted at constant speed";
    } else {
      EXPECT_TRUE(out.instances.empty()) << "frame " << f;
    }
  }
  EXPECT_EQ(tracker.live_tracks(), 1u);
}

namespace {

/// A box 100 x 60 on a belt at 25 px a frame with a smaller `rider` (60 x 40, 40 % of the box)
/// lying on it, both detected for 6 frames, then the box not detected for 12 frames (400 ms,
/// under the 500 ms timeout) while the rider is, moving at `rider_speed` px a frame from then.
/// Returns, per hidden frame, whether the box was reported (carried forward), and checks how.
std::vector<bool> carried_under(float rider_speed) {
  Tracker tracker;
  std::uint64_t id = 0;
  cv::Point2f rider_at(85.f, 505.f); // 10 px right of the box's centre once moved.
  std::vector<bool> reported;
  for (int f = 0; f < 18; f++) {
    const cv::Point2f c(100.f + 25.f * f, 500.f);
    rider_at.x += f < 6 ? 25.f : rider_speed;
    std::vector<Instance> frame = {box(rider_at, "fish", 60.f, 40.f)};
    if (f < 6)
      frame.push_back(box(c));
    const TrackedFrame out = tracker.update(frame, f * kFrameNs, kFrame);
    EXPECT_EQ(ended_with(out, TrackEnd::Timeout), 0);
    if (f < 6) {
      id = out.instances.at(1).track_id;
      continue;
    }
    bool seen = false;
    for (const TrackedInstance& t : out.instances) {
      if (t.instance.model_name != "box")
        continue;
      seen = true;
      EXPECT_EQ(t.track_id, id) << "frame " << f;
      EXPECT_TRUE(t.tracked) << "frame " << f;
      EXPECT_FALSE(t.instance.pickable) << "frame " << f;
      EXPECT_NEAR(t.instance.center.x, c.x, 1.0) << "predicted at constant speed, frame " << f;
    }
    reported.push_back(seen);
  }
  return reported;
}

} // namespace

TEST(Tracker, HiddenUnderANeighbourRidingWithItIsCarriedTillTheTimeout) {
  // The rider covers 40 % of the box: it hides the box, it does not replace it.
  const std::vector<bool> reported = carried_under(25.f);
  EXPECT_EQ(std::count(reported.begin(), reported.end(), true), 12)
      << "the box riding hidden under the rider is reported in each of the 12 frames";
}

TEST(Tracker, HiddenUnderANeighbourNotMovingWithItIsCarriedBriefly) {
  // The rider stopped (taken off by a hand, say): it says nothing of where the box is.
  const std::vector<bool> reported = carried_under(0.f);
  EXPECT_EQ(reported, std::vector<bool>({true, true, false, false, false, false, false, false,
                                         false, false, false, false}))
      << "carried for 70 ms like any missed detection";
}

TEST(Tracker, HiddenLongerThanTheTimeoutEndsAndComesBackUnderANewId) {
  TrackerSettings settings;
  settings.timeout_ms = 200;
  Tracker tracker(settings);
  const std::uint64_t id = tracker.update({box({300.f, 300.f})}, 0, kFrame).instances[0].track_id;
  int vanished = 0;
  for (int f = 1; f <= 8; f++)
    vanished += ended_with(tracker.update({}, f * kFrameNs, kFrame), TrackEnd::Vanished);
  EXPECT_EQ(vanished, 1) << "a still box not seen for 267 ms";
  const TrackedFrame back = tracker.update({box({300.f, 300.f})}, 9 * kFrameNs, kFrame);
  EXPECT_NE(back.instances.at(0).track_id, id);
}

TEST(Tracker, AMovingObjectLostInViewEndsByTimeout) {
  Tracker tracker;
  for (int f = 0; f < 4; f++)
    tracker.update({box({200.f + 10.f * f, 300.f})}, f * kFrameNs, kFrame);
  int timeouts = 0;
  for (int f = 4; f < 25; f++)
    timeouts += ended_with(tracker.update({}, f * kFrameNs, kFrame), TrackEnd::Timeout);
  EXPECT_EQ(timeouts, 1);
  EXPECT_EQ(tracker.live_tracks(), 0u);
}

TEST(Tracker, LeavingTheFrameEndsTheTrackAsLeftView) {
  Tracker tracker;
  int left = 0, frames = 0;
  for (int f = 0; f < 40 && !left; f++, frames++) {
    const float x = 1000.f + 30.f * f;
    // Detection stops once a third of the box is out of the frame.
    std::vector<Instance> frame;
    if (x < kFrame.width - 20)
      frame.push_back(box({x, 300.f}));
    left += ended_with(tracker.update(frame, f * kFrameNs, kFrame), TrackEnd::LeftView);
  }
  EXPECT_EQ(left, 1);
  EXPECT_LE(frames, 12) << "ended as soon as its predicted centre left the frame";
}

TEST(Tracker, PickedFromABinEndsAndTheOthersKeepTheirIds) {
  Tracker tracker;
  const std::vector<Instance> bin = {box({300.f, 300.f}), box({500.f, 320.f}),
                                     box({400.f, 500.f}, "other")};
  const TrackedFrame first = tracker.update(bin, 0, kFrame);
  int vanished = 0;
  for (int f = 1; f < 30; f++) {
    std::vector<Instance> now = bin;
    if (f >= 5)
      now.erase(now.begin() + 1); // Picked.
    const TrackedFrame out = tracker.update(now, f * kFrameNs, kFrame);
    vanished += ended_with(out, TrackEnd::Vanished);
    EXPECT_EQ(id_near(out, {300.f, 300.f}), first.instances[0].track_id);
    EXPECT_EQ(id_near(out, {400.f, 500.f}), first.instances[2].track_id);
  }
  EXPECT_EQ(vanished, 1);
  EXPECT_EQ(tracker.live_tracks(), 2u);
}

TEST(Tracker, AStillObjectNoLongerSeenIsNotCarriedForward) {
  // A pick from a bin: the picked box must not be reported where it was, not even for a frame.
  Tracker tracker;
  const std::vector<Instance> bin = {box({300.f, 300.f}), box({500.f, 320.f})};
  for (int f = 0; f < 5; f++)
    tracker.update(bin, f * kFrameNs, kFrame);
  const TrackedFrame out = tracker.update({bin[0]}, 5 * kFrameNs, kFrame);
  ASSERT_EQ(out.instances.size(), 1u) << "the picked box is reported carried forward";
  EXPECT_FALSE(out.instances[0].tracked);
}

TEST(Tracker, OnlyTheSameModelContinuesATrack) {
  Tracker tracker;
  const std::uint64_t a =
      tracker.update({box({300.f, 300.f}, "a")}, 0, kFrame).instances[0].track_id;
  const TrackedFrame out = tracker.update({box({302.f, 300.f}, "b")}, kFrameNs, kFrame);
  EXPECT_NE(out.instances.at(0).track_id, a);
}

TEST(Tracker, EndModelsNotInEndsOnlyTheRemovedModels) {
  Tracker tracker;
  tracker.update({box({300.f, 300.f}, "a"), box({600.f, 300.f}, "b")}, 0, kFrame);
  const std::vector<TrackEvent> ends = tracker.end_models_not_in({"b"});
  ASSERT_EQ(ends.size(), 1u);
  EXPECT_EQ(ends[0].model, "a");
  EXPECT_EQ(ends[0].reason, TrackEnd::ModelRemoved);
  EXPECT_EQ(tracker.live_tracks(), 1u);
}

TEST(Tracker, TimeGoingBackResetsTheTracksAndIdsGoOn) {
  Tracker tracker;
  const std::uint64_t a =
      tracker.update({box({300.f, 300.f})}, 10 * kFrameNs, kFrame).instances[0].track_id;
  const TrackedFrame out = tracker.update({box({300.f, 300.f})}, 0, kFrame);
  EXPECT_EQ(ended_with(out, TrackEnd::Reset), 1);
  EXPECT_GT(out.instances.at(0).track_id, a);
}

TEST(Tracker, FirstSeenAndFramesSeenFollowTheDetections) {
  Tracker tracker;
  TrackedFrame out;
  for (int f = 3; f < 8; f++)
    out = tracker.update({box({300.f + f, 300.f})}, f * kFrameNs, kFrame);
  EXPECT_EQ(out.instances.at(0).first_seen_ns, 3 * kFrameNs);
  EXPECT_EQ(out.instances[0].frames_seen, 5);
}

TEST(CountLine, ACrossingCountsOncePerTrackAndModel) {
  Tracker tracker;
  tracker.set_count_line(CountLine{{640, 0}, {640, 960}});
  std::map<std::string, int> last;
  int events = 0;
  for (int f = 0; f < 40; f++) {
    const float x = 300.f + 20.f * f;
    const TrackedFrame out =
        tracker.update({box({x, 200.f}, "a"), box({x - 150.f, 500.f}, "a"), box({x, 800.f}, "b")},
                       f * kFrameNs, kFrame);
    for (const CountEvent& c : out.counts) {
      events++;
      last[c.model] = c.count;
      EXPECT_EQ(c.total, events);
    }
  }
  EXPECT_EQ(events, 3);
  EXPECT_EQ(last["a"], 2);
  EXPECT_EQ(last["b"], 1);
}

TEST(CountLine, JitterStopsAndHidingOnTheLineCountOnce) {
  Tracker tracker;
  tracker.set_count_line(CountLine{{640, 0}, {640, 960}});
  int counted = 0;
  int f = 0;
  auto step = [&](std::vector<Instance> frame) {
    counted += static_cast<int>(tracker.update(frame, (f++) * kFrameNs, kFrame).counts.size());
  };
  for (float x = 500.f; x < 640.f; x += 20.f)
    step({box({x, 300.f})});
  for (int k = 0; k < 20; k++) // Stopped on the line, jittering 12 px across it.
    step({box({k % 2 ? 652.f : 628.f, 300.f})});
  for (int k = 0; k < 5; k++) // Hidden on the line.
    step({});
  for (int k = 0; k < 10; k++) // Back, jittering, then on its way.
    step({box({k % 2 ? 650.f : 630.f, 300.f})});
  for (float x = 660.f; x < 900.f; x += 20.f)
    step({box({x, 300.f})});
  EXPECT_EQ(counted, 1);
}

TEST(CountLine, ATrackPassingBesideTheSegmentIsNotCounted) {
  Tracker tracker;
  tracker.set_count_line(CountLine{{640, 0}, {640, 400}});
  int counted = 0;
  for (int f = 0; f < 30; f++)
    counted += static_cast<int>(
        tracker.update({box({400.f + 20.f * f, 700.f})}, f * kFrameNs, kFrame).counts.size());
  EXPECT_EQ(counted, 0);
}

TEST(CountLine, ParsesFourNumbersAndRejectsTheRest) {
  EXPECT_FALSE(parse_count_line("").has_value());
  const std::optional<CountLine> line = parse_count_line("10, 20,30,40.5");
  ASSERT_TRUE(line.has_value());
  EXPECT_EQ(line->a, cv::Point2d(10, 20));
  EXPECT_EQ(line->b, cv::Point2d(30, 40.5));
  EXPECT_THROW(parse_count_line("1,2,3"), Error);
  EXPECT_THROW(parse_count_line("1,2,3,4,5"), Error);
  EXPECT_THROW(parse_count_line("1,2,x,4"), Error);
  EXPECT_THROW(parse_count_line("5,5,5,5"), Error);
}
