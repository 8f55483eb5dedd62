// SPDX-License-Identifier: LGPL-2.1-or-later
// The motion blur of a moving belt: its length measured on an instance, undone before SIFT.
#include "motion_blur.hpp"

#include "object_mask.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace pickdetect::detail {
namespace {

/// Wiener deconvolution's noise-to-signal ratio: where the box's spectrum is weaker than this
/// (near its zeros) the frame's frequencies are damped, not amplified into noise.
constexpr double kNoiseToSignal = 0.01;
/// Beside a strong edge (the frame's grey level stepping by kStrongEdgeStep or more across one
/// blur length, as a light box's rim on a dark belt does) the damped frequencies near the box's
/// zeros ring: bands parallel to the edge, which SIFT finds as rows of small blobs, and a model
/// of thin strokes on plain ground matches them (a hand-drawn picture found on another light
/// box's rim, its instance carried from frame to frame). There the frame is deconvolved with
/// kEdgeNoiseToSignal instead, within a blur length of the edge's ramp.
constexpr double kEdgeNoiseToSignal = 0.05;
constexpr float kStrongEdgeStep = 150.f;
/// A motion within this share of an axis (its sine or cosine) is taken along it: the rows or
/// columns are deconvolved as they are, with no rotation.
constexpr double kAxisSlack = 0.02;
/// Blur lengths are measured to this many pixels.
constexpr double kLengthStep = 0.5;
/// The blur is measured on at most this many pixels a side of the middle of the instance.
constexpr int kMeasuredSide = 160;
/// Changes of light slower than a Gaussian of this sigma (pixels) are left out of the
/// comparison: a highlight or a shadow on the object is not in its picture.
constexpr double kLightSigma = 8.0;
/// The lens's own round blur, which the frame has and the picture has not, is matched by one of
/// these Gaussian sigmas (pixels), so that the box does not stretch to stand in for it.
constexpr double kRoundBlurs[] = {0.0, 0.7, 1.4};

/// The weights of a centred box of `length` pixels on whole-pixel offsets -r..r (the end
/// pixels partly covered), summing to 1.
std::vector<double> box_weights(double length) {
  const int r = static_cast<int>(std::ceil((length - 1.0) / 2.0));
  std::vector<double> w(static_cast<size_t>(2 * r + 1));
  for (int k = -r; k <= r; ++k)
    w[static_cast<size_t>(k + r)] =
        std::max(0.0, std::min(k + 0.5, length / 2) - std::max(k - 0.5, -length / 2)) / length;
  return w;
}

/// The Wiener filter of a box blur of weights `w` (centred), for a DFT of `n` points.
std::vector<cv::Vec2f> wiener_filter(const std::vector<double>& w, int n, double noise_to_signal) {
  const int r = static_cast<int>(w.size() / 2);
  std::vector<cv::Vec2f> filter(static_cast<size_t>(n));
  for (int u = 0; u < n; ++u) {
    double re = 0.0, im = 0.0;
    for (int k = -r; k <= r; ++k) {
      const double a = -2.0 * CV_PI * u * k / n;
      re += w[static_cast<size_t>(k + r)] * std::cos(a);
      im += w[static_cast<size_t>(k + r)] * std::sin(a);
    }
    const double power = re * re + im * im + noise_to_signal;
    filter[static_cast<size_t>(u)] =
        cv::Vec2f(static_cast<float>(re / power), static_cast<float>(-im / power));
  }
  return filter;
}

/// `spectrum`'s rows (DFT_ROWS, complex) through `filter`, back to real rows.
cv::Mat filtered_rows(const cv::Mat& spectrum, const std::vector<cv::Vec2f>& filter) {
  cv::Mat product(spectrum.size(), spectrum.type());
  for (int y = 0; y < spectrum.rows; ++y) {
    const cv::Vec2f* row = spectrum.ptr<cv::Vec2f>(y);
    cv::Vec2f* out = product.ptr<cv::Vec2f>(y);
    for (int u = 0; u < spectrum.cols; ++u) {
      const cv::Vec2f a = row[u], g = filter[static_cast<size_t>(u)];
      out[u] = cv::Vec2f(a[0] * g[0] - a[1] * g[1], a[0] * g[1] + a[1] * g[0]);
    }
  }
  cv::Mat real;
  cv::idft(product, real, cv::DFT_ROWS | cv::DFT_REAL_OUTPUT | cv::DFT_SCALE);
  return real;
}

/// Where `f`'s rows step by kStrongEdgeStep or more across `length` pixels, grown by a length
/// along the rows and a pixel across them (CV_8U, 255 there).
cv::Mat strong_edges(const cv::Mat& f, double length) {
  const int half = std::max(1, static_cast<int>(std::lround(length / 2.0)));
  cv::Mat strong = cv::Mat::zeros(f.size(), CV_8UC1);
  if (f.cols <= 2 * half)
    return strong;
  cv::Mat step;
  cv::absdiff(f.colRange(2 * half, f.cols), f.colRange(0, f.cols - 2 * half), step);
  cv::Mat ramp = step >= kStrongEdgeStep;
  ramp.copyTo(strong.colRange(half, f.cols - half));
  const int reach = static_cast<int>(std::ceil(length));
  cv::dilate(strong, strong, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * reach + 1, 3)));
  return strong;
}

/// Rows of `f` (CV_32F) deconvolved from a box blur of `length` along them.
void deconvolve_rows(cv::Mat& f, double length) {
  const std::vector<double> w = box_weights(length);
  const int r = static_cast<int>(w.size() / 2);
  const int pad = std::max(32, 4 * r);
  cv::Mat padded;
  cv::copyMakeBorder(f, padded, 0, 0, pad, pad, cv::BORDER_REFLECT_101);
  const int n = cv::getOptimalDFTSize(padded.cols);
  cv::copyMakeBorder(padded, padded, 0, 0, 0, n - padded.cols, cv::BORDER_REFLECT_101);
  cv::Mat spectrum;
  cv::dft(padded, spectrum, cv::DFT_ROWS | cv::DFT_COMPLEX_OUTPUT);
  const cv::Rect frame(pad, 0, f.cols, f.rows);
  const cv::Mat strong = strong_edges(f, length);
  const cv::Mat sharp = filtered_rows(spectrum, wiener_filter(w, n, kNoiseToSignal))(frame);
  if (cv::countNonZero(strong) > 0)
    filtered_rows(spectrum, wiener_filter(w, n, kEdgeNoiseToSignal))(frame).copyTo(sharp, strong);
  sharp.copyTo(f);
}

/// A kernel blurring along `direction` (a unit vector) by a centred box of `length` pixels.
cv::Mat line_kernel(const cv::Point2f& direction, double length) {
  const int r = static_cast<int>(std::ceil(length / 2.0)) + 1;
  cv::Mat k = cv::Mat::zeros(2 * r + 1, 2 * r + 1, CV_32F);
  const int samples = std::max(1, static_cast<int>(std::ceil(length * 4)));
  for (int i = 0; i < samples; ++i) {
    const double t = (i + 0.5) / samples * length - length / 2;
    const double x = r + t * direction.x, y = r + t * direction.y;
    const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
    const double fx = x - x0, fy = y - y0;
    k.at<float>(y0, x0) += static_cast<float>((1 - fx) * (1 - fy));
    k.at<float>(y0, x0 + 1) += static_cast<float>(fx * (1 - fy));
    k.at<float>(y0 + 1, x0) += static_cast<float>((1 - fx) * fy);
    k.at<float>(y0 + 1, x0 + 1) += static_cast<float>(fx * fy);
  }
  return k / samples;
}

/// `picture` blurred along `direction` (a unit vector) by a centred box of `length` pixels, its
/// border replicated; under a pixel, as it is.
cv::Mat blurred_along(const cv::Mat& picture, const cv::Point2f& direction, double length) {
  if (length < 1.0)
    return picture;
  // Only the kernel's nonzero rows and columns (one row along the rows): filter2D's cost
  // follows the kernel's area.
  const cv::Mat kernel = line_kernel(direction, length);
  const cv::Rect used = cv::boundingRect(kernel != 0);
  cv::Mat blurred;
  cv::filter2D(picture, blurred, -1, kernel(used),
               cv::Point(kernel.cols / 2 - used.x, kernel.rows / 2 - used.y), 0,
               cv::BORDER_REPLICATE);
  return blurred;
}

/// Normalised correlation of `a` and `b` (CV_32F) over `mask`.
double correlation(const cv::Mat& a, const cv::Mat& b, const cv::Mat& mask) {
  cv::Scalar ma, sa, mb, sb;
  cv::meanStdDev(a, ma, sa, mask);
  cv::meanStdDev(b, mb, sb, mask);
  if (sa[0] <= 0.0 || sb[0] <= 0.0)
    return 0.0;
  cv::Mat da = a - ma[0], db = b - mb[0], product;
  cv::multiply(da, db, product);
  return cv::mean(product, mask)[0] / (sa[0] * sb[0]);
}

/// `f` (CV_32F) without its slow changes of light (a highlight, a shadow, shading): what is
/// left after taking out its blur of kLightSigma.
cv::Mat detail_of(const cv::Mat& f) {
  cv::Mat slow;
  cv::GaussianBlur(f, slow, cv::Size(0, 0), kLightSigma);
  return f - slow;
}

} // namespace

std::optional<double> measure_blur_length(const cv::Mat& grey, const Model& model,
                                          const cv::Matx33d& homography, const cv::Point2f& step,
                                          double least_correlation) {
  const double longest = std::hypot(step.x, step.y);
  if (model.image.empty() || model.outline.size() < 3 || !(longest > 0.0))
    return std::nullopt;
  std::vector<cv::Point2f> outline;
  cv::perspectiveTransform(model.outline, outline, cv::Matx33f(homography));
  const cv::Rect frame(cv::Point(0, 0), grey.size());
  const int margin = static_cast<int>(std::ceil(longest)) + 2;
  // The middle of the instance is enough, as for ECC (feature_reuse.cpp), at a fraction of
  // the cost.
  const cv::Rect whole = cv::boundingRect(outline);
  const int w = std::min(whole.width, kMeasuredSide), h = std::min(whole.height, kMeasuredSide);
  const cv::Rect middle(whole.x + (whole.width - w) / 2, whole.y + (whole.height - h) / 2, w, h);
  const cv::Rect box =
      cv::Rect(middle.x - margin, middle.y - margin, w + 2 * margin, h + 2 * margin) & frame;
  if (box.width < 16 || box.height < 16)
    return std::nullopt;
  // The model's picture and mask as they lie in the frame's window.
  const cv::Matx33d to_window = cv::Matx33d(1, 0, -box.x, 0, 1, -box.y, 0, 0, 1) * homography;
  cv::Mat picture, mask;
  cv::warpPerspective(model.image, picture, to_window, box.size(), cv::INTER_LINEAR,
                      cv::BORDER_REPLICATE);
  cv::warpPerspective(object_mask(model.mask, model.image.size()), mask, to_window, box.size(),
                      cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar(0));
  // Off the rim, where the belt around the object blurs in, by the longest blur and more.
  cv::erode(mask, mask,
            cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * margin + 1, 2 * margin + 1)));
  // And off the window's own edges, where the blur reaches pixels the window leaves out.
  const int edge = static_cast<int>(std::ceil(longest / 2)) + 1;
  const cv::Rect inner(edge, edge, box.width - 2 * edge, box.height - 2 * edge);
  if (inner.width <= 0 || inner.height <= 0)
    return std::nullopt;
  cv::Mat inside = cv::Mat::zeros(mask.size(), CV_8UC1);
  mask(inner).copyTo(inside(inner));
  mask = inside;
  if (cv::countNonZero(mask) < 256)
    return std::nullopt;
  cv::Mat seen, drawn;
  grey(box).convertTo(seen, CV_32F);
  picture.convertTo(drawn, CV_32F);
  const cv::Point2f direction(static_cast<float>(step.x / longest),
                              static_cast<float>(step.y / longest));
  auto blurred_by = [&](const cv::Mat& f, double length) {
    return blurred_along(f, direction, length);
  };
  // The length whose box blur of the picture is most like the frame's pixels (normalised
  // correlation of their detail, the light's slow changes left out): sensor noise and a
  // highlight are no more like one length than another. Whole pixels first, for each round
  // blur of the lens, then half a pixel either side of the best.
  const cv::Mat seen_detail = detail_of(seen), drawn_detail = detail_of(drawn);
  double best = -2.0, best_length = 0.0;
  cv::Mat best_round;
  for (const double sigma : kRoundBlurs) {
    cv::Mat round; // Its own pixels: drawn_detail stays as it is for the next sigma.
    if (sigma > 0.0)
      cv::GaussianBlur(drawn_detail, round, cv::Size(0, 0), sigma);
    else
      round = drawn_detail;
    for (double length = 0.0; length <= longest; length += 1.0) {
      const double c = correlation(blurred_by(round, length), seen_detail, mask);
      if (c > best) {
        best = c;
        best_length = length;
        best_round = round;
      }
    }
  }
  const double coarse = best_length;
  for (const double length : {coarse - kLengthStep, coarse + kLengthStep}) {
    if (length < 1.0 || length > longest)
      continue;
    const double c = correlation(blurred_by(best_round, length), seen_detail, mask);
    if (c > best) {
      best = c;
      best_length = length;
    }
  }
  // The instance must lie there: its blurred picture like the frame's pixels.
  if (correlation(blurred_by(drawn, best_length), seen, mask) < least_correlation)
    return std::nullopt;
  return best_length;
}

cv::Mat motion_blurred(const cv::Mat& picture, const cv::Point2f& blur) {
  const double length = std::hypot(blur.x, blur.y);
  if (!(length >= 1.0))
    return picture;
  return blurred_along(
      picture,
      cv::Point2f(static_cast<float>(blur.x / length), static_cast<float>(blur.y / length)),
      length);
}

cv::Mat undo_motion_blur(const cv::Mat& grey, const cv::Point2f& blur) {
  CV_Assert(grey.type() == CV_8UC1);
  const double length = std::hypot(blur.x, blur.y);
  if (!(length >= kLeastBlurPx) || grey.empty())
    return grey;
  const double c = blur.x / length, s = blur.y / length;
  cv::Mat f, out;
  grey.convertTo(f, CV_32F);
  if (std::abs(s) <= kAxisSlack) {
    deconvolve_rows(f, length);
  } else if (std::abs(c) <= kAxisSlack) {
    cv::Mat t = f.t();
    deconvolve_rows(t, length);
    f = t.t();
  } else {
    // Turned so that the motion runs along the rows, on a canvas that holds the whole frame.
    const double degrees = std::atan2(s, c) * 180.0 / CV_PI;
    const cv::Point2f centre(static_cast<float>(grey.cols - 1) / 2.f,
                             static_cast<float>(grey.rows - 1) / 2.f);
    const cv::Rect2f bounds =
        cv::RotatedRect(centre, grey.size(), static_cast<float>(degrees)).boundingRect2f();
    cv::Mat turn = cv::getRotationMatrix2D(centre, degrees, 1.0);
    turn.at<double>(0, 2) += bounds.width / 2.0 - centre.x;
    turn.at<double>(1, 2) += bounds.height / 2.0 - centre.y;
    cv::Mat turned;
    cv::warpAffine(f, turned, turn,
                   cv::Size(static_cast<int>(std::ceil(bounds.width)),
                            static_cast<int>(std::ceil(bounds.height))),
                   cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    deconvolve_rows(turned, length);
    cv::warpAffine(turned, f, turn, grey.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                   cv::BORDER_REPLICATE);
  }
  f.convertTo(out, CV_8U);
  return out;
}

} // namespace pickdetect::detail
