// SPDX-License-Identifier: LGPL-2.1-or-later
// Tracking across the frames of one video: each instance gets the identity of its physical
// object (a track id, never reused), its velocity, how long it has been seen; instances that
// move together give the belt's motion; tracks crossing a count line are counted once.
#pragma once

#include <pickdetect/detector.hpp>

#include <opencv2/core.hpp>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace pickdetect {

/// The numbers of the association, with their units. Defaults are the element's.
struct TrackerSettings {
  /// A track not detected for longer than this (milliseconds) ends; until then it keeps its id
  /// and is found again where its motion says it should be.
  double timeout_ms = 500.0;
  /// An unseen track is still reported (carried forward, `tracked`) for this long, in ms...
  double carry_forward_ms = 70.0;
  /// ...when it moves at least this fast, in object sizes per second: a moving object missed by
  /// one frame's detection is where its motion says; a still one that is not seen any more was
  /// most likely taken away (a pick from a bin), and is not reported.
  double carry_forward_min_speed = 0.5;
  /// ...and until the timeout while it rides under another: an instance tracked beside it since
  /// it was last seen, moving with it (see `common_motion_tolerance`), covers at least this
  /// share of where it is predicted (its hull's area). Such a neighbour does not replace it.
  double carry_under_cover_share = 0.25;
  /// A detection may continue a track when its centre lies within this distance of the track's
  /// predicted centre, in object sizes (square root of the outline's area). Grows by
  /// `gate_growth` per frame the track went unseen, up to `max_gate`.
  double gate = 0.5;
  double gate_growth = 0.25;
  double max_gate = 1.5;
  /// The gate of a track's first step when neither it nor the belt has a known motion.
  double new_track_gate = 2.0;
  /// A detection may also be near the track's last centre (it stopped, or jitters): that
  /// distance counts this much more, in object sizes.
  double last_pose_penalty = 0.1;
  /// Weight of the velocity measured on each new detection against the track's estimate (0-1].
  double velocity_smoothing = 0.5;
  /// Instances move together when their velocities differ from the median by at most this
  /// share of its length, or `common_motion_slack` px/s, whichever is larger.
  double common_motion_tolerance = 0.15;
  double common_motion_slack = 30.0;
  int common_motion_min_tracks = 2; ///< Fewest tracks that make a common motion.
  /// A centre nearer the count line than this share of the object size is on neither side.
  double count_hysteresis = 0.1;
};

/// A segment in frame pixels that counts the tracks crossing it.
struct CountLine {
  cv::Point2d a, b;
};

/// Parses "x1,y1,x2,y2" (pixels); nullopt for an empty string; throws Error when malformed or
/// when both ends are the same point.
PICKDETECT_API std::optional<CountLine> parse_count_line(const std::string& text);

/// Why a track ended.
enum class TrackEnd {
  LeftView, ///< Its motion carried it out of the frame.
  Vanished, ///< A still object no longer seen where it was (taken away, picked).
  Timeout,  ///< A moving object not seen again where its motion says, within the timeout.
  Reset,    ///< Ended by the stream (flush, seek, new segment, size change, tracking turned off).
  ModelRemoved, ///< Its model left the model set.
};
/// "left-view", "vanished", "timeout", "reset", "model-removed".
PICKDETECT_API const char* track_end_name(TrackEnd reason);

/// One instance of a frame with its track.
struct TrackedInstance {
  Instance instance;
  std::uint64_t track_id = 0;     ///< Unique, never reused; 1 is the first.
  std::int64_t first_seen_ns = 0; ///< Time of the first frame that detected it.
  int frames_seen = 0;            ///< Frames that detected it, this one included.
  cv::Point2d velocity;           ///< Pixels per second.
  /// Carried forward from earlier frames (its pose predicted), not detected in this one; such
  /// an instance is never pickable.
  bool tracked = false;
};

/// A track starting or ending.
struct TrackEvent {
  bool started = true; ///< False: it ended, for `reason`.
  std::uint64_t track_id = 0;
  std::string model;
  std::int64_t first_seen_ns = 0;
  std::int64_t last_seen_ns = 0; ///< The last frame that detected it.
  int frames_seen = 0;
  Instance last;                     ///< The last detected pose.
  TrackEnd reason = TrackEnd::Reset; ///< Ended tracks only.
};

/// A track crossing the count line, once per track.
struct CountEvent {
  std::uint64_t track_id = 0;
  std::string model;
  int count = 0; ///< Tracks of this model counted so far, this one included.
  int total = 0; ///< Tracks of all models counted so far.
};

/// The motion shared by the instances that move together (a belt), when there is one.
struct CommonMotion {
  bool found = false;
  cv::Point2d velocity; ///< Pixels per second.
  int tracks = 0;       ///< Tracks that move with it.
};

struct TrackedFrame {
  /// The frame's detections in their order, then the tracks carried forward.
  std::vector<TrackedInstance> instances;
  std::vector<TrackEvent> events; ///< Ends first, then starts.
  std::vector<CountEvent> counts;
  CommonMotion motion;
};

/// Follows the instances of one stream, frame after frame. Association: each live track's
/// centre is predicted at constant velocity (a new track: with the common motion); detections
/// of the same model are paired with tracks greedily by cost (predicted centre distance in
/// object sizes, plus outline overlap and angle), within a gate, so that a fast belt with no
/// overlap between frames keeps its ids.
class PICKDETECT_API Tracker {
public:
  explicit Tracker(TrackerSettings settings = TrackerSettings());

  /// Settings for the next frames; the tracks are kept.
  void set_settings(const TrackerSettings& settings) { settings_ = settings; }
  const TrackerSettings& settings() const { return settings_; }
  /// A new line (or none) resets the counts and which tracks have been counted.
  void set_count_line(const std::optional<CountLine>& line);

  /// The instances detected in the frame of time `time_ns` (non-decreasing; a frame at an
  /// earlier time than the last one resets the tracks first) and size `frame`.
  TrackedFrame update(const std::vector<Instance>& detected, std::int64_t time_ns, cv::Size frame);

  /// Ends every track, for `reason`; ids go on counting from where they were.
  std::vector<TrackEvent> end_all(TrackEnd reason);
  /// Ends the tracks whose model is not among `models` (TrackEnd::ModelRemoved).
  std::vector<TrackEvent> end_models_not_in(const std::vector<std::string>& models);

  size_t live_tracks() const { return tracks_.size(); }
  const std::map<std::string, int>& counts() const { return counts_; }

private:
  struct Track {
    std::uint64_t id = 0;
    Instance last; ///< Last detected pose.
    std::int64_t first_seen_ns = 0, last_seen_ns = 0;
    int frames_seen = 0;
    int missed = 0; ///< Frames since last detected.
    cv::Point2d velocity;
    bool has_velocity = false;
    int side = 0; ///< Side of the count line last seen on: -1, +1, 0 unknown.
    bool counted = false;
  };

  cv::Point2d predicted_offset(const Track& track, std::int64_t time_ns) const;
  /// Whether two tracks move together (common_motion_tolerance, of `b`'s speed).
  bool moves_with(const Track& a, const Track& b) const;
  TrackEvent ended(const Track& track, TrackEnd reason) const;
  TrackEnd end_reason(const Track& track, cv::Point2d predicted, cv::Size frame) const;
  void update_count(Track& track, std::vector<CountEvent>& counts);

  TrackerSettings settings_;
  std::optional<CountLine> line_;
  std::vector<Track> tracks_;
  std::uint64_t next_id_ = 1;
  std::int64_t last_time_ns_ = 0;
  bool has_time_ = false;
  CommonMotion motion_;
  std::map<std::string, int> counts_;
  int total_count_ = 0;
};

} // namespace pickdetect
