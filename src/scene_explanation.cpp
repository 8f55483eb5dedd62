// SPDX-License-Identifier: LGPL-2.1-or-later
// Scene-level verification: the instances of all models compete for the frame's keypoints.
#include "scene_explanation.hpp"

#include "descriptor_distance.hpp"
#include "foreign_cover.hpp"
#include "keypoint_grid.hpp"
#include "median.hpp"
#include "model_scene.hpp"
#include "point_grid.hpp"
#include "polygon.hpp"

#include <pickdetect/occlusion.hpp>
#include <pickdetect/pose.hpp>

#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>

namespace pickdetect::detail {
namespace {

/// A scene keypoint agrees with an instance when a model keypoint lies within this share of the
/// model's smaller side (at least kMinPlacePx scene pixels) of where the instance's pose carries
/// the scene keypoint back into the model...
constexpr double kPlaceShare = 0.02;
constexpr double kMinPlacePx = 3.0;
/// ...with the rotation and size ratio the pose predicts there (kInlierAngleDeg and
/// kInlierScaleFactor, as for the refinement's inliers) and a descriptor within
/// agree_distance() of the scene keypoint's (descriptor_distance.hpp).
/// An instance is kept when nearly all the keypoints it explains are its own: a few may lie on
/// an edge it shares with a neighbour.
constexpr double kOwnShare = 0.9;
/// ...and when they spread over at least this share of the model's area (their convex hull, in
/// model pixels): a few keypoints bunched on one small part of the design (a logo the product
/// also prints on another face) do not tell where the rest of the face is. On the real tote
/// such instances on the soap cartons' narrow sides spread over 0-2 %, true ones mostly over
/// 5 % and more.
constexpr double kMinSpread = 0.03;
/// An instance that rests on few matches (fewer than kFewMatchesTimes times the fewest an
/// instance needs) must also explain at least kMinExplainedShare of the scene keypoints on its
/// outline. A few matches can agree by chance where the frame holds many keypoints of no
/// object (clutter, the print of another product); around such a pose only the chance share
/// of the keypoints agrees with the model, 1-2 % on the dev sets' ghosts, while a true
/// instance, even a washed-out soap carton of the real tote that gives 4-10 matches, explains
/// 13 % and more. Well-supported instances are left alone: a box mostly covered by another
/// explains little of its outline and is still there.
constexpr int kFewMatchesTimes = 3;
constexpr double kMinExplainedShare = 0.05;
/// An instance must show its print where it is seen: of the cells of its picture that the frame
/// tells about (foreign_cover's cell comparison; cells where the print of an instance kept
/// before it shows tell nothing, as it may lie under that one), at least this share must show
/// its print (correlate with the picture carried there) rather than deny it (show something
/// else, or lie flat where the print keeps clear detail elsewhere in this frame; see
/// denies_print). Keypoints can agree with a pose that the frame's pixels deny: a fine graffiti
/// print found at about twice its size on 11-32 keypoints along a striped distractor's lines and
/// a box's edge (docs/tracking.md's bin of other products) showed its print in 5-26 % of those
/// cells (median 9 %), a box just picked out of that bin, still found for three frames on
/// keypoints carried from the frames before, in 13-17 %; the true instances of the development
/// sets, the sequences of docs/tracking.md and the real tote in 45 % and more (the lowest: glare
/// on the tote's soap cartons; motion-blurred belts 58 %). Objects nearly all hidden (don't
/// care) went down to 18 %.
constexpr double kMinPrintShare = 0.35;
/// Fewest cells that tell either way for that test: fewer say too little (in a dim frame the
/// print keeps too little detail to be told from flat ground).
constexpr int kMinToldCells = 8;
/// A face guided matching built rests on a few pairs found without the ratio test, and a flat
/// cell where its print has texture counts against it too: of the cells compared (not under a
/// kept instance's print; kMinForeignCells or more), at least this share must show its print.
/// A line drawing of faint print (`pic3`, opencv-doc) was built from 6-16 pairs along a striped
/// card's lines and a bin's rim in a bin of other pictures (docs/accuracy.md); its print showed
/// in 7-45 % of the compared cells there, most of the others flat, which the test above does
/// not count (the print's own detail is faint). Guided faces of the real tote, the hard sets and
/// beltA showed it in 29-100 % (partly covered, blurred, tilted far).
constexpr double kMinGuidedPrintShare = 0.25;
/// ...in a frame lit well enough (exposure_contrast_share at least this): in a dim or flat one
/// faint print keeps too little detail to be told from flat ground (seed 29's tote-like-faces
/// at 30 % of the light, share 0.35-0.38, lost 7 of its 170 faces to the test; the bin of
/// other pictures reads 0.64-1.00, the real tote 1.00, and 0.57-0.58 at half its light).
constexpr double kMinGuidedExposure = 0.5;
/// The test is made for instances that explain fewer keypoints than this (it costs about a
/// millisecond an instance, and kept instances are compared where they overlap it); one that
/// explains more has shown its print keypoint by keypoint. The ghosts above explained 11-32.
constexpr size_t kPixelCheckBelow = 64;
/// How much of a print's detail the frame keeps (its blur and exposure,
/// CellComparison::detail_kept) is the camera's, the same for every object in it; an instance on
/// few keypoints measures it on its own few cells that match its print, and a false one's match
/// by chance (a cartoon's ghost riding a dim belt on 7 keypoints read 0.19-0.21, where the
/// frame's true instances read 0.67 and more, so that the plain belt under it denied nothing).
/// For that test an instance's own measure is taken no lower than the median over the instances
/// that explain kPixelCheckBelow keypoints or more and show their print in this many cells.
constexpr int kMinKeptPrintCells = 8;
/// An instance that guided matching completed (voting.cpp) rests on descriptors that agree
/// with a model only where its pose puts them, no ratio test: where more than this share of
/// its outline lies on an instance already kept, its pairs are that instance's print read as
/// this model's (on the real tote, a soap face's pose built on a toothpaste carton's white
/// label).
constexpr double kMaxGuidedOverlap = 0.2;

/// Whether instance `i`'s outline lies more than kMaxGuidedOverlap on an instance kept so far.
bool lies_on_kept(const std::vector<Instance>& instances, const std::vector<char>& keep, size_t i) {
  const double area = hull_area(instances[i].outline); // overlap_area's hulls
  for (size_t j = 0; j < instances.size(); ++j)
    if (keep[j] &&
        overlap_area(instances[i].outline, instances[j].outline) > kMaxGuidedOverlap * area)
      return true;
  return false;
}

/// The scene keypoints (indices) that instance `inst` of `model` explains.
std::vector<int> explained(const Instance& inst, const cv::Rect2f& model_box,
                           const KeypointGrid& model_grid, double model_radius,
                           const Features& model_features, const Features& scene,
                           const PointGrid& scene_grid, FeatureKind kind, int& on_outline) {
  on_outline = 0;
  std::vector<int> out;
  cv::Matx33d back;
  if (!cv::invert(inst.homography, back, cv::DECOMP_LU))
    return out;
  const cv::Rect2f box = bounds(inst.outline);
  const double limit = agree_distance(kind);
  for (int s : scene_grid.inside(box)) {
    const cv::KeyPoint& ks = scene.keypoints[s];
    const cv::Vec3d q = back * cv::Vec3d(ks.pt.x, ks.pt.y, 1.0);
    if (!(q[2] > 0.0))
      continue;
    const cv::Point2d at(q[0] / q[2], q[1] / q[2]);
    // On the model's outline (its box: no model keypoint lies beyond the outline to agree).
    if (!in_box(model_box, cv::Point2f(static_cast<float>(at.x), static_cast<float>(at.y))))
      continue;
    ++on_outline;
    bool agrees = false;
    for_alike(model_grid, ks, at, inst.angle, inst.scale, [&](int k) {
      if (agrees) // One model keypoint that agrees is enough.
        return;
      if (!placed_alike(ks, model_features.keypoints[k], at, model_radius, inst.angle, inst.scale))
        return;
      agrees =
          distance_within(scene.descriptors, s, model_features.descriptors, k, limit, kind) >= 0.0;
    });
    if (agrees)
      out.push_back(s);
  }
  return out;
}

/// Share of the model's outline area that the convex hull of the explained keypoints, carried
/// back into the model, covers.
double spread_of(const Instance& inst, const Model& model, const std::vector<int>& explained,
                 const Features& scene) {
  cv::Matx33d back;
  if (explained.size() < 3 || model.outline.size() < 3 ||
      !cv::invert(inst.homography, back, cv::DECOMP_LU))
    return 0.0;
  std::vector<cv::Point2f> at;
  at.reserve(explained.size());
  for (int s : explained) {
    const cv::Vec3d q = back * cv::Vec3d(scene.keypoints[s].pt.x, scene.keypoints[s].pt.y, 1.0);
    if (q[2] > 0.0)
      at.emplace_back(static_cast<float>(q[0] / q[2]), static_cast<float>(q[1] / q[2]));
  }
  if (at.size() < 3)
    return 0.0;
  std::vector<cv::Point2f> hull;
  cv::convexHull(at, hull);
  const double area = std::abs(cv::contourArea(model.outline));
  return area > 0.0 ? cv::contourArea(hull) / area : 0.0;
}

/// Where the print of a kept instance shows in the frame (CV_8UC1, 255), painted as the test
/// below needs it: each kept instance over each candidate's box, once; in a frame of
/// `motion_blur` (compare_cells).
class ShownPrint {
public:
  explicit ShownPrint(const cv::Point2f& motion_blur) : blur_(motion_blur) {}

  const cv::Mat& around(const std::vector<Instance>& instances, size_t i,
                        const std::vector<char>& keep, const std::vector<Model>& models,
                        const cv::Mat& grey) {
    if (shown_.empty())
      shown_ = cv::Mat::zeros(grey.size(), CV_8UC1);
    const cv::Rect frame(0, 0, grey.cols, grey.rows);
    const cv::Rect box = cv::boundingRect(instances[i].outline) & frame;
    for (size_t j = 0; j < instances.size(); ++j) {
      if (!keep[j])
        continue;
      const cv::Rect overlap = box & cv::boundingRect(instances[j].outline);
      if (overlap.empty())
        continue;
      const CellComparison cells =
          compare_cells(instances[j], models[instances[j].model], grey, {}, overlap, {}, blur_);
      for (int r = 0; r < cells.rows; ++r)
        for (int c = 0; c < cells.columns; ++c) {
          const CellLook& look = cells.looks[static_cast<size_t>(r) * cells.columns + c];
          if (shows_print(look))
            shown_(cv::Rect(cells.origin.x + c * kCoverCell, cells.origin.y + r * kCoverCell,
                            kCoverCell, kCoverCell) &
                   frame)
                .setTo(255);
        }
    }
    return shown_;
  }

private:
  cv::Point2f blur_;
  cv::Mat shown_;
};

/// Whether instance `i` shows its print in the frame where it is seen (kMinPrintShare; a guided
/// face in a `lit` frame, kMinGuidedPrintShare too), from
/// `cells`, its comparison with the frame; cells where a kept instance's print shows tell nothing
/// about it (it may lie under that instance); true when too little of it tells.
bool instance_shows_print(const std::vector<Instance>& instances, size_t i,
                          const CellComparison& cells, const std::vector<char>& keep,
                          const std::vector<Model>& models, const cv::Mat& grey, ShownPrint& shown,
                          bool lit) {
  const cv::Mat& others = shown.around(instances, i, keep, models, grey);
  int compared = 0, print = 0, denied = 0;
  for (int r = 0; r < cells.rows; ++r)
    for (int c = 0; c < cells.columns; ++c) {
      const CellLook& look = cells.looks[static_cast<size_t>(r) * cells.columns + c];
      const cv::Point middle(cells.origin.x + c * kCoverCell + kCoverCell / 2,
                             cells.origin.y + r * kCoverCell + kCoverCell / 2);
      if (!look.compared ||
          (middle.inside(cv::Rect(0, 0, others.cols, others.rows)) && others.at<uchar>(middle)))
        continue;
      ++compared;
      if (shows_print(look))
        ++print;
      else
        denied += denies_print(look, cells);
    }
  const int told = print + denied;
  if (told >= kMinToldCells && print < kMinPrintShare * told)
    return false;
  return !instances[i].guided || !lit || compared < kMinForeignCells ||
         print >= kMinGuidedPrintShare * compared;
}

/// The comparisons of `cells` (those made) with their detail kept taken no lower than the
/// frame's: the median over the `placed` instances that explain kPixelCheckBelow keypoints or
/// more (`explains`), compared here, that show their print in kMinKeptPrintCells cells or more.
/// Nothing changes without such an instance.
void lift_detail_kept(std::vector<std::optional<CellComparison>>& cells,
                      const std::vector<Instance>& instances, const std::vector<Model>& models,
                      const std::vector<std::vector<int>>& explains,
                      const std::vector<char>& placed, const cv::Mat& grey,
                      const cv::Point2f& motion_blur) {
  if (std::none_of(cells.begin(), cells.end(), [](const auto& c) { return c.has_value(); }))
    return;
  std::vector<size_t> strong;
  for (size_t i = 0; i < instances.size(); ++i)
    if (placed[i] && explains[i].size() >= kPixelCheckBelow)
      strong.push_back(i);
  std::vector<double> kept(strong.size(), std::numeric_limits<double>::quiet_NaN());
  cv::parallel_for_(cv::Range(0, static_cast<int>(strong.size())), [&](const cv::Range& r) {
    for (int k = r.start; k < r.end; ++k) {
      const Instance& inst = instances[strong[static_cast<size_t>(k)]];
      const CellComparison c = compare_cells(inst, models[static_cast<size_t>(inst.model)], grey,
                                             {}, {}, {}, motion_blur);
      if (c.print_cells >= kMinKeptPrintCells)
        kept[static_cast<size_t>(k)] = c.detail_kept;
    }
  });
  kept.erase(std::remove_if(kept.begin(), kept.end(), [](double v) { return std::isnan(v); }),
             kept.end());
  if (kept.empty())
    return;
  const double frame = median(kept);
  for (std::optional<CellComparison>& c : cells)
    if (c && !(c->detail_kept >= frame))
      c->detail_kept = frame;
}

} // namespace

void explain_scene(std::vector<Instance>& instances, const std::vector<Model>& models,
                   const Features& scene, FeatureKind kind, int min_matches, const cv::Mat& grey,
                   const cv::Point2f& motion_blur) {
  const size_t n = instances.size();
  if (n == 0 || scene.keypoints.empty())
    return;
  std::vector<cv::Point2f> at;
  at.reserve(scene.keypoints.size());
  for (const cv::KeyPoint& k : scene.keypoints)
    at.push_back(k.pt);
  double smallest_side = 1e9;
  for (const Instance& inst : instances)
    smallest_side = std::min(smallest_side, model_side(models[inst.model]) * inst.scale);
  const PointGrid scene_grid(std::move(at), std::max(8.0, 0.5 * smallest_side));

  // Each instance's search radius in model pixels; each model's keypoints on one grid whose
  // cells are the largest radius its instances need (so that the 3x3 cells around a point
  // hold every keypoint within any of them), built once for the models found.
  std::vector<double> radius(n);
  std::vector<double> cell(models.size(), 0.0);
  for (size_t i = 0; i < n; ++i) {
    const Instance& inst = instances[i];
    radius[i] = std::max(kMinPlacePx / std::max(inst.scale, 1e-3),
                         kPlaceShare * model_side(models[inst.model]));
    cell[inst.model] = std::max(cell[inst.model], radius[i]);
  }
  // The grids, then what each instance explains: each on its own, in parallel, into its own slot
  // (the same result whatever the threads).
  std::vector<KeypointGrid> model_grid(models.size());
  cv::parallel_for_(cv::Range(0, static_cast<int>(models.size())), [&](const cv::Range& r) {
    for (int m = r.start; m < r.end; ++m)
      if (cell[static_cast<size_t>(m)] > 0.0)
        model_grid[static_cast<size_t>(m)] = KeypointGrid(
            models[static_cast<size_t>(m)].features(kind).keypoints, cell[static_cast<size_t>(m)]);
  });
  std::vector<std::vector<int>> explains(n);
  std::vector<int> on_outline(n, 0);
  cv::parallel_for_(cv::Range(0, static_cast<int>(n)), [&](const cv::Range& r) {
    for (int k = r.start; k < r.end; ++k) {
      const size_t i = static_cast<size_t>(k);
      const Instance& inst = instances[i];
      const Model& model = models[static_cast<size_t>(inst.model)];
      explains[i] =
          explained(inst, bounds(model.outline), model_grid[static_cast<size_t>(inst.model)],
                    radius[i], model.features(kind), scene, scene_grid, kind, on_outline[i]);
    }
  });

  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  // Most explained first; the instances of guided matching, paired without the ratio test, only
  // after every other: they take what those leave.
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    if (instances[a].guided != instances[b].guided)
      return !instances[a].guided;
    return explains[a].size() > explains[b].size();
  });
  // The tests that do not depend on which instances are kept, and the comparison of the frame's
  // pixels with the print of each instance that passes them and explains few keypoints (the
  // pixel test below), in parallel: nearly all of those reach that test.
  std::vector<char> placed(n, 0);
  std::vector<std::optional<CellComparison>> cells(n);
  cv::parallel_for_(cv::Range(0, static_cast<int>(n)), [&](const cv::Range& r) {
    for (int k = r.start; k < r.end; ++k) {
      const size_t i = static_cast<size_t>(k);
      const Instance& inst = instances[i];
      const Model& model = models[static_cast<size_t>(inst.model)];
      placed[i] = spread_of(inst, model, explains[i], scene) >= kMinSpread &&
                  !(inst.matches < kFewMatchesTimes * min_matches &&
                    static_cast<double>(explains[i].size()) < kMinExplainedShare * on_outline[i]);
      if (placed[i] && !grey.empty() && explains[i].size() < kPixelCheckBelow &&
          explains[i].size() >= static_cast<size_t>(std::max(min_matches, 0)))
        cells[i] = compare_cells(inst, model, grey, {}, {}, {}, motion_blur);
    }
  });
  lift_detail_kept(cells, instances, models, explains, placed, grey, motion_blur);
  std::vector<int> taken(scene.keypoints.size(), 0);
  std::vector<char> keep(n, 0);
  ShownPrint shown(motion_blur);
  // The frame's exposure matters only to faces of guided matching (kMinGuidedExposure).
  const bool lit = !grey.empty() &&
                   std::any_of(instances.begin(), instances.end(),
                               [](const Instance& inst) { return inst.guided; }) &&
                   exposure_contrast_share(grey) >= kMinGuidedExposure;
  for (size_t i : order) {
    size_t own = 0;
    for (int s : explains[i])
      own += !taken[s];
    if (static_cast<int>(own) < min_matches ||
        static_cast<double>(own) < kOwnShare * static_cast<double>(explains[i].size()))
      continue;
    if (!placed[i])
      continue;
    if (cells[i] && !instance_shows_print(instances, i, *cells[i], keep, models, grey, shown, lit))
      continue;
    if (instances[i].guided && lies_on_kept(instances, keep, i))
      continue;
    keep[i] = 1;
    for (int s : explains[i])
      taken[s] = 1;
  }
  std::vector<Instance> kept;
  for (size_t i = 0; i < n; ++i)
    if (keep[i])
      kept.push_back(std::move(instances[i]));
  instances = std::move(kept);
}

} // namespace pickdetect::detail
