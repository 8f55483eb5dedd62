// SPDX-License-Identifier: LGPL-2.1-or-later
#include "foreign_cover.hpp"

#include "median.hpp"
#include "object_mask.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace pickdetect::detail {
namespace {

/// The comparison runs on pictures shrunk by this factor (the band-pass below leaves nothing
/// finer anyway): a quarter of the pixels to warp, blur and sum.
constexpr int kShrink = 2;
/// Both pictures are compared through a band-pass (the difference of two blurs, each a box
/// filter run twice; sides in shrunk pixels: Gaussian-like with sigma about 1.4 and 5.7 frame
/// pixels, at the cost of a few additions per pixel): the light blur evens out the frame's
/// optics, motion blur, noise and JPEG blocks against the model picture's finest print; the
/// wide one removes what light does (shading, the soft rim of a highlight), which would
/// otherwise lower the correlation of a plainly seen print.
constexpr int kFineBox = 2;
constexpr int kLightBox = 7;
/// Shrunk pixels along the object's edge left out of the comparison.
constexpr int kEdgeMargin = 2;
/// Frame grey levels at least this are taken as clipped.
constexpr int kClipped = 250;
/// Share of a cell that must be compared pixels for the cell to count.
constexpr double kMinCellFill = 0.75;

/// Per cell: compared pixels, sums of the band-passed frame f and model m (and their squares
/// and product), and of the shrunk grey levels of both (lf, lm).
struct CellSums {
  double n = 0, f = 0, m = 0, ff = 0, mm = 0, fm = 0, lf = 0, lm = 0;
};

std::vector<cv::Point> mapped(const std::vector<cv::Point2f>& outline, const cv::Matx33d& map) {
  std::vector<cv::Point> out;
  out.reserve(outline.size());
  for (const cv::Point2f& p : outline)
    out.emplace_back(cvRound(map(0, 0) * p.x + map(0, 2)), cvRound(map(1, 1) * p.y + map(1, 2)));
  return out;
}

cv::Mat twice_boxed(const cv::Mat& picture, int side) {
  cv::Mat once, out;
  cv::blur(picture, once, cv::Size(side, side), cv::Point(-1, -1), cv::BORDER_REFLECT);
  cv::blur(once, out, cv::Size(side, side), cv::Point(-1, -1), cv::BORDER_REFLECT);
  return out;
}

cv::Mat detail_of(const cv::Mat& grey) {
  cv::Mat picture;
  grey.convertTo(picture, CV_32F);
  return twice_boxed(picture, kFineBox) - twice_boxed(picture, kLightBox);
}

} // namespace

CellComparison compare_cells(const Instance& inst, const Model& model, const cv::Mat& grey,
                             const std::vector<const Instance*>& above, const cv::Rect& within) {
  CellComparison out;
  if (grey.empty() || model.image.empty() || inst.outline.size() < 3)
    return out;
  cv::Rect seen = cv::boundingRect(inst.outline) & cv::Rect(0, 0, grey.cols, grey.rows);
  if (!within.empty())
    seen &= within;
  // Whole shrunk pixels and whole cells only.
  const int cell = kCoverCell / kShrink;
  const cv::Rect box(seen.x, seen.y, seen.width / kShrink * kShrink,
                     seen.height / kShrink * kShrink);
  const cv::Size size(box.width / kShrink, box.height / kShrink);
  const int columns = size.width / cell, rows = size.height / cell;
  if (columns <= 0 || rows <= 0)
    return out;
  // Frame pixels to shrunk ones: pixel j of the shrunk picture averages frame pixels
  // kShrink * j ... kShrink * j + kShrink - 1 (centres on whole numbers).
  const double k = 1.0 / kShrink, half = 0.5 * (kShrink - 1) * k;
  const cv::Matx33d to_small(k, 0, -k * box.x - half, 0, k, -k * box.y - half, 0, 0, 1);
  const cv::Matx33d to_box = to_small * inst.homography;
  cv::Mat picture, mask;
  // Replicated past the picture's edge, so that the band-pass sees no false edge there.
  cv::warpPerspective(model.image, picture, cv::Mat(to_box), size, cv::INTER_LINEAR,
                      cv::BORDER_REPLICATE);
  // A model without a mask is all object.
  cv::warpPerspective(object_mask(model.mask, model.image.size()), mask, cv::Mat(to_box), size,
                      cv::INTER_NEAREST, cv::BORDER_CONSTANT);
  for (const Instance* other : above)
    if (other->outline.size() >= 3)
      cv::fillPoly(mask, std::vector<std::vector<cv::Point>>{mapped(other->outline, to_small)},
                   cv::Scalar(0));
  // Near the edges of what is seen of the object the blurs mix in what lies beside it (more
  // so under motion blur): only the inside is compared.
  cv::erode(
      mask, mask,
      cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * kEdgeMargin + 1, 2 * kEdgeMargin + 1)),
      cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::Mat shrunk;
  cv::resize(grey(box), shrunk, size, 0, 0, cv::INTER_AREA);
  // Clipped frame pixels (glare) show nothing of what lies there.
  mask.setTo(0, shrunk >= kClipped);
  const cv::Mat frame = detail_of(shrunk), carried = detail_of(picture);

  std::vector<CellSums> cells(static_cast<size_t>(columns) * rows);
  for (int y = 0; y < rows * cell; ++y) {
    const uchar* in = mask.ptr<uchar>(y);
    const float* f = frame.ptr<float>(y);
    const float* m = carried.ptr<float>(y);
    const uchar* lf = shrunk.ptr<uchar>(y);
    const uchar* lm = picture.ptr<uchar>(y); // model pictures are 8-bit grey
    CellSums* row = &cells[static_cast<size_t>(y / cell) * columns];
    for (int x = 0; x < columns * cell; ++x) {
      if (!in[x])
        continue;
      CellSums& c = row[x / cell];
      c.n += 1;
      c.f += f[x];
      c.m += m[x];
      c.ff += static_cast<double>(f[x]) * f[x];
      c.mm += static_cast<double>(m[x]) * m[x];
      c.fm += static_cast<double>(f[x]) * m[x];
      c.lf += lf[x];
      c.lm += lm[x];
    }
  }
  std::vector<CellLook> looks(cells.size());
  std::vector<double> detail_ratios, level_ratios;
  const double min_fill = kMinCellFill * cell * cell;
  for (size_t i = 0; i < cells.size(); ++i) {
    const CellSums& s = cells[i];
    if (s.n < min_fill)
      continue;
    CellLook& l = looks[i];
    const double mf = s.f / s.n, mm = s.m / s.n;
    const double vf = std::max(0.0, s.ff / s.n - mf * mf), vm = s.mm / s.n - mm * mm;
    l.detail_f = std::sqrt(vf);
    l.detail_m = std::sqrt(std::max(0.0, vm));
    if (!(vm >= kMinCellTexture * kMinCellTexture)) {
      l.detail_over_plain = l.detail_f >= kMinDetailOverPlain;
      continue;
    }
    l.compared = true;
    l.level_f = s.lf / s.n;
    l.level_m = s.lm / s.n;
    if (l.detail_f < kMinFrameTexture)
      continue;
    l.correlation = (s.fm / s.n - mf * mm) / (l.detail_f * l.detail_m);
    if (shows_print(l)) {
      detail_ratios.push_back(l.detail_f / l.detail_m);
      if (l.level_m > 0.0)
        level_ratios.push_back(l.level_f / l.level_m);
    }
  }
  out.origin = box.tl();
  out.rows = rows;
  out.columns = columns;
  out.looks = std::move(looks);
  out.print_cells = static_cast<int>(detail_ratios.size());
  // How much of the print's detail and light this frame shows where the print is seen (blur,
  // exposure): the median over the cells that match.
  out.detail_kept = median(detail_ratios);
  out.light = median(level_ratios);
  return out;
}

bool shows_print(const CellLook& l) {
  return l.compared && l.detail_f >= kMinFrameTexture && l.correlation >= kMaxForeignCorrelation;
}

bool denies_print(const CellLook& l, const CellComparison& cmp) {
  if (!l.compared)
    return false;
  if (l.detail_f >= kMinFrameTexture)
    return l.correlation < kMaxForeignCorrelation;
  // Flat where the print, as this frame shows it elsewhere, would have clear detail, and not
  // brighter than the print there: a plain surface lies on it. Brighter is a highlight washing
  // the print out (or a white surface: it cannot be told).
  return cmp.print_cells >= kMinForeignCells &&
         cmp.detail_kept * l.detail_m >= kFlatCoverDetail * kMinFrameTexture &&
         l.detail_f <= kFlatCoverShare * cmp.detail_kept * l.detail_m &&
         l.level_f <= cmp.light * (l.level_m + kGlareLevels);
}

int foreign_cover_cells(const Instance& inst, const Model& model, const cv::Mat& grey,
                        const std::vector<const Instance*>& above) {
  const CellComparison cmp = compare_cells(inst, model, grey, above);
  const int rows = cmp.rows, columns = cmp.columns;
  if (rows <= 0 || columns <= 0)
    return 0;
  const std::vector<CellLook>& looks = cmp.looks;
  const bool seen_enough = cmp.print_cells >= kMinForeignCells;
  const double detail_kept = cmp.detail_kept, light = cmp.light;

  cv::Mat foreign = cv::Mat::zeros(rows, columns, CV_8UC1);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < columns; ++c) {
      const CellLook& l = looks[static_cast<size_t>(r) * columns + c];
      if (!l.compared) {
        // Texture where the print is plain, well beyond what the frame keeps of the print's
        // own faint detail there: a textured object lies on a plain part of the print.
        if (l.detail_over_plain &&
            (!seen_enough || l.detail_f >= kDetailOverPlainTimes * detail_kept * l.detail_m))
          foreign.at<uchar>(r, c) = 255;
        continue;
      }
      if (denies_print(l, cmp))
        foreign.at<uchar>(r, c) = 255;
    }

  // The cells that do not show the print: something else, or flat where no highlight washes the
  // print out. A cover seen through motion blur or in dim light is partly flat, partly smeared
  // texture: its flat cells join the cells that show something else into one group.
  cv::Mat unseen = foreign.clone();
  if (seen_enough)
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < columns; ++c) {
        const CellLook& l = looks[static_cast<size_t>(r) * columns + c];
        if (l.compared && l.detail_f < kMinFrameTexture &&
            l.level_f <= light * (l.level_m + kGlareLevels))
          unseen.at<uchar>(r, c) = 255;
      }
  cv::Mat labels, stats, centroids;
  const int groups = cv::connectedComponentsWithStats(unseen, labels, stats, centroids, 4);
  std::vector<int> other(static_cast<size_t>(groups), 0);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < columns; ++c)
      if (foreign.at<uchar>(r, c))
        ++other[static_cast<size_t>(labels.at<int>(r, c))];
  int largest = 0;
  for (int g = 1; g < groups; ++g) {
    const int cells = stats.at<int>(g, cv::CC_STAT_AREA);
    const int seen_other = other[static_cast<size_t>(g)];
    if (seen_other >= kMinForeignCells ||
        (seen_other >= kMinForeignInGroup && cells >= kMinMixedGroupCells))
      largest = std::max(largest, cells);
  }
  return largest;
}

} // namespace pickdetect::detail
