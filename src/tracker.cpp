// SPDX-License-Identifier: LGPL-2.1-or-later
// Tracking across frames: association by predicted pose, common motion, track ends, counting.
#include <pickdetect/error.hpp>
#include <pickdetect/occlusion.hpp>
#include <pickdetect/tracker.hpp>

#include "median.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>
#include <tuple>

namespace pickdetect {
namespace {

constexpr double kNsPerSecond = 1e9;
constexpr double kFallbackSizePx = 50.0; ///< Object size of an instance without an outline.

/// Square root of the outline's area: the object's size in pixels.
double object_size(const Instance& instance) {
  if (instance.outline.size() < 3)
    return kFallbackSizePx * std::max(instance.scale, 0.1);
  const double area = std::abs(cv::contourArea(instance.outline));
  return area > 1.0 ? std::sqrt(area) : kFallbackSizePx;
}

std::vector<cv::Point2f> shifted(const std::vector<cv::Point2f>& points, cv::Point2d by) {
  std::vector<cv::Point2f> out = points;
  for (cv::Point2f& p : out)
    p += cv::Point2f(static_cast<float>(by.x), static_cast<float>(by.y));
  return out;
}

Instance moved(const Instance& instance, cv::Point2d by) {
  Instance out = instance;
  const cv::Point2f d(static_cast<float>(by.x), static_cast<float>(by.y));
  out.center += d;
  out.grasp += d;
  out.points = shifted(instance.points, by);
  out.outline = shifted(instance.outline, by);
  out.support = shifted(instance.support, by);
  out.homography = cv::Matx33d(1, 0, by.x, 0, 1, by.y, 0, 0, 1) * instance.homography;
  return out;
}

/// Intersection over union of two outlines taken as convex, from the area they share and
/// their own areas (0 when they share none).
double hull_iou(double shared, double area_a, double area_b) {
  return shared > 0.0 ? shared / (area_a + area_b - shared) : 0.0;
}

/// Smallest difference between two angles in degrees, in [0, 180].
double angle_difference(double a, double b) {
  double d = std::fmod(std::abs(a - b), 360.0);
  return d > 180.0 ? 360.0 - d : d;
}

/// How far a velocity may be from `v` and still move together with it (px/s).
double together_tolerance(const TrackerSettings& s, cv::Point2d v) {
  return std::max(s.common_motion_slack, s.common_motion_tolerance * cv::norm(v));
}

bool inside(cv::Point2d p, cv::Size frame) {
  return p.x >= 0.0 && p.y >= 0.0 && p.x < frame.width && p.y < frame.height;
}

} // namespace

std::optional<CountLine> parse_count_line(const std::string& text) {
  const bool blank = std::all_of(
      text.begin(), text.end(), [](char c) { return std::isspace(static_cast<unsigned char>(c)); });
  if (blank)
    return std::nullopt;
  std::string spaced = text;
  std::replace(spaced.begin(), spaced.end(), ',', ' ');
  std::istringstream in(spaced);
  double v[4];
  for (double& x : v) {
    if (!(in >> x) || !std::isfinite(x))
      throw Error("count line \"" + text + "\": expected four numbers x1,y1,x2,y2 in pixels");
  }
  std::string rest;
  if (in >> rest)
    throw Error("count line \"" + text + "\": expected four numbers x1,y1,x2,y2, got more");
  CountLine line{{v[0], v[1]}, {v[2], v[3]}};
  if (cv::norm(line.b - line.a) < 1e-9)
    throw Error("count line \"" + text + "\": both ends are the same point");
  return line;
}

const char* track_end_name(TrackEnd reason) {
  switch (reason) {
  case TrackEnd::LeftView:
    return "left-view";
  case TrackEnd::Vanished:
    return "vanished";
  case TrackEnd::Timeout:
    return "timeout";
  case TrackEnd::ModelRemoved:
    return "model-removed";
  case TrackEnd::Reset:
    break;
  }
  return "reset";
}

Tracker::Tracker(TrackerSettings settings) : settings_(settings) {}

void Tracker::set_count_line(const std::optional<CountLine>& line) {
  line_ = line;
  counts_.clear();
  total_count_ = 0;
  for (Track& t : tracks_) {
    t.side = 0;
    t.counted = false;
  }
}

cv::Point2d Tracker::predicted_offset(const Track& track, std::int64_t time_ns) const {
  const double dt = static_cast<double>(time_ns - track.last_seen_ns) / kNsPerSecond;
  if (track.has_velocity)
    return track.velocity * dt;
  if (motion_.found)
    return motion_.velocity * dt;
  return {0.0, 0.0};
}

bool Tracker::moves_with(const Track& a, const Track& b) const {
  if (!a.has_velocity || !b.has_velocity)
    return false;
  return cv::norm(a.velocity - b.velocity) <= together_tolerance(settings_, b.velocity);
}

TrackEnd Tracker::end_reason(const Track& track, cv::Point2d predicted, cv::Size frame) const {
  const double size = object_size(track.last);
  const bool near_edge = predicted.x < size / 2 || predicted.y < size / 2 ||
                         predicted.x > frame.width - size / 2 ||
                         predicted.y > frame.height - size / 2;
  if (!inside(predicted, frame) || near_edge)
    return TrackEnd::LeftView;
  // Still: it would have moved less than a tenth of its size over the timeout.
  const double speed = track.has_velocity ? cv::norm(track.velocity) : 0.0;
  return speed * settings_.timeout_ms / 1000.0 < 0.1 * size ? TrackEnd::Vanished
                                                            : TrackEnd::Timeout;
}

TrackEvent Tracker::ended(const Track& track, TrackEnd reason) const {
  TrackEvent e;
  e.started = false;
  e.track_id = track.id;
  e.model = track.last.model_name;
  e.first_seen_ns = track.first_seen_ns;
  e.last_seen_ns = track.last_seen_ns;
  e.frames_seen = track.frames_seen;
  e.last = track.last;
  e.reason = reason;
  return e;
}

void Tracker::update_count(Track& track, std::vector<CountEvent>& counts) {
  if (!line_)
    return;
  const cv::Point2d a = line_->a, b = line_->b, c(track.last.center.x, track.last.center.y);
  const cv::Point2d ab = b - a;
  const double length = cv::norm(ab);
  const double signed_distance = (ab.x * (c.y - a.y) - ab.y * (c.x - a.x)) / length;
  const double hysteresis = settings_.count_hysteresis * object_size(track.last);
  if (std::abs(signed_distance) <= hysteresis)
    return; // On the line: neither side yet.
  const int side = signed_distance > 0 ? 1 : -1;
  const double along = ((c - a).dot(ab)) / (length * length); // 0 at a, 1 at b.
  if (track.side != 0 && side != track.side && !track.counted && along >= 0.0 && along <= 1.0) {
    track.counted = true;
    CountEvent e;
    e.track_id = track.id;
    e.model = track.last.model_name;
    e.count = ++counts_[e.model];
    e.total = ++total_count_;
    counts.push_back(e);
  }
  track.side = side;
}

TrackedFrame Tracker::update(const std::vector<Instance>& detected, std::int64_t time_ns,
                             cv::Size frame) {
  TrackedFrame out;
  if (has_time_ && time_ns < last_time_ns_)
    out.events = end_all(TrackEnd::Reset);
  has_time_ = true;
  last_time_ns_ = time_ns;

  // Tracks unseen for longer than the timeout end before they could take a detection.
  std::vector<TrackEvent> expired;
  {
    std::vector<Track> live;
    for (const Track& track : tracks_) {
      if (static_cast<double>(time_ns - track.last_seen_ns) / 1e6 <= settings_.timeout_ms) {
        live.push_back(track);
        continue;
      }
      const cv::Point2d predicted =
          cv::Point2d(track.last.center.x, track.last.center.y) + predicted_offset(track, time_ns);
      expired.push_back(ended(track, end_reason(track, predicted, frame)));
    }
    tracks_ = std::move(live);
  }

  // Each detection's area (its outline taken as convex), for the overlaps below.
  std::vector<double> detected_area(detected.size());
  for (size_t d = 0; d < detected.size(); d++)
    detected_area[d] = hull_area(detected[d].outline);
  // Candidate pairs (cost, track, detection), gated, of the same model.
  std::vector<std::tuple<double, size_t, size_t>> pairs;
  std::vector<cv::Point2d> offsets(tracks_.size());
  for (size_t t = 0; t < tracks_.size(); t++) {
    const Track& track = tracks_[t];
    offsets[t] = predicted_offset(track, time_ns);
    const cv::Point2d predicted =
        cv::Point2d(track.last.center.x, track.last.center.y) + offsets[t];
    const double size = object_size(track.last);
    // A track that has no motion of its own yet, on a belt whose motion is not known yet,
    // may have moved far: its first step is only gated loosely.
    const double gate =
        !track.has_velocity && !motion_.found
            ? settings_.new_track_gate
            : std::min(settings_.max_gate, settings_.gate + settings_.gate_growth * track.missed);
    const cv::Point2d last(track.last.center.x, track.last.center.y);
    const std::vector<cv::Point2f> predicted_outline = shifted(track.last.outline, offsets[t]);
    const double predicted_area = hull_area(predicted_outline);
    for (size_t d = 0; d < detected.size(); d++) {
      const Instance& det = detected[d];
      if (det.model_name != track.last.model_name)
        continue;
      // From the predicted centre, or (an object jittering or stopping) from the last one.
      const cv::Point2d at(det.center.x, det.center.y);
      const double distance = std::min(cv::norm(at - predicted) / size,
                                       cv::norm(at - last) / size + settings_.last_pose_penalty);
      if (distance > gate)
        continue;
      const double cost = distance +
                          0.3 * (1.0 - hull_iou(overlap_area(predicted_outline, det.outline),
                                                predicted_area, detected_area[d])) +
                          0.2 * angle_difference(det.angle, track.last.angle) / 90.0;
      pairs.emplace_back(cost, t, d);
    }
  }
  std::sort(pairs.begin(), pairs.end());
  std::vector<int> track_of(detected.size(), -1);
  std::vector<bool> track_taken(tracks_.size(), false);
  for (const auto& [cost, t, d] : pairs) {
    (void)cost;
    if (track_taken[t] || track_of[d] >= 0)
      continue;
    track_taken[t] = true;
    track_of[d] = static_cast<int>(t);
  }

  // Matched tracks take their detection; unmatched detections start tracks.
  std::vector<size_t> detection_track(detected.size());
  std::vector<Track> started;
  for (size_t d = 0; d < detected.size(); d++) {
    const Instance& det = detected[d];
    if (track_of[d] >= 0) {
      Track& track = tracks_[static_cast<size_t>(track_of[d])];
      const double dt = static_cast<double>(time_ns - track.last_seen_ns) / kNsPerSecond;
      if (dt > 0.0) {
        const cv::Point2d measured =
            cv::Point2d(det.center.x - track.last.center.x, det.center.y - track.last.center.y) /
            dt;
        track.velocity = track.has_velocity
                             ? settings_.velocity_smoothing * measured +
                                   (1.0 - settings_.velocity_smoothing) * track.velocity
                             : measured;
        track.has_velocity = true;
      }
      track.last = det;
      track.last_seen_ns = time_ns;
      track.frames_seen++;
      track.missed = 0;
      detection_track[d] = static_cast<size_t>(track_of[d]);
    } else {
      Track track;
      track.id = next_id_++;
      track.last = det;
      track.first_seen_ns = track.last_seen_ns = time_ns;
      track.frames_seen = 1;
      detection_track[d] = tracks_.size() + started.size();
      started.push_back(track);
    }
  }
  const size_t old_count = tracks_.size();
  for (Track& t : started)
    tracks_.push_back(t);

  for (size_t d = 0; d < detected.size(); d++)
    update_count(tracks_[detection_track[d]], out.counts);

  // The common motion of the tracks seen in this frame with a velocity of their own.
  std::vector<double> vx, vy;
  std::vector<cv::Point2d> velocities;
  for (size_t t = 0; t < old_count; t++) {
    if (track_taken[t] && tracks_[t].has_velocity && tracks_[t].frames_seen >= 3) {
      velocities.push_back(tracks_[t].velocity);
      vx.push_back(tracks_[t].velocity.x);
      vy.push_back(tracks_[t].velocity.y);
    }
  }
  CommonMotion motion;
  if (static_cast<int>(velocities.size()) >= settings_.common_motion_min_tracks) {
    const cv::Point2d m(detail::median(vx), detail::median(vy));
    const double tolerance = together_tolerance(settings_, m);
    cv::Point2d sum;
    int n = 0;
    for (const cv::Point2d& v : velocities) {
      if (cv::norm(v - m) <= tolerance) {
        sum += v;
        n++;
      }
    }
    if (n >= settings_.common_motion_min_tracks && 2 * n > static_cast<int>(velocities.size())) {
      motion.found = true;
      motion.velocity = sum / n;
      motion.tracks = n;
    }
  }
  if (motion.found)
    motion_ = motion;
  else if (velocities.size() >= 2)
    motion_ = CommonMotion(); // Tracks seen, no longer together: forget the old motion.
  out.motion = motion_;

  // The frame's instances in the detector's order.
  for (size_t d = 0; d < detected.size(); d++) {
    const Track& track = tracks_[detection_track[d]];
    TrackedInstance ti;
    ti.instance = detected[d];
    ti.track_id = track.id;
    ti.first_seen_ns = track.first_seen_ns;
    ti.frames_seen = track.frames_seen;
    ti.velocity =
        track.has_velocity ? track.velocity : (motion_.found ? motion_.velocity : cv::Point2d());
    out.instances.push_back(ti);
  }

  // Unseen tracks: carried forward, or ended.
  std::vector<Track> kept;
  std::vector<TrackEvent> ends;
  for (size_t t = 0; t < tracks_.size(); t++) {
    Track& track = tracks_[t];
    if (t >= old_count || track_taken[t]) {
      kept.push_back(track);
      continue;
    }
    track.missed++;
    const cv::Point2d offset = offsets[t];
    const cv::Point2d predicted = cv::Point2d(track.last.center.x, track.last.center.y) + offset;
    const double unseen_ms = static_cast<double>(time_ns - track.last_seen_ns) / 1e6;
    if (!inside(predicted, frame)) {
      ends.push_back(ended(track, TrackEnd::LeftView));
      continue;
    }
    if (unseen_ms > settings_.timeout_ms) {
      ends.push_back(ended(track, end_reason(track, predicted, frame)));
      continue;
    }
    // Carried forward while time goes on, unless a new detection (of any model) now lies
    // where it is predicted: that one replaces it. A neighbour tracked beside it since it was
    // last seen replaces nothing; when it moves with it and covers enough of where it is
    // predicted, this one rides hidden under it and is carried till the timeout.
    bool replaced = false, under_cover = false;
    const std::vector<cv::Point2f> predicted_outline = shifted(track.last.outline, offset);
    const double predicted_area = hull_area(predicted_outline);
    for (size_t d = 0; d < detected.size(); d++) {
      const double shared = overlap_area(predicted_outline, detected[d].outline);
      if (shared <= 0.0)
        continue;
      const int u = track_of[d];
      if (u < 0 || tracks_[static_cast<size_t>(u)].first_seen_ns > track.last_seen_ns) {
        replaced = replaced || hull_iou(shared, predicted_area, detected_area[d]) > 0.3;
        continue;
      }
      under_cover = under_cover || (moves_with(tracks_[static_cast<size_t>(u)], track) &&
                                    shared >= settings_.carry_under_cover_share * predicted_area);
    }
    const bool moving =
        track.has_velocity &&
        cv::norm(track.velocity) >= settings_.carry_forward_min_speed * object_size(track.last);
    if (unseen_ms > 0.0 && (unseen_ms <= settings_.carry_forward_ms || under_cover) && !replaced &&
        moving) {
      TrackedInstance ti;
      ti.instance = moved(track.last, offset);
      ti.instance.pickable = false;
      ti.instance.pick_order = 0;
      ti.track_id = track.id;
      ti.first_seen_ns = track.first_seen_ns;
      ti.frames_seen = track.frames_seen;
      ti.velocity = track.velocity;
      ti.tracked = true;
      out.instances.push_back(ti);
    }
    kept.push_back(track);
  }
  tracks_ = std::move(kept);

  out.events.insert(out.events.end(), expired.begin(), expired.end());
  out.events.insert(out.events.end(), ends.begin(), ends.end());
  for (const Track& t : started) {
    TrackEvent e;
    e.started = true;
    e.track_id = t.id;
    e.model = t.last.model_name;
    e.first_seen_ns = e.last_seen_ns = t.first_seen_ns;
    e.frames_seen = 1;
    e.last = t.last;
    out.events.push_back(e);
  }
  return out;
}

std::vector<TrackEvent> Tracker::end_all(TrackEnd reason) {
  std::vector<TrackEvent> events;
  for (const Track& t : tracks_)
    events.push_back(ended(t, reason));
  tracks_.clear();
  motion_ = CommonMotion();
  has_time_ = false;
  return events;
}

std::vector<TrackEvent> Tracker::end_models_not_in(const std::vector<std::string>& models) {
  std::vector<TrackEvent> events;
  std::vector<Track> kept;
  for (const Track& t : tracks_) {
    if (std::find(models.begin(), models.end(), t.last.model_name) == models.end())
      events.push_back(ended(t, TrackEnd::ModelRemoved));
    else
      kept.push_back(t);
  }
  tracks_ = std::move(kept);
  return events;
}

} // namespace pickdetect
