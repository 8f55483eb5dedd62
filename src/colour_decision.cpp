// SPDX-License-Identifier: LGPL-2.1-or-later
// Look-alike products that differ in colour: the frame's colour under each pose names them.
#include "colour_decision.hpp"

#include "look_alikes.hpp"
#include "polygon.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace pickdetect::detail {
namespace {

/// Points of the model's mask sampled for its colour, about this many.
constexpr double kColourSamples = 2000.0;
/// Fewest points seen in the frame for a colour misfit.
constexpr int kMinColourPoints = 50;
/// Points darker than this (sum of the three channels, of 765) have no reliable chromaticity.
constexpr int kMinColourSum = 60;
/// Frame pixels with a channel this bright may be clipped (a highlight): their colour is not
/// the object's.
constexpr int kSaturated = 250;
/// Colour decides between look-alikes when the better fit's misfit is at most this (a fit at
/// all: chromaticity distances run from 0 to 4/3)...
constexpr double kMaxColourMisfit = 0.12;
/// ...and the worse one's is at least kColourRatio times and kColourMargin more than it. The
/// right edition measured 0.02-0.05 on the tests' scenes, the wrong one 0.6, and an edition of
/// no model (its hue turned by 120 degrees) 0.29 and 0.68. A colour cast raises the right
/// one's: 0.064, 0.114, 0.161 and 0.242 with blue divided and red multiplied by 1.1, 1.2, 1.3
/// and 1.5 (the wrong one's 0.67-0.85): colour decides up to a cast of about 1.2, leaves it to
/// the matches up to about 1.4, and beyond names neither.
constexpr double kColourRatio = 1.5;
constexpr double kColourMargin = 0.04;
/// Look-alikes whose colours all misfit by more than this are another edition, of no model.
constexpr double kNoColourFit = 0.2;

/// The chromaticity distance of two BGR pixels, or a negative number when either is too dark.
double chroma_distance(const cv::Vec3b& a, const cv::Vec3b& b) {
  const int sa = a[0] + a[1] + a[2], sb = b[0] + b[1] + b[2];
  if (sa < kMinColourSum || sb < kMinColourSum)
    return -1.0;
  double d = 0.0;
  for (int c = 0; c < 3; ++c)
    d += std::abs(a[c] / static_cast<double>(sa) - b[c] / static_cast<double>(sb));
  return d;
}

} // namespace

double colour_misfit(const Instance& instance, const Model& model, const cv::Mat& frame_bgr) {
  if (model.colour.empty() || frame_bgr.empty() || frame_bgr.type() != CV_8UC3 ||
      model.colour.size() != model.mask.size())
    return std::numeric_limits<double>::quiet_NaN();
  // The model's colour at about the frame's resolution: a frame pixel averages 1 / scale model
  // pixels.
  cv::Mat picture = model.colour;
  const double sigma = instance.scale > 0.0 ? 0.5 / instance.scale : 0.0;
  if (sigma > 0.5)
    cv::GaussianBlur(model.colour, picture, cv::Size(), sigma);
  const double area = std::max(1, cv::countNonZero(model.mask));
  const int step = std::max(1, static_cast<int>(std::sqrt(area / kColourSamples)));
  const cv::Matx33d& h = instance.homography;
  double sum = 0.0;
  int seen = 0;
  for (int y = step / 2; y < model.mask.rows; y += step)
    for (int x = step / 2; x < model.mask.cols; x += step) {
      if (!model.mask.at<uchar>(y, x))
        continue;
      const cv::Vec3d q = h * cv::Vec3d(x + 0.5, y + 0.5, 1.0);
      if (!(q[2] > 0.0))
        continue;
      const int u = static_cast<int>(std::floor(q[0] / q[2])),
                v = static_cast<int>(std::floor(q[1] / q[2]));
      if (u < 0 || v < 0 || u >= frame_bgr.cols || v >= frame_bgr.rows)
        continue;
      const cv::Vec3b f = frame_bgr.at<cv::Vec3b>(v, u);
      if (f[0] >= kSaturated || f[1] >= kSaturated || f[2] >= kSaturated)
        continue;
      const double d = chroma_distance(picture.at<cv::Vec3b>(y, x), f);
      if (d < 0.0)
        continue;
      sum += d;
      ++seen;
    }
  return seen >= kMinColourPoints ? sum / seen : std::numeric_limits<double>::quiet_NaN();
}

void decide_by_colour(std::vector<Instance>& instances, const std::vector<Model>& models,
                      const cv::Mat& frame_bgr) {
  const size_t n = instances.size();
  if (frame_bgr.empty() || n < 2)
    return;
  std::vector<double> misfit(n, -1.0); // -1: not measured yet.
  auto misfit_of = [&](size_t i) {
    if (misfit[i] == -1.0)
      misfit[i] =
          colour_misfit(instances[i], models[static_cast<size_t>(instances[i].model)], frame_bgr);
    return misfit[i];
  };
  std::vector<cv::Rect2f> box(n);
  for (size_t i = 0; i < n; ++i)
    box[i] = bounds(instances[i].outline);
  std::vector<char> lost(n, 0), won(n, 0);
  for (size_t a = 0; a < n; ++a)
    for (size_t b = a + 1; b < n; ++b) {
      const Instance& x = instances[a];
      const Instance& y = instances[b];
      if (x.model_name == y.model_name || models[x.model].colour.empty() ||
          models[y.model].colour.empty() || !touch(box[a], box[b]) || !same_place(x, y))
        continue;
      const double fa = misfit_of(a), fb = misfit_of(b);
      if (!std::isfinite(fa) || !std::isfinite(fb))
        continue;
      const bool a_better = fa < fb;
      const double lo = a_better ? fa : fb, hi = a_better ? fb : fa;
      if (lo > kNoColourFit) { // Another edition, of no model: neither is named.
        lost[a] = lost[b] = 1;
        continue;
      }
      if (lo > kMaxColourMisfit || hi < kColourRatio * lo || hi < lo + kColourMargin)
        continue;
      lost[a_better ? b : a] = 1;
      won[a_better ? a : b] = 1;
    }
  std::vector<Instance> kept;
  for (size_t i = 0; i < n; ++i) {
    if (lost[i])
      continue;
    if (won[i])
      instances[i].distinct_matches = instances[i].matches;
    kept.push_back(std::move(instances[i]));
  }
  instances = std::move(kept);
}

} // namespace pickdetect::detail
