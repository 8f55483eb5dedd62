// SPDX-License-Identifier: LGPL-2.1-or-later
// Detection that reuses the last frame's keypoints and matches where the picture did not change.
#include <pickdetect/feature_reuse.hpp>

#include "median.hpp"
#include "motion_blur.hpp"
#include "stopwatch.hpp"

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include <algorithm>
#include <cmath>
#include <optional>

namespace pickdetect {
namespace {

/// The frame is compared on blocks of this many pixels a side (their mean grey).
constexpr int kBlock = 8;
/// A block whose mean grey moved by more than this many levels changed. The mean of 64 pixels
/// carries an eighth of the sensor noise (a sigma of 5 levels per pixel: 0.9 levels between two
/// frames), far below; an object moving over the block changes it by tens of levels.
constexpr float kChangeLevels = 4.0f;
/// SIFT's descriptor window reaches 3 * sigma * sqrt(2) * (4 + 1) / 2 from the keypoint, with
/// sigma half the keypoint's size: 5.3 sizes; the blur that found the extremum and the
/// orientation window lie within that, plus this many pixels.
constexpr double kReachPerSize = 5.3;
constexpr double kReachSlack = 12.0;
/// Crops reach this far around the changed blocks: keypoints reaching that far or less (size
/// up to 15.8 px) come out of the crop as they would out of the whole frame. Bigger ones that
/// reach into a change are left out until the next whole frame.
constexpr int kCropReach = 96;
/// Crops start on multiples of this, so that SIFT's octaves (each one every other pixel of the
/// last) sample the same pixels as on the whole frame down to a scale of 32.
constexpr int kCropAlign = 32;
/// The exposure's contrast threshold may drift by this share before the frame is extracted
/// whole (the noise moves the frame's grey percentiles by a level now and then).
constexpr double kContrastDrift = 0.02;

using detail::Clock;
using detail::median;
using detail::ms_since;

double reach(const cv::KeyPoint& k) {
  return kReachPerSize * k.size + kReachSlack;
}

/// Block means of the frame (CV_32F, one per kBlock x kBlock pixels, the last ones partial).
cv::Mat block_means(const cv::Mat& grey) {
  cv::Mat small, out;
  cv::resize(grey, small,
             cv::Size((grey.cols + kBlock - 1) / kBlock, (grey.rows + kBlock - 1) / kBlock), 0, 0,
             cv::INTER_AREA);
  small.convertTo(out, CV_32F);
  return out;
}

/// The crops covering every block within kCropReach of a changed block, widened by kCropReach,
/// aligned and merged until none overlap.
std::vector<cv::Rect> crops_around(const cv::Mat& changed, const cv::Size& frame, cv::Mat& zone) {
  const int grow = (kCropReach + kBlock - 1) / kBlock + 1;
  cv::dilate(changed, zone,
             cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * grow + 1, 2 * grow + 1)));
  cv::Mat labels, boxes, centres;
  const int n = cv::connectedComponentsWithStats(zone, labels, boxes, centres, 8, CV_32S);
  std::vector<cv::Rect> crops;
  const cv::Rect whole(cv::Point(0, 0), frame);
  for (int i = 1; i < n; ++i) {
    cv::Rect r(boxes.at<int>(i, cv::CC_STAT_LEFT) * kBlock - kCropReach,
               boxes.at<int>(i, cv::CC_STAT_TOP) * kBlock - kCropReach,
               boxes.at<int>(i, cv::CC_STAT_WIDTH) * kBlock + 2 * kCropReach,
               boxes.at<int>(i, cv::CC_STAT_HEIGHT) * kBlock + 2 * kCropReach);
    const int x0 = std::max(0, r.x / kCropAlign * kCropAlign);
    const int y0 = std::max(0, r.y / kCropAlign * kCropAlign);
    crops.push_back(cv::Rect(cv::Point(x0, y0), r.br()) & whole);
  }
  for (bool merged = true; merged;) {
    merged = false;
    for (size_t i = 0; i < crops.size() && !merged; ++i)
      for (size_t j = i + 1; j < crops.size() && !merged; ++j)
        if ((crops[i] & crops[j]).area() > 0) {
          crops[i] |= crops[j];
          crops.erase(crops.begin() + static_cast<std::ptrdiff_t>(j));
          merged = true;
        }
  }
  return crops;
}

/// Whether a keypoint's whole support lies inside the crop (or runs off the frame's own edge
/// there, as it would on the whole frame).
bool supported_in(const cv::KeyPoint& k, const cv::Rect& crop, const cv::Size& frame) {
  const double r = reach(k);
  return (crop.x == 0 || k.pt.x - r >= crop.x) && (crop.y == 0 || k.pt.y - r >= crop.y) &&
         (crop.br().x == frame.width || k.pt.x + r <= crop.br().x) &&
         (crop.br().y == frame.height || k.pt.y + r <= crop.br().y);
}

/// An instance of the last frame found again in this one, moved by `shift` (frame pixels).
struct Moved {
  const Instance* instance = nullptr;
  cv::Point2f shift;
  cv::Rect before, after; ///< Its outline's box in the last frame and in this one.
  /// How far it moved since the whole frame, when it was followed from there.
  std::optional<cv::Point2f> since_whole;
  /// How far it moved since its keypoints at the frame's edge were extracted.
  cv::Point2f since_edge;
  /// Whether what came into view of it since then is extracted in this frame.
  bool renew = false;
};

/// ECC over the instance's own pixels (its outline, the belt under it left out) must agree this
/// well for the instance to count as moved rigidly; else its region is extracted again.
constexpr double kLeastCorrelation = 0.95;
/// The search reaches this far beyond the instance's box, in pixels (a belt's frame step and
/// more); the phase correlation that starts ECC finds shifts up to about a third of the box.
constexpr int kSearchMargin = 48;
/// Started from its last step, the search reaches this much farther.
constexpr int kPredictedMargin = 8;
/// A moved instance is this frame's instance of its model whose centre lies nearest where it
/// moved to, within this share of the box's diagonal.
constexpr double kSameInstanceShare = 0.1;
/// ECC follows an instance on at most this many pixels a side of the middle of its box.
constexpr int kEccSide = 128;
/// A frame in which more than this share of the blocks changed is detected whole: following
/// its instances would cost more than it saves (unrelated pictures, a camera that moved).
constexpr double kMostChanged = 0.5;
/// Keypoints this close outside an instance's outline (pixels) ride with it.
constexpr double kOutlineSlack = 4.0;
/// An instance is followed by its motion while this share of its box is in the frame.
constexpr double kLeastInFrame = 0.3;
/// An instance coming into view across the frame's edge has what came into view extracted
/// (and its keypoints whose windows the edge cut) once this share more of its box is in view.
constexpr double kMoreInView = 0.4;
/// The moved instances move together (a belt) when each one's step lies within this share of
/// their median step (or kBeltAgreePx, whichever is more) of it.
constexpr double kBeltAgreeShare = 0.15;
constexpr double kBeltAgreePx = 1.0;
/// A belt's step is at least this long (pixels a frame); slower, its blur is too short to undo.
constexpr double kLeastBeltStep = 2.0;
/// The blur is measured on at most this many of the instances the belt carries.
constexpr size_t kBlurMeasured = 3;

cv::Rect box_of(const std::vector<cv::Point2f>& outline) {
  return cv::boundingRect(outline);
}

/// The shift of the pixels inside `outline` (in `from`'s pixels) from `from` to `to`, by ECC
/// started at `guess`, on windows of both pictures `margin` pixels around the outline's box
/// (the same size, as ECC wants; the whole-pixel part of the guess between them). False when
/// the pictures do not agree.
bool ecc_shift(const cv::Mat& from, const cv::Mat& to, const std::vector<cv::Point2f>& outline,
               const cv::Point2f& guess, int margin, cv::Point2f& shift) {
  const cv::Rect frame(cv::Point(0, 0), to.size());
  const cv::Point offset(cvRound(guess.x), cvRound(guess.y));
  // The middle of the box is enough: ECC's cost follows the window's area, its precision
  // (about 0.01 px on the belt's objects) hardly changes down to kEccSide.
  const cv::Rect whole = box_of(outline) & frame;
  const int w = std::min(whole.width, kEccSide), h = std::min(whole.height, kEccSide);
  const cv::Rect box(whole.x + (whole.width - w) / 2, whole.y + (whole.height - h) / 2, w, h);
  const cv::Rect window =
      cv::Rect(box.x - margin, box.y - margin, box.width + 2 * margin, box.height + 2 * margin) &
      frame & (frame - offset);
  if (window.width < 16 || window.height < 16)
    return false;
  cv::Mat mask = cv::Mat::zeros(window.size(), CV_8UC1);
  std::vector<cv::Point> inside;
  for (const cv::Point2f& p : outline)
    inside.emplace_back(cvRound(p.x - window.x), cvRound(p.y - window.y));
  cv::fillConvexPoly(mask, inside, cv::Scalar(255));
  cv::erode(mask, mask, cv::Mat(), cv::Point(-1, -1), 2);
  cv::Mat warp = (cv::Mat_<float>(2, 3) << 1, 0, guess.x - offset.x, 0, 1, guess.y - offset.y);
  try {
    const double cc = cv::findTransformECC(
        from(window), to(window + offset), warp, cv::MOTION_TRANSLATION,
        cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 50, 1e-4), mask, 1);
    shift = cv::Point2f(static_cast<float>(offset.x) + warp.at<float>(0, 2),
                        static_cast<float>(offset.y) + warp.at<float>(1, 2));
    return cc >= kLeastCorrelation;
  } catch (const cv::Exception&) {
    return false; // ECC did not converge.
  }
}

/// What following what is left in view of a leaving instance needs (its model, outline and
/// centre), moved by `shift`.
Instance remnant_moved(const Instance& instance, cv::Point2f shift) {
  Instance left;
  left.model = instance.model;
  left.outline = instance.outline;
  for (cv::Point2f& p : left.outline)
    p += shift;
  left.center = instance.center + shift;
  return left;
}

/// Whether `step` carries an object whose box is `box` out of the frame: less of it in view.
bool moves_out(const cv::Rect& box, const cv::Point2f& step, const cv::Size& size) {
  const cv::Rect frame(cv::Point(0, 0), size);
  const cv::Rect next = box + cv::Point(cvRound(step.x), cvRound(step.y));
  return (next & frame).area() < (box & frame).area();
}

/// Whether enough of the instance is in the frame to follow it by its motion: kLeastInFrame of
/// its box, or any part ECC can measure of one leaving the frame (its last `step` carries it
/// out). What is left of a leaving object is followed out rather than extracted again each
/// frame: found when more of it was in view, its keypoints are those of then.
bool in_view(const Instance& instance, const cv::Size& size,
             const std::optional<cv::Point2f>& step) {
  const cv::Rect whole = box_of(instance.outline);
  const cv::Rect box = whole & cv::Rect(cv::Point(0, 0), size);
  if (box.width < 16 || box.height < 16)
    return false;
  return box.area() >= kLeastInFrame * whole.area() || (step && moves_out(whole, *step, size));
}

/// Whether an object at `outline` in the last frame that moved by `shift` is leaving the frame
/// with less than kLeastInFrame of its box in view.
bool leaves(const std::vector<cv::Point2f>& outline, const cv::Point2f& shift,
            const cv::Size& size) {
  const cv::Rect before = box_of(outline);
  const cv::Rect now = before + cv::Point(cvRound(shift.x), cvRound(shift.y));
  const int in_view = (now & cv::Rect(cv::Point(0, 0), size)).area();
  return in_view > 0 && moves_out(before, shift, size) && in_view < kLeastInFrame * now.area();
}

/// How `instance` moved from `last` to `grey`: ECC on its outline's pixels, started from
/// `step` (its last one) when known, else from the phase correlation of its box (the part in
/// the frame).
bool step_shift(const cv::Mat& last, const cv::Mat& grey, const Instance& instance,
                const std::optional<cv::Point2f>& step, cv::Point2f& shift) {
  if (step && ecc_shift(last, grey, instance.outline, *step, kPredictedMargin, shift))
    return true;
  const cv::Rect box = box_of(instance.outline) & cv::Rect(cv::Point(0, 0), grey.size());
  cv::Mat a, b, window;
  last(box).convertTo(a, CV_32F);
  grey(box).convertTo(b, CV_32F);
  cv::createHanningWindow(window, box.size(), CV_32F);
  const cv::Point2d start = cv::phaseCorrelate(a, b, window);
  return ecc_shift(last, grey, instance.outline,
                   cv::Point2f(static_cast<float>(start.x), static_cast<float>(start.y)),
                   kSearchMargin, shift);
}

/// Whether a point of an object that moved by `moved` since its keypoints were extracted lay
/// there within `r` pixels of the frame's edge it came in across (or beyond it).
bool came_across_edge(const cv::Point2f& p, const cv::Point2f& moved, double r,
                      const cv::Size& frame) {
  const cv::Point2f then = p - moved;
  return (moved.x > 0 && then.x < r) || (moved.x < 0 && then.x > frame.width - r) ||
         (moved.y > 0 && then.y < r) || (moved.y < 0 && then.y > frame.height - r);
}

/// The block (row, column) a point lies in, on a grid of `blocks`.
cv::Point block_of(const cv::Point2f& p, const cv::Mat& blocks) {
  return {std::clamp(static_cast<int>(p.x) / kBlock, 0, blocks.cols - 1),
          std::clamp(static_cast<int>(p.y) / kBlock, 0, blocks.rows - 1)};
}

/// On the instance: inside its outline or within kOutlineSlack of it (the outline is fitted,
/// and the keypoints on the object's rim ride with it too).
bool inside_outline(const Instance& instance, const cv::Point2f& p) {
  return cv::pointPolygonTest(instance.outline, p, true) >= -kOutlineSlack;
}

/// `s` with the belt's motion blur, where it is measured (else as given): the detector's checks
/// of the frame's pixels compare the models' pictures blurred as the frame is.
Settings with_motion_blur(const Settings& s, const cv::Point2f& blur) {
  Settings out = s;
  if (cv::norm(blur) >= detail::kLeastBlurPx) {
    out.motion_blur_x = blur.x;
    out.motion_blur_y = blur.y;
  }
  return out;
}

} // namespace

void FeatureReuse::reset() {
  detector_ = nullptr;
  motions_.clear();
  leaving_.clear();
  leaving_motions_.clear();
  features_ = Features();
  matches_.clear();
  detection_ = Detection();
  reference_.release();
  belt_step_.reset();
  exposure_.reset();
}

void FeatureReuse::set_whole_interval(int frames) {
  whole_interval_ = std::max(1, frames);
}

bool FeatureReuse::same_run(const Detector& detector, const cv::Mat& grey, const Settings& s,
                            double contrast) const {
  return detector_ == &detector && grey.size() == size_ && s.features == FeatureKind::Sift &&
         !(s.detection_scale < 1.0) && s == settings_ &&
         std::abs(contrast - contrast_) <= kContrastDrift * contrast_;
}

Detection FeatureReuse::detect_whole(const Detector& detector, const cv::Mat& grey,
                                     const cv::Mat& colour, const Settings& s, double contrast,
                                     bool refresh) {
  auto t = Clock::now();
  // SIFT on the frame with the belt's motion blur undone (when known: the run goes on).
  const bool sharpen = s.features == FeatureKind::Sift && !(s.detection_scale < 1.0) &&
                       detector_ == &detector && grey.size() == size_ && s == settings_;
  if (!sharpen)
    belt_step_.reset();
  features_ = extract_features_scaled(sharpen ? detail::undo_motion_blur(grey, belt_blur()) : grey,
                                      s.detection_scale, s.features, contrast);
  const double features_ms = ms_since(t);
  t = Clock::now();
  matches_ = detector.match(features_, s);
  const double matching_ms = ms_since(t);
  detection_ = detector.detect(grey, features_, matches_, with_motion_blur(s, belt_blur()), colour);
  detection_.timings.features_ms = features_ms;
  detection_.timings.matching_ms = matching_ms;
  detector_ = &detector;
  settings_ = s;
  contrast_ = contrast;
  size_ = grey.size();
  reference_ = block_means(grey);
  grey.copyTo(last_grey_);
  grey.copyTo(whole_grey_);
  motions_.assign(detection_.instances.size(), Motion{std::nullopt, cv::Point2f(), cv::Point2f()});
  // What is left in view of the objects leaving the frame: too little to find, it rides on out
  // by its last step through a whole frame of the run, so that its blocks are not extracted
  // again in each frame after it.
  std::vector<Instance> leaving;
  std::vector<Motion> leaving_motions;
  if (refresh)
    for (size_t i = 0; i < leaving_.size(); ++i) {
      const std::optional<cv::Point2f>& step = leaving_motions_[i].step;
      if (!step || !leaves(leaving_[i].outline, *step, grey.size()))
        continue;
      leaving.push_back(remnant_moved(leaving_[i], *step));
      leaving_motions.push_back(Motion{step, std::nullopt, cv::Point2f()});
    }
  leaving_ = std::move(leaving);
  leaving_motions_ = std::move(leaving_motions);
  since_whole_ = 0;
  last_ = ReuseStats{static_cast<int>(features_.keypoints.size()), 0, 1.0, true, false};
  return detection_;
}

Detection FeatureReuse::detect(const Detector& detector, const cv::Mat& grey, const Settings& s,
                               const cv::Mat& colour) {
  if (grey.cols < 16 || grey.rows < 16 || grey.type() != CV_8UC1)
    return detector.detect(grey, colour, s); // Its checks and its answer for tiny frames.
  const auto t0 = Clock::now();
  const double contrast = detector.frame_contrast_threshold(grey, s);
  const bool run = whole_interval_ > 1 && same_run(detector, grey, s, contrast);
  if (!run || since_whole_ + 1 >= whole_interval_)
    return detect_whole(detector, grey, colour, s, contrast, run);
  ++since_whole_;

  const cv::Mat means = block_means(grey);
  cv::Mat diff;
  cv::absdiff(means, reference_, diff);
  const cv::Mat changed = diff > kChangeLevels;
  const int changed_blocks = cv::countNonZero(changed);
  if (changed_blocks > kMostChanged * static_cast<double>(changed.total())) {
    belt_step_.reset(); // Another picture: nothing to reuse, no belt known to move in it.
    return detect_whole(detector, grey, colour, s, contrast);
  }
  if (changed_blocks == 0) {
    reference_ = means;
    grey.copyTo(last_grey_);
    Detection same = detection_;
    same.timings = Timings{ms_since(t0), 0.0, 0.0};
    last_ = ReuseStats{0, static_cast<int>(features_.keypoints.size()), 0.0, false, true};
    return same;
  }

  // The last frame's instances under changed blocks that moved rigidly (a belt): their
  // keypoints and matches move with them, and the blocks they left and came to are explained.
  std::vector<Moved> moved;
  cv::Mat explained = cv::Mat::zeros(changed.size(), CV_8UC1);
  const cv::Rect blocks(cv::Point(0, 0), changed.size());
  auto block_box = [&](const cv::Rect& r) {
    const cv::Point tl(r.x / kBlock - 1, r.y / kBlock - 1);
    const cv::Point br((r.br().x + kBlock - 1) / kBlock + 1, (r.br().y + kBlock - 1) / kBlock + 1);
    return cv::Rect(tl, br) & blocks;
  };
  const cv::Rect frame(cv::Point(0, 0), grey.size());
  // Each instance's motion, followed on its own pixels: the instances in parallel (ECC is most
  // of a belt frame's cost), each into its own slot, gathered in order below.
  // The last frame's instances, then what is left in view of those leaving it (not reported).
  const size_t found = detection_.instances.size();
  auto carrier_at = [&](size_t n) -> const Instance& {
    return n < found ? detection_.instances[n] : leaving_[n - found];
  };
  auto motion_at = [&](size_t n) -> const Motion& {
    return n < found ? motions_[n] : leaving_motions_[n - found];
  };
  // How an instance moved since the last frame. Measured from the whole frame its keypoints
  // came from when it was followed from there, so that the small errors of each step do not add
  // up; else from the last frame.
  auto measure_shift = [&](const Instance& instance, const Motion& motion, cv::Point2f& shift,
                           std::optional<cv::Point2f>& since_whole) {
    if (motion.since_whole && motion.step) {
      std::vector<cv::Point2f> there = instance.outline;
      for (cv::Point2f& p : there)
        p -= *motion.since_whole;
      cv::Point2f total;
      if (ecc_shift(whole_grey_, grey, there, *motion.since_whole + *motion.step, kPredictedMargin,
                    total)) {
        shift = total - *motion.since_whole;
        since_whole = total;
        return true;
      }
    }
    if (!step_shift(last_grey_, grey, instance, motion.step, shift))
      return false;
    if (motion.since_whole)
      since_whole = *motion.since_whole + shift;
    return true;
  };
  std::vector<std::optional<Moved>> follow(found + leaving_.size());
  std::vector<char> still(follow.size(), 0);
  cv::parallel_for_(cv::Range(0, static_cast<int>(follow.size())), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      const size_t n = static_cast<size_t>(i);
      const Instance& instance = carrier_at(n);
      const cv::Rect box = box_of(instance.outline);
      const cv::Rect before = box & frame;
      if (cv::countNonZero(changed(block_box(before))) == 0) {
        still[n] = 1;
        continue; // Still: its keypoints stay as they are.
      }
      const Motion& motion = motion_at(n);
      cv::Point2f shift;
      std::optional<cv::Point2f> since_whole;
      // Its last step; found in a whole frame (its step not known yet), the belt's, if known.
      const std::optional<cv::Point2f> step = motion.step ? motion.step : belt_step_;
      // What is left in view of one leaving the frame (no longer found, or less than
      // kLeastInFrame of it in view), too narrow to measure or that ECC no longer follows (the
      // middle of its box, where ECC looks, is out of view; too little is left to find anything
      // on): moved by its last step.
      const bool left_over = step && moves_out(box, *step, grey.size()) &&
                             (n >= found || before.area() < kLeastInFrame * box.area());
      if (!in_view(instance, grey.size(), step)) {
        if (!left_over)
          continue; // Its blocks are extracted again.
        shift = *step;
      } else if (!measure_shift(instance, motion, shift, since_whole)) {
        if (!left_over)
          continue; // Its blocks are extracted again.
        shift = *step;
      }
      // What was in view moved to `after`; what comes into view beside it is extracted.
      const cv::Rect after = (before + cv::Point(cvRound(shift.x), cvRound(shift.y))) & frame;
      // Coming into view across the frame's edge: once a good share more of it is in view than
      // when its keypoints there were extracted, what came in is extracted.
      const cv::Point2f edge = motion.since_edge + shift;
      const cv::Rect whole = box + cv::Point(cvRound(shift.x), cvRound(shift.y));
      const cv::Rect then = (whole - cv::Point(cvRound(edge.x), cvRound(edge.y))) & frame;
      const bool renew = (whole & frame).area() - then.area() >= kMoreInView * whole.area();
      follow[n] = Moved{&instance, shift, before, after, since_whole, edge, renew};
    }
  });
  size_t moved_found = 0; // Of them, the last frame's instances (the leaving ones follow).
  for (size_t n = 0; n < follow.size(); ++n)
    if (const std::optional<Moved>& m = follow[n]) {
      moved.push_back(*m);
      moved_found += n < found ? 1 : 0;
      explained(block_box(m->before)).setTo(255);
      explained(block_box(m->after)).setTo(255);
    }
  // What came into view of an entering instance, and its keypoints the edge cut: extracted.
  cv::Mat renewed = cv::Mat::zeros(changed.size(), CV_8UC1);
  for (const Moved& m : moved) {
    if (!m.renew)
      continue;
    const cv::Rect area = block_box(m.after);
    for (int y = area.y; y < area.br().y; ++y)
      for (int x = area.x; x < area.br().x; ++x) {
        const cv::Point2f c((static_cast<float>(x) + 0.5f) * kBlock,
                            (static_cast<float>(y) + 0.5f) * kBlock);
        if (inside_outline(*m.instance, c - m.shift) &&
            came_across_edge(c, m.since_edge, kCropReach, grey.size()))
          renewed.at<uchar>(y, x) = 255;
      }
  }
  const cv::Mat unexplained = (changed & (explained == 0)) | renewed;
  // The belt and its blur from the instances found (what is left of leaving ones is too little).
  std::vector<std::pair<const Instance*, cv::Point2f>> shifts;
  for (size_t i = 0; i < moved_found; ++i)
    shifts.emplace_back(moved[i].instance, moved[i].shift);
  measure_belt(detector, grey, shifts);
  const cv::Point2f blur = belt_blur();

  // How far each keypoint lies from the nearest block that changed unexplained, in pixels, at
  // the least.
  cv::Mat distance;
  cv::distanceTransform(unexplained == 0, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  auto affected = [&](const cv::KeyPoint& k) {
    return distance.at<float>(block_of(k.pt, distance)) * kBlock - 1.5 * kBlock <= reach(k);
  };
  auto in_explained = [&](const cv::KeyPoint& k) {
    return explained.at<uchar>(block_of(k.pt, explained)) != 0;
  };
  // Whether `m` carries a keypoint like `k` that lay at `from` in the last frame, one the edge
  // did not cut while `m` came into view (those are extracted again).
  auto carries = [&](const Moved& m, const cv::KeyPoint& k, const cv::Point2f& from) {
    return inside_outline(*m.instance, from) &&
           !(m.renew && came_across_edge(from + m.shift, m.since_edge, reach(k), grey.size()));
  };
  // A moved instance's keypoint of that size lies there now (not one the edge cut and that is
  // extracted again).
  auto carried = [&](const cv::KeyPoint& k) {
    return std::any_of(moved.begin(), moved.end(), [&](const Moved& m) {
      return frame.contains(k.pt - m.shift) && carries(m, k, k.pt - m.shift);
    });
  };

  // The keypoints the change left alone or carried along, with their matches.
  Features merged;
  std::vector<int> index(features_.keypoints.size(), -1);
  std::vector<int> kept_rows;
  for (size_t i = 0; i < features_.keypoints.size(); ++i) {
    cv::KeyPoint k = features_.keypoints[i];
    const auto carrier = std::find_if(moved.begin(), moved.end(), [&](const Moved& m) {
      return inside_outline(*m.instance, k.pt);
    });
    if (carrier != moved.end()) {
      const cv::Point2f from = k.pt;
      k.pt += carrier->shift;
      if (!frame.contains(k.pt))
        continue; // Carried out of view.
      if (std::none_of(moved.begin(), moved.end(),
                       [&](const Moved& m) { return carries(m, k, from); }))
        continue; // Its window was cut by the frame's edge: extracted again below.
    } else if (affected(k) || in_explained(k))
      continue; // Uncovered, covered or changed: what lies there now is extracted below.
    index[i] = static_cast<int>(merged.keypoints.size());
    merged.keypoints.push_back(k);
    kept_rows.push_back(static_cast<int>(i));
  }
  std::vector<Match> matches;
  for (const Match& m : matches_)
    if (index[static_cast<size_t>(m.scene_point)] >= 0) {
      matches.push_back(m);
      matches.back().scene_point = index[static_cast<size_t>(m.scene_point)];
    }
  // New keypoints where it changed, from crops around the changed blocks.
  cv::Mat zone;
  std::vector<cv::Rect> crops;
  if (cv::countNonZero(unexplained) > 0)
    crops = crops_around(unexplained, grey.size(), zone);
  Features fresh;
  double cropped = 0.0;
  for (const cv::Rect& crop : crops) {
    cropped += crop.area();
    Features f = extract_features(detail::undo_motion_blur(grey(crop), blur), cv::Mat(),
                                  FeatureKind::Sift, contrast_);
    for (size_t i = 0; i < f.keypoints.size(); ++i) {
      cv::KeyPoint k = f.keypoints[i];
      k.pt += cv::Point2f(static_cast<float>(crop.x), static_cast<float>(crop.y));
      if (affected(k) && supported_in(k, crop, grey.size()) && !carried(k)) {
        fresh.keypoints.push_back(k);
        fresh.descriptors.push_back(f.descriptors.row(static_cast<int>(i)));
      }
    }
  }
  const double features_ms = ms_since(t0);

  const auto t = Clock::now();
  std::vector<Match> fresh_matches;
  if (!fresh.keypoints.empty())
    fresh_matches = detector.match(fresh, s);
  const int offset = static_cast<int>(merged.keypoints.size());
  for (Match& m : fresh_matches) {
    m.scene_point += offset;
    matches.push_back(m);
  }
  const double matching_ms = ms_since(t);

  const cv::Mat& like = fresh.descriptors.empty() ? features_.descriptors : fresh.descriptors;
  merged.descriptors.create(static_cast<int>(kept_rows.size()) + fresh.descriptors.rows, like.cols,
                            like.type());
  for (size_t r = 0; r < kept_rows.size(); ++r)
    features_.descriptors.row(kept_rows[r]).copyTo(merged.descriptors.row(static_cast<int>(r)));
  if (fresh.descriptors.rows > 0)
    fresh.descriptors.copyTo(merged.descriptors.rowRange(offset, merged.descriptors.rows));
  merged.keypoints.insert(merged.keypoints.end(), fresh.keypoints.begin(), fresh.keypoints.end());

  features_ = std::move(merged);
  matches_ = std::move(matches);
  reference_ = means;
  grey.copyTo(last_grey_);
  const std::vector<Instance> last_instances = std::move(detection_.instances);
  const std::vector<Motion> last_motions = std::move(motions_);
  detection_ = detector.detect(grey, features_, matches_, with_motion_blur(s, belt_blur()), colour);
  detection_.timings.features_ms = features_ms;
  detection_.timings.matching_ms = matching_ms;
  // Each instance's motion, for the next frame: that of the last frame's instance it is. One
  // that lay still keeps its own; one that was not followed (too little of it in view, or its
  // step not measured) was found again from keypoints extracted in this frame: its motion
  // starts here, not from the whole frame.
  const size_t followed = moved.size();
  for (size_t n = 0; n < last_instances.size(); ++n)
    if (std::none_of(moved.begin(), moved.end(),
                     [&](const Moved& m) { return m.instance == &last_instances[n]; }))
      moved.push_back({&last_instances[n],
                       cv::Point2f(),
                       {},
                       {},
                       still[n] ? last_motions[n].since_whole : std::nullopt,
                       still[n] ? last_motions[n].since_edge : cv::Point2f(),
                       false});
  motions_.assign(detection_.instances.size(), Motion{});
  std::vector<char> found_again(moved.size(), 0);
  for (size_t n = 0; n < detection_.instances.size(); ++n) {
    const Instance& now = detection_.instances[n];
    const cv::Rect box = box_of(now.outline);
    double nearest = kSameInstanceShare * std::hypot(box.width, box.height);
    std::optional<size_t> from;
    for (size_t i = 0; i < moved.size(); ++i) {
      const Moved& m = moved[i];
      const double d = cv::norm(m.instance->center + m.shift - now.center);
      if (m.instance->model == now.model && d < nearest) {
        nearest = d;
        from = i;
        motions_[n] = Motion{m.shift, m.since_whole, m.renew ? cv::Point2f() : m.since_edge};
      }
    }
    if (from)
      found_again[*from] = 1;
  }
  // Those followed here and not found again that are leaving the frame, too little of them in
  // view to be found: what is left of them in view is followed out, not extracted each frame.
  std::vector<Instance> leaving;
  std::vector<Motion> leaving_motions;
  for (size_t i = 0; i < followed; ++i) {
    const Moved& m = moved[i];
    if (found_again[i] || !leaves(m.instance->outline, m.shift, grey.size()))
      continue;
    leaving.push_back(remnant_moved(*m.instance, m.shift)); // Where it is now.
    leaving_motions.push_back(Motion{m.shift, m.since_whole, m.since_edge});
  }
  for (size_t n = found; n < still.size(); ++n)
    if (still[n]) { // Lying still where it was: it stays.
      leaving.push_back(leaving_[n - found]);
      leaving_motions.push_back(leaving_motions_[n - found]);
    }
  leaving_ = std::move(leaving);
  leaving_motions_ = std::move(leaving_motions);
  last_ = ReuseStats{static_cast<int>(fresh.keypoints.size()), offset,
                     cropped / static_cast<double>(grey.total()), false, false};
  return detection_;
}

cv::Point2f FeatureReuse::belt_blur() const {
  if (!belt_step_ || !exposure_)
    return {};
  return *belt_step_ * static_cast<float>(*exposure_);
}

void FeatureReuse::measure_belt(
    const Detector& detector, const cv::Mat& grey,
    const std::vector<std::pair<const Instance*, cv::Point2f>>& shifts) {
  belt_step_.reset();
  std::vector<double> xs, ys;
  for (const auto& [instance, shift] : shifts) {
    xs.push_back(shift.x);
    ys.push_back(shift.y);
  }
  if (xs.empty())
    return;
  const cv::Point2f step(static_cast<float>(median(xs)), static_cast<float>(median(ys)));
  const double length = cv::norm(step);
  if (length < kLeastBeltStep)
    return;
  const double agree = std::max(kBeltAgreePx, kBeltAgreeShare * length);
  for (const auto& [instance, shift] : shifts)
    if (cv::norm(shift - step) > agree)
      return; // Not one motion: no belt.
  belt_step_ = step;
  if (exposure_ && since_whole_ != 1)
    return; // Measured once after each whole frame.
  // On the instances most in view, each at its pose in this frame.
  std::vector<std::pair<double, size_t>> order;
  for (size_t i = 0; i < shifts.size(); ++i)
    order.emplace_back(-shifts[i].first->visibility * cv::contourArea(shifts[i].first->outline), i);
  std::sort(order.begin(), order.end());
  std::vector<double> exposures;
  for (size_t k = 0; k < order.size() && k < kBlurMeasured; ++k) {
    const auto& [instance, shift] = shifts[order[k].second];
    const cv::Matx33d moved_by(1, 0, shift.x, 0, 1, shift.y, 0, 0, 1);
    const std::optional<double> blur =
        detail::measure_blur_length(grey, detector.models()[static_cast<size_t>(instance->model)],
                                    moved_by * instance->homography, shift);
    if (blur)
      exposures.push_back(*blur / cv::norm(shift));
  }
  if (exposures.empty())
    return;
  const bool first = !exposure_;
  exposure_ = median(exposures);
  // The first frame to undo the blur on is detected whole: what the blur hid there till now is
  // found at once.
  if (first && cv::norm(belt_blur()) >= detail::kLeastBlurPx)
    since_whole_ = whole_interval_;
}

} // namespace pickdetect
