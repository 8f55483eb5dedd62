// SPDX-License-Identifier: LGPL-2.1-or-later
// Detection on the frames of one stream that reuses what the last frame found: SIFT runs only
// where the picture changed, the other keypoints and their matches are carried over, and a
// frame in which nothing changed gets the last frame's detection (issue 18, item 5).
#pragma once

#include <pickdetect/export.hpp>

#include <pickdetect/detector.hpp>

#include <opencv2/core.hpp>

#include <optional>
#include <vector>

namespace pickdetect {

/// What one frame's detection took over from the frames before it.
struct ReuseStats {
  int extracted = 0; ///< Keypoints SIFT extracted in this frame.
  int reused = 0;    ///< Keypoints (with their matches) carried over from the frames before.
  /// Share of the frame's pixels SIFT ran on: 1 for a whole extraction, 0 for a frame in which
  /// nothing changed.
  double extracted_share = 1.0;
  bool whole = true;      ///< The frame was extracted and matched whole.
  bool unchanged = false; ///< Nothing changed: the last frame's detection, as it was.
};

/// Detects on consecutive frames of one stream (one thread). A frame is compared with the last
/// on a grid of 8x8-pixel blocks (block means, so the sensor's noise stays below the
/// threshold). An instance of the last frame under changed blocks that moved rigidly (a belt;
/// ECC on its outline's pixels, at least 0.95 correlation) carries its keypoints and their
/// matches along by the sub-pixel shift measured; the blocks it left and came to are
/// explained. When the instances moved together (a belt), the motion blur they carry is
/// measured on one of them (its model's picture blurred along the motion against the frame)
/// and undone (Wiener deconvolution along the motion) on every frame SIFT runs on after: a
/// whole frame and the crops; the checks of the frame's pixels (what lies on an instance) then
/// compare the models' pictures blurred the same way (Settings::motion_blur_x, motion_blur_y).
/// Around the changed blocks nothing explains (objects coming into view, taken away, turned), SIFT
/// runs on crops wide enough that the keypoints it gives there are those of the whole frame, and
/// every keypoint whose descriptor reaches into such a block is replaced. An instance coming into
/// view across the frame's edge rides in with the keypoints it had; each time 0.4 more of its box
/// is in view than when they were extracted, what came into view since, and its keypoints whose
/// windows the edge cut, are extracted again. An instance riding out across the frame's edge is
/// followed out, also once it is no longer found and through a whole frame: what is left of it in
/// view moves by its motion (by its last step once ECC no longer follows it, by the belt's after a
/// whole frame) instead of being extracted again each frame. The matching runs on the new keypoints
/// only; voting, poses, look-alikes and occlusion run on all of them, on the frame's pixels. A
/// frame in which nothing changed gets the last detection. Every `whole_interval`-th frame, a frame
/// of another size, contrast threshold, detector or settings, ORB and detection-scale < 1 are
/// detected whole, exactly as Detector::detect does.
class PICKDETECT_API FeatureReuse {
public:
  /// `whole_interval`: every so many frames one is detected whole (1: every frame, no reuse).
  explicit FeatureReuse(int whole_interval = 15) : whole_interval_(whole_interval) {}

  /// detector.detect(grey, colour, settings) reusing what the last frames found (`colour`: the
  /// same frame in BGR, or empty; see Detector::detect). Timings as detect's.
  Detection detect(const Detector& detector, const cv::Mat& grey, const Settings& settings,
                   const cv::Mat& colour = cv::Mat());

  /// Forgets the last frames: the next one is detected whole.
  void reset();
  void set_whole_interval(int frames);
  int whole_interval() const { return whole_interval_; }
  /// What the last call reused.
  const ReuseStats& last() const { return last_; }

private:
  /// `refresh`: the whole frame every whole_interval frames of a run (what is left in view of
  /// objects leaving the frame rides on out), not a new start.
  Detection detect_whole(const Detector& detector, const cv::Mat& grey, const cv::Mat& colour,
                         const Settings& settings, double contrast, bool refresh = false);
  /// The motion blur a frame carries along the belt (frame pixels), when both are known.
  cv::Point2f belt_blur() const;
  /// The belt's step and the exposure, from the instances that moved by `shifts` (each with
  /// its pose in this frame) on `grey`.
  void measure_belt(const Detector& detector, const cv::Mat& grey,
                    const std::vector<std::pair<const Instance*, cv::Point2f>>& shifts);
  /// Whether `grey` goes on the run of the last frame: same detector, size and settings, about
  /// the same contrast threshold.
  bool same_run(const Detector& detector, const cv::Mat& grey, const Settings& settings,
                double contrast) const;

  int whole_interval_;
  int since_whole_ = 0;
  const Detector* detector_ = nullptr;
  Settings settings_;
  double contrast_ = 0.0;
  cv::Size size_;
  cv::Mat reference_;  ///< Block means of the last frame (CV_32F).
  cv::Mat last_grey_;  ///< The last frame.
  cv::Mat whole_grey_; ///< The last frame detected whole.
  Features features_;
  std::vector<Match> matches_;
  Detection detection_;
  /// How an instance of detection_ moved: from the frame before (unknown after a whole one),
  /// and since the whole frame, when it was followed from there.
  struct Motion {
    std::optional<cv::Point2f> step;
    std::optional<cv::Point2f> since_whole;
    /// How far it moved since its keypoints at the frame's edge were last extracted.
    cv::Point2f since_edge;
  };
  std::vector<Motion> motions_;
  /// What is left in view of the last frame's instances leaving the frame that were not found
  /// again (too little of them in view), with their motions: followed out of the frame, never
  /// reported.
  std::vector<Instance> leaving_;
  std::vector<Motion> leaving_motions_;
  /// The belt's motion in the last frame (frame pixels), when the instances that moved there
  /// moved together.
  std::optional<cv::Point2f> belt_step_;
  /// The shutter's share of the frame time: the motion blur's length over the belt's step,
  /// measured on the instances the belt carries (once after each whole frame).
  std::optional<double> exposure_;
  ReuseStats last_;
};

} // namespace pickdetect
