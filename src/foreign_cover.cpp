// SPDX-License-Identifier: LGPL-2.1-or-later
#include "foreign_cover.hpp"

#include "median.hpp"
#include "motion_blur.hpp"
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
/// Under this share of the object's own pixels in a blur's reach, the blur is taken as that
/// share (a pixel that far from the object is not compared anyway).
constexpr double kLeastWeight = 1e-3;

/// Per cell: compared pixels, sums of the band-passed frame f and model m (and their squares
/// and product), and of the shrunk grey levels of both (lf, lm); under a motion blur, the
/// band-passed picture before it (t, and its squares), which tells where it has texture; with
/// colour, the pixels whose colour is compared (nc) and the sums of the frame's and the model's
/// channels (BGR).
struct CellSums {
  double n = 0, f = 0, m = 0, ff = 0, mm = 0, fm = 0, lf = 0, lm = 0, t = 0, tt = 0;
  double nc = 0;
  cv::Vec3d cf, cm;
};

/// Hue (degrees) and saturation (the channels' spread over the largest) of a BGR colour.
void hue_saturation(const cv::Vec3d& bgr, double& hue, double& saturation) {
  const double hi = std::max({bgr[0], bgr[1], bgr[2]}), lo = std::min({bgr[0], bgr[1], bgr[2]});
  saturation = hi > 0.0 ? (hi - lo) / hi : 0.0;
  hue = std::atan2(0.8660254 * (bgr[1] - bgr[0]), bgr[2] - 0.5 * (bgr[1] + bgr[0])) * 180.0 / CV_PI;
}

/// Whether the frame's colour `f` in a cell is another than the print's `m` there (both BGR
/// means, the frame's already scaled to the print's light): see kMaxHueTurn.
bool colour_differs(const cv::Vec3d& f, const cv::Vec3d& m) {
  const double level_f = (f[0] + f[1] + f[2]) / 3.0, level_m = (m[0] + m[1] + m[2]) / 3.0;
  if (level_f < kMinColourLevel || level_m < kMinColourLevel)
    return false;
  double hue_f, sat_f, hue_m, sat_m;
  hue_saturation(f, hue_f, sat_f);
  hue_saturation(m, hue_m, sat_m);
  if (sat_f >= kMinCellSaturation && sat_m >= kMinCellSaturation)
    return std::abs(std::remainder(hue_f - hue_m, 360.0)) > kMaxHueTurn;
  // Grey where the print has clear colour: a grey object, unless as light as the print or
  // lighter (a highlight washes the print out towards white; a white object cannot be told
  // from it).
  if (sat_f < kGreySaturation && sat_m >= kClearSaturation)
    return level_f < level_m;
  return sat_m < kGreySaturation && sat_f >= kClearSaturation;
}

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

/// The object's own pixels (1, elsewhere 0) and their share under each of the band-pass's
/// blurs.
struct OwnPixels {
  cv::Mat weight, fine, light;
};

OwnPixels own_pixels(const cv::Mat& mask) {
  OwnPixels own;
  mask.convertTo(own.weight, CV_32F, 1.0 / 255.0);
  own.fine = twice_boxed(own.weight, kFineBox);
  own.light = twice_boxed(own.weight, kLightBox);
  return own;
}

/// detail_of with each blur taken over the object's own pixels only (a normalised convolution:
/// the blur of the pixels weighted by `own`, over the blur of the weights), so that what lies
/// beside the object does not reach into its rim.
cv::Mat detail_within(const cv::Mat& grey, const OwnPixels& own) {
  cv::Mat picture;
  grey.convertTo(picture, CV_32F);
  picture = picture.mul(own.weight);
  cv::Mat fine, light;
  cv::divide(twice_boxed(picture, kFineBox), cv::max(own.fine, kLeastWeight), fine);
  cv::divide(twice_boxed(picture, kLightBox), cv::max(own.light, kLeastWeight), light);
  return fine - light;
}

/// `picture` carried by `map` into a window of `size` and blurred by `blur` (window pixels) as
/// the frame is: warped with a margin of the blur's reach, so that what lies past the window's
/// edge (the frame's) blurs in as it does in the frame.
cv::Mat blurred_warp(const cv::Mat& picture, const cv::Matx33d& map, const cv::Size& size,
                     const cv::Point2f& blur) {
  const int r = static_cast<int>(std::ceil(std::hypot(blur.x, blur.y) / 2.0)) + 1;
  const cv::Matx33d shift(1, 0, r, 0, 1, r, 0, 0, 1);
  cv::Mat wide;
  cv::warpPerspective(picture, wide, cv::Mat(shift * map), size + cv::Size(2 * r, 2 * r),
                      cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  return motion_blurred(wide, blur)(cv::Rect(r, r, size.width, size.height)).clone();
}

} // namespace

CellComparison compare_cells(const Instance& inst, const Model& model, const cv::Mat& grey,
                             const std::vector<const Instance*>& above, const cv::Rect& within,
                             const cv::Mat& colour, const cv::Point2f& motion_blur) {
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
  // In a frame blurred by motion the print is compared as the frame shows it, blurred the same
  // way (the blur in shrunk pixels); where it has texture is still told by the picture itself.
  const bool blurred = std::hypot(motion_blur.x, motion_blur.y) >= kLeastBlurPx;
  const cv::Point2f blur = motion_blur * static_cast<float>(k);
  const cv::Mat sharp = picture;
  if (blurred)
    picture = blurred_warp(model.image, to_box, size, blur);
  // A model without a mask is all object.
  cv::warpPerspective(object_mask(model.mask, model.image.size()), mask, cv::Mat(to_box), size,
                      cv::INTER_NEAREST, cv::BORDER_CONSTANT);
  for (const Instance* other : above)
    if (other->outline.size() >= 3)
      cv::fillPoly(mask, std::vector<std::vector<cv::Point>>{mapped(other->outline, to_small)},
                   cv::Scalar(0));
  // What lies beside the object (a dark belt, a neighbour, the comparison window's edge across
  // a turned box) would reach into its rim through the band-pass's blurs as detail the print
  // does not have there: on a sharp frame both pictures are band-passed over the object's own
  // pixels only (those of `above` are not its own). Under a motion blur the frame's rim holds
  // what lies beside the object already, smeared over the blur's length, and the picture is
  // carried through the same blur: both are band-passed as they are.
  const OwnPixels own = blurred ? OwnPixels() : own_pixels(mask);
  // Near the edges of what is seen of the object the blurs mix in what lies beside it (more
  // so under motion blur): only the inside is compared.
  cv::erode(
      mask, mask,
      cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * kEdgeMargin + 1, 2 * kEdgeMargin + 1)),
      cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::Mat shrunk;
  cv::resize(grey(box), shrunk, size, 0, 0, cv::INTER_AREA);
  // The frame's colours, when it has them, and the picture's, when both have them, at the same
  // size.
  const bool frame_in_colour =
      !colour.empty() && colour.type() == CV_8UC3 && colour.size() == grey.size();
  const bool in_colour = frame_in_colour && !model.colour.empty() &&
                         model.colour.type() == CV_8UC3 &&
                         model.colour.size() == model.image.size();
  cv::Mat shrunk_colour, picture_colour;
  if (frame_in_colour)
    cv::resize(colour(box), shrunk_colour, size, 0, 0, cv::INTER_AREA);
  if (in_colour && blurred)
    picture_colour = blurred_warp(model.colour, to_box, size, blur);
  else if (in_colour)
    cv::warpPerspective(model.colour, picture_colour, cv::Mat(to_box), size, cv::INTER_LINEAR,
                        cv::BORDER_REPLICATE);
  // Clipped frame pixels (glare) show nothing of what lies there.
  mask.setTo(0, shrunk >= kClipped);
  const auto band_pass = [&](const cv::Mat& grey_levels) {
    return blurred ? detail_of(grey_levels) : detail_within(grey_levels, own);
  };
  const cv::Mat frame = band_pass(shrunk), carried = band_pass(picture);
  // Unblurred, the picture's own texture is `carried` itself (its sums m and mm).
  const cv::Mat textured = blurred ? detail_of(sharp) : cv::Mat();

  std::vector<CellSums> cells(static_cast<size_t>(columns) * rows);
  for (int y = 0; y < rows * cell; ++y) {
    const uchar* in = mask.ptr<uchar>(y);
    const float* f = frame.ptr<float>(y);
    const float* m = carried.ptr<float>(y);
    const float* t = blurred ? textured.ptr<float>(y) : nullptr;
    const uchar* lf = shrunk.ptr<uchar>(y);
    const uchar* lm = picture.ptr<uchar>(y); // model pictures are 8-bit grey
    const cv::Vec3b* cf = frame_in_colour ? shrunk_colour.ptr<cv::Vec3b>(y) : nullptr;
    const cv::Vec3b* cm = in_colour ? picture_colour.ptr<cv::Vec3b>(y) : nullptr;
    CellSums* row = &cells[static_cast<size_t>(y / cell) * columns];
    for (int x = 0; x < columns * cell; ++x) {
      if (!in[x])
        continue;
      CellSums& c = row[x / cell];
      // A channel at the top may be clipped: its colour is not the object's.
      if (frame_in_colour && cf[x][0] < kClipped && cf[x][1] < kClipped && cf[x][2] < kClipped) {
        c.nc += 1;
        c.cf += cv::Vec3d(cf[x][0], cf[x][1], cf[x][2]);
        if (in_colour)
          c.cm += cv::Vec3d(cm[x][0], cm[x][1], cm[x][2]);
      }
      c.n += 1;
      c.f += f[x];
      c.m += m[x];
      c.ff += static_cast<double>(f[x]) * f[x];
      c.mm += static_cast<double>(m[x]) * m[x];
      c.fm += static_cast<double>(f[x]) * m[x];
      if (t) {
        c.t += t[x];
        c.tt += static_cast<double>(t[x]) * t[x];
      }
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
    const double mt = s.t / s.n; // The picture's own texture:
    const double vt = blurred ? s.tt / s.n - mt * mt : vm;
    l.detail_f = std::sqrt(vf);
    l.detail_m = std::sqrt(std::max(0.0, vm));
    if (!(vt >= kMinCellTexture * kMinCellTexture)) {
      l.detail_over_plain = l.detail_f >= kMinDetailOverPlain;
      continue;
    }
    l.compared = true;
    l.level_f = s.lf / s.n;
    l.level_m = s.lm / s.n;
    if (s.nc >= min_fill) {
      const cv::Vec3d f = s.cf / s.nc;
      double hue, saturation;
      hue_saturation(f, hue, saturation);
      l.clear_colour =
          saturation >= kClearSaturation && (f[0] + f[1] + f[2]) / 3.0 >= kMinColourLevel;
    }
    if (l.detail_f < kMinFrameTexture)
      continue;
    l.correlation = (s.fm / s.n - mf * mm) / (l.detail_f * l.detail_m);
    if (shows_print(l)) {
      detail_ratios.push_back(l.detail_f / l.detail_m);
      if (l.level_m > 0.0)
        level_ratios.push_back(l.level_f / l.level_m);
    }
  }
  if (in_colour) {
    // The frame's channels scaled to the print's (the light's colour and gain): by the medians,
    // over the cells, of their ratios.
    std::vector<double> ratios[3];
    for (const CellSums& c : cells)
      if (c.nc >= min_fill)
        for (int k = 0; k < 3; ++k)
          if (c.cm[k] / c.nc >= kMinColourLevel)
            ratios[k].push_back(c.cf[k] / c.cm[k]);
    cv::Vec3d gain;
    for (int k = 0; k < 3; ++k)
      gain[k] = median(ratios[k]);
    if (std::isfinite(gain[0]) && std::isfinite(gain[1]) && std::isfinite(gain[2]) &&
        gain[0] > 0.0 && gain[1] > 0.0 && gain[2] > 0.0)
      for (size_t i = 0; i < cells.size(); ++i) {
        const CellSums& c = cells[i];
        if (c.nc < min_fill)
          continue;
        const cv::Vec3d f = c.cf / c.nc, m = c.cm / c.nc;
        looks[i].other_colour =
            colour_differs(f, cv::Vec3d(m[0] * gain[0], m[1] * gain[1], m[2] * gain[2]));
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

bool may_be_glare(const CellLook& l, double light) {
  return l.level_f > light * (l.level_m + kGlareLevels) && !l.clear_colour;
}

bool denies_print(const CellLook& l, const CellComparison& cmp) {
  if (!l.compared)
    return false;
  if (l.detail_f >= kMinFrameTexture)
    return l.correlation < kMaxForeignCorrelation;
  // Flat where the print, as this frame shows it elsewhere, would have clear detail, and no
  // highlight: a plain surface lies on it.
  return cmp.print_cells >= kMinForeignCells &&
         cmp.detail_kept * l.detail_m >= kFlatCoverDetail * kMinFrameTexture &&
         l.detail_f <= kFlatCoverShare * cmp.detail_kept * l.detail_m &&
         !may_be_glare(l, cmp.light);
}

int foreign_cover_cells(const Instance& inst, const Model& model, const cv::Mat& grey,
                        const std::vector<const Instance*>& above, const cv::Mat& colour,
                        const cv::Point2f& motion_blur) {
  const CellComparison cmp =
      compare_cells(inst, model, grey, above, cv::Rect(), colour, motion_blur);
  const int rows = cmp.rows, columns = cmp.columns;
  if (rows <= 0 || columns <= 0)
    return 0;
  const std::vector<CellLook>& looks = cmp.looks;
  const bool seen_enough = cmp.print_cells >= kMinForeignCells;
  const double detail_kept = cmp.detail_kept;

  cv::Mat foreign = cv::Mat::zeros(rows, columns, CV_8UC1);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < columns; ++c) {
      const CellLook& l = looks[static_cast<size_t>(r) * columns + c];
      if (l.other_colour) { // Another colour than the print's, plain or printed.
        foreign.at<uchar>(r, c) = 255;
        continue;
      }
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

  // The cells that do not show the print: something else, or flat. A cover seen through motion
  // blur or in dim light is partly flat, partly smeared texture: its flat cells join the cells
  // that show something else into one group. So do flat cells lighter than the print, which
  // count for nothing themselves (a highlight washing the print out, or a light plain surface):
  // a light lid has a sharp rim that shows something else around its flat inside, where a
  // highlight fades into the print around it.
  cv::Mat unseen = foreign.clone();
  if (seen_enough)
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < columns; ++c) {
        const CellLook& l = looks[static_cast<size_t>(r) * columns + c];
        if (l.compared && l.detail_f < kMinFrameTexture)
          unseen.at<uchar>(r, c) = 255;
      }
  cv::Mat labels, stats, centroids;
  const int groups = cv::connectedComponentsWithStats(unseen, labels, stats, centroids, 4);
  std::vector<int> other(static_cast<size_t>(groups), 0);
  // Per group: whether two of its cells of another colour lie side by side.
  std::vector<char> colour_pair(static_cast<size_t>(groups), 0);
  auto other_colour = [&](int r, int c) {
    return r < rows && c < columns && looks[static_cast<size_t>(r) * columns + c].other_colour;
  };
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < columns; ++c) {
      if (!foreign.at<uchar>(r, c))
        continue;
      const size_t g = static_cast<size_t>(labels.at<int>(r, c));
      ++other[g];
      if (other_colour(r, c) && (other_colour(r, c + 1) || other_colour(r + 1, c)))
        colour_pair[g] = 1;
    }
  int largest = 0;
  for (int g = 1; g < groups; ++g) {
    const int cells = stats.at<int>(g, cv::CC_STAT_AREA);
    const int seen_other = other[static_cast<size_t>(g)];
    if (seen_other >= kMinForeignCells ||
        (seen_other >= kMinForeignInGroup && cells >= kMinMixedGroupCells) ||
        colour_pair[static_cast<size_t>(g)])
      largest = std::max(largest, cells);
  }
  return largest;
}

} // namespace pickdetect::detail
