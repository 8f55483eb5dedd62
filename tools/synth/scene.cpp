// SPDX-License-Identifier: LGPL-2.1-or-later
// Scenes: floors (bin or belt), distractors, foreign covers, the placement of instances in heaps
// and along belts, and the rendering that measures each instance's layers for its ground truth.
#include "synth.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>

namespace synth {

/// Model pixels -> frame pixels: tilt about an in-plane axis (perspective seen from above),
/// then scale, rotation (clockwise on screen, y down) and translation of the model's centre.
cv::Matx33d placement(const ModelPicture& m, double angle, double scale, double tilt,
                      double tilt_axis, cv::Point2d at) {
  const cv::Point2d c = m.principal_points[0];
  const double focal = 3.0 * std::max(m.bgr.cols, m.bgr.rows);
  const double ca = std::cos(tilt_axis), sa = std::sin(tilt_axis);
  const double t = tilt * CV_PI / 180.0, r = angle * CV_PI / 180.0;
  auto map = [&](cv::Point2d p) {
    const double x = p.x - c.x, y = p.y - c.y;
    // Rotate by `t` about the axis (ca, sa, 0): the component across the axis leaves the plane.
    const double along = x * ca + y * sa, across = -x * sa + y * ca;
    const double across_in = across * std::cos(t), z = across * std::sin(t);
    double px = along * ca - across_in * sa, py = along * sa + across_in * ca;
    px *= focal / (focal + z);
    py *= focal / (focal + z);
    px *= scale;
    py *= scale;
    return cv::Point2f(static_cast<float>(at.x + std::cos(r) * px - std::sin(r) * py),
                       static_cast<float>(at.y + std::sin(r) * px + std::cos(r) * py));
  };
  const double w = m.bgr.cols, h = m.bgr.rows;
  const cv::Point2f from[4] = {{0.f, 0.f},
                               {static_cast<float>(w), 0.f},
                               {static_cast<float>(w), static_cast<float>(h)},
                               {0.f, static_cast<float>(h)}};
  const cv::Point2f to[4] = {map({0, 0}), map({w, 0}), map({w, h}), map({0, h})};
  return cv::Matx33d(cv::getPerspectiveTransform(from, to));
}

std::vector<cv::Point2d> apply(const cv::Matx33d& h, const std::vector<cv::Point2d>& pts) {
  std::vector<cv::Point2d> out;
  for (const cv::Point2d& p : pts) {
    const cv::Vec3d q = h * cv::Vec3d(p.x, p.y, 1.0);
    out.emplace_back(q[0] / q[2], q[1] / q[2]);
  }
  return out;
}

cv::Mat background(const std::string& kind, cv::Size size, Random& rng) {
  cv::Mat noise(size, CV_32FC1);
  cv::randn(noise, 0.0, 1.0); // seeded below
  cv::Mat bg(size, CV_32FC3);
  if (kind == "bin") {
    const cv::Scalar base(rng.uniform(60, 110), rng.uniform(70, 120), rng.uniform(80, 130));
    bg.setTo(base);
    cv::Mat coarse;
    cv::GaussianBlur(noise, coarse, cv::Size(0, 0), 6.0);
    cv::Mat coarse3;
    cv::merge(std::vector<cv::Mat>{coarse, coarse, coarse}, coarse3);
    bg += coarse3 * 40.0;
    // Darker walls of the bin around the floor.
    const int wall = static_cast<int>(std::min(size.width, size.height) * 0.06);
    cv::rectangle(bg, cv::Rect(0, 0, size.width, size.height), cv::Scalar(40, 40, 45), wall);
  } else {
    const double grey = rng.uniform(35, 70);
    bg.setTo(cv::Scalar(grey, grey, grey * 1.05));
    // Belt texture: fine horizontal weave and the two rails.
    for (int y = 0; y < size.height; y += 6)
      cv::line(bg, {0, y}, {size.width, y}, cv::Scalar::all(grey * 0.85), 1);
    const int rail = size.height / 12;
    cv::rectangle(bg, cv::Rect(0, 0, size.width, rail), cv::Scalar(150, 150, 155), cv::FILLED);
    cv::rectangle(bg, cv::Rect(0, size.height - rail, size.width, rail), cv::Scalar(150, 150, 155),
                  cv::FILLED);
    cv::Mat noise3;
    cv::merge(std::vector<cv::Mat>{noise, noise, noise}, noise3);
    bg += noise3 * 6.0;
  }
  return bg;
}

void draw_distractors(cv::Mat& bg, int count, Random& rng) {
  for (int i = 0; i < count; ++i) {
    const cv::Point c(rng.integer(0, bg.cols - 1), rng.integer(0, bg.rows - 1));
    const cv::Size axes(rng.integer(20, bg.cols / 8), rng.integer(10, bg.rows / 10));
    const cv::Scalar colour(rng.uniform(20, 230), rng.uniform(20, 230), rng.uniform(20, 230));
    if (rng.chance(0.5)) {
      cv::ellipse(bg, c, axes, rng.uniform(0, 180), 0, 360, colour, cv::FILLED, cv::LINE_AA);
    } else {
      const cv::RotatedRect r(
          c, cv::Size2f(static_cast<float>(axes.width * 2), static_cast<float>(axes.height * 2)),
          static_cast<float>(rng.uniform(0, 180)));
      cv::Point2f v[4];
      r.points(v);
      std::vector<cv::Point> poly(v, v + 4);
      cv::fillConvexPoly(bg, poly, colour, cv::LINE_AA);
      // Print-like stripes so that distractors carry texture (and features) too.
      for (int k = 0; k < 6; ++k)
        cv::line(bg, poly[0] + (poly[1] - poly[0]) * k / 6, poly[3] + (poly[2] - poly[3]) * k / 6,
                 colour * 0.5, 2, cv::LINE_AA);
    }
  }
}

namespace {

/// A foreign object over a random instance: a striped box or a plain ellipse a fifth to a half
/// of the instance's shorter side, centred on a random point of its picture. Drawn on the frame
/// (`bg`, CV_32FC3) and marked as -2 (nobody's) in `owner` (the canvas, `margin` around the
/// frame), so the instances' truth counts it as covering.
void draw_cover(cv::Mat& bg, cv::Mat& owner, int margin, const std::vector<ModelPicture>& models,
                const std::vector<Placed>& placed, Random& rng) {
  const Placed& target =
      placed[static_cast<size_t>(rng.integer(0, static_cast<int>(placed.size()) - 1))];
  const ModelPicture& m = models[static_cast<size_t>(target.model)];
  const cv::Point2d on =
      apply(target.homography, {{rng.uniform(0, m.bgr.cols), rng.uniform(0, m.bgr.rows)}})[0];
  const double side = std::min(m.bgr.cols, m.bgr.rows) * target.scale;
  const cv::Size2f size(static_cast<float>(rng.uniform(0.2, 0.5) * side),
                        static_cast<float>(rng.uniform(0.2, 0.5) * side));
  const float angle = static_cast<float>(rng.uniform(0, 180));
  const cv::Scalar colour(rng.uniform(20, 230), rng.uniform(20, 230), rng.uniform(20, 230));
  const bool box = rng.chance(0.6);
  auto draw = [&](cv::Mat& image, cv::Point2d offset, const cv::Scalar& fill, bool stripes) {
    const cv::RotatedRect r(
        cv::Point2f(static_cast<float>(on.x + offset.x), static_cast<float>(on.y + offset.y)), size,
        angle);
    if (!box) {
      cv::ellipse(image, r, fill, cv::FILLED, cv::LINE_8);
      return;
    }
    cv::Point2f v[4];
    r.points(v);
    std::vector<cv::Point> poly;
    for (const cv::Point2f& p : v)
      poly.emplace_back(cvRound(p.x), cvRound(p.y));
    cv::fillConvexPoly(image, poly, fill, cv::LINE_8);
    if (stripes) // print-like texture, so that the cover has features of its own
      for (int k = 1; k < 6; ++k)
        cv::line(image, poly[0] + (poly[1] - poly[0]) * k / 6,
                 poly[3] + (poly[2] - poly[3]) * k / 6, fill * 0.5, 2, cv::LINE_8);
  };
  draw(bg, {0, 0}, colour, true);
  draw(owner, cv::Point2d(margin, margin), cv::Scalar(-2), false);
}

} // namespace

/// Draws the instances in order (z = index) over `bg` (CV_32FC3, frame size) and measures the
/// layers on a canvas with `margin` pixels around the frame.
Rendered render(cv::Mat bg, const std::vector<ModelPicture>& models,
                const std::vector<Placed>& placed, Random& rng, int margin, const Extras& extras) {
  const cv::Size frame = bg.size();
  const cv::Size canvas(frame.width + 2 * margin, frame.height + 2 * margin);
  const cv::Matx33d shift(1, 0, margin, 0, 1, margin, 0, 0, 1);
  const cv::Rect inner(margin, margin, frame.width, frame.height);

  cv::Mat owner(canvas, CV_16SC1, cv::Scalar(-1)); // top-most instance per pixel
  struct Layer {
    cv::Rect rect; ///< On the canvas.
    cv::Mat mask;  ///< The instance's pixels within rect.
  };
  std::vector<Layer> layers;
  Rendered out;
  const cv::Point2d shadow_offset(rng.uniform(-8, 8), rng.uniform(3, 10));
  const double shadow_blur = 5.0;
  for (size_t i = 0; i < placed.size(); ++i) {
    const Placed& p = placed[i];
    const ModelPicture& m = models[static_cast<size_t>(p.model)];
    const cv::Matx33d h = p.homography;
    const double w = m.bgr.cols, hh = m.bgr.rows;
    const std::vector<cv::Point2d> corners = apply(h, {{0, 0}, {w, 0}, {w, hh}, {0, hh}});
    std::vector<cv::Point2f> cf;
    for (const cv::Point2d& c : corners)
      cf.emplace_back(static_cast<float>(c.x), static_cast<float>(c.y));
    const cv::Rect box = cv::boundingRect(cf);

    // The layer on the canvas (every part of the instance, in the frame or not).
    const cv::Rect rc = (box + cv::Point(margin, margin) - cv::Point(2, 2) + cv::Size(4, 4)) &
                        cv::Rect(cv::Point(0, 0), canvas);
    Layer layer{rc, cv::Mat()};
    if (!rc.empty()) {
      const cv::Matx33d to_rc(1, 0, margin - rc.x, 0, 1, margin - rc.y, 0, 0, 1);
      cv::Mat alpha;
      cv::warpPerspective(m.alpha, alpha, cv::Mat(to_rc * h), rc.size(), cv::INTER_LINEAR,
                          cv::BORDER_CONSTANT, cv::Scalar(0));
      layer.mask = alpha >= 128;
      owner(rc).setTo(static_cast<short>(i), layer.mask);
    }
    layers.push_back(layer);

    // Drop shadow, then the object itself, on the frame (within the instance's reach).
    const int reach = static_cast<int>(std::ceil(std::abs(shadow_offset.x) +
                                                 std::abs(shadow_offset.y) + 4 * shadow_blur)) +
                      2;
    const cv::Rect rf = (box - cv::Point(reach, reach) + cv::Size(2 * reach, 2 * reach)) &
                        cv::Rect(cv::Point(0, 0), frame);
    if (rf.empty())
      continue;
    const cv::Matx33d to_rf(1, 0, -rf.x, 0, 1, -rf.y, 0, 0, 1);
    cv::Mat a;
    cv::warpPerspective(m.alpha, a, cv::Mat(to_rf * h), rf.size(), cv::INTER_LINEAR,
                        cv::BORDER_CONSTANT, cv::Scalar(0));
    a.convertTo(a, CV_32F, 1.0 / 255.0);
    cv::Mat shadow;
    const cv::Matx23d move(1, 0, shadow_offset.x, 0, 1, shadow_offset.y);
    cv::warpAffine(a, shadow, cv::Mat(move), rf.size());
    cv::GaussianBlur(shadow, shadow, cv::Size(0, 0), shadow_blur);
    cv::Mat shade;
    cv::merge(std::vector<cv::Mat>{shadow, shadow, shadow}, shade);
    cv::Mat region = bg(rf);
    region = region.mul(cv::Scalar::all(1.0) - shade * 0.45);

    cv::Mat look;
    m.bgr.convertTo(look, CV_32FC3, p.brightness);
    if (p.highlight) {
      cv::Mat spot(look.size(), CV_32FC1, cv::Scalar(0));
      const double radius = 0.18 * std::min(look.cols, look.rows);
      cv::circle(spot, p.highlight_at, static_cast<int>(radius), cv::Scalar(1.0), cv::FILLED);
      cv::GaussianBlur(spot, spot, cv::Size(0, 0), radius / 2);
      cv::Mat spot3;
      cv::merge(std::vector<cv::Mat>{spot, spot, spot}, spot3);
      look += spot3 * 150.0;
    }
    cv::Mat warped;
    cv::warpPerspective(look, warped, cv::Mat(to_rf * h), rf.size(), cv::INTER_LINEAR,
                        cv::BORDER_CONSTANT);
    cv::Mat a3;
    cv::merge(std::vector<cv::Mat>{a, a, a}, a3);
    region = region.mul(cv::Scalar::all(1.0) - a3) + warped.mul(a3);
    region.copyTo(bg(rf));
  }
  for (int k = 0; k < extras.covers && !placed.empty(); ++k)
    draw_cover(bg, owner, margin, models, placed, *extras.cover_rng);
  // What lies on an instance: a cover, or an instance of a higher level. Without levels each
  // instance is its own (its z), so that is any other owner; with them (--packed) a neighbour
  // of the same layer that touches it takes the shared edge's pixels but covers nothing.
  std::vector<int> level(placed.size());
  for (size_t i = 0; i < placed.size(); ++i)
    level[i] = placed[i].level < 0 ? static_cast<int>(i) : placed[i].level;
  for (size_t i = 0; i < placed.size(); ++i) {
    const Placed& p = placed[i];
    const ModelPicture& m = models[static_cast<size_t>(p.model)];
    Rendered::Truth t;
    t.model = p.model;
    t.points = apply(p.homography, m.principal_points);
    t.polygon = apply(p.homography, m.polygon);
    t.angle = p.angle;
    t.scale = p.scale;
    t.tilt = p.tilt;
    t.z = static_cast<int>(i);
    t.track = p.track;
    const Layer& layer = layers[i];
    if (!layer.mask.empty()) {
      const cv::Mat mine = owner(layer.rect) == static_cast<short>(i);
      const double total = cv::countNonZero(layer.mask);
      cv::Mat on_top = layer.mask & ~mine;
      const cv::Mat under = owner(layer.rect);
      for (int y = 0; y < on_top.rows; ++y) {
        uchar* row = on_top.ptr<uchar>(y);
        const short* who = under.ptr<short>(y);
        for (int x = 0; x < on_top.cols; ++x)
          if (row[x] && who[x] >= 0 && level[static_cast<size_t>(who[x])] <= level[i])
            row[x] = 0;
      }
      const cv::Mat seen = layer.mask & mine;
      const cv::Rect in = (inner & layer.rect) - layer.rect.tl();
      if (total > 0) {
        t.covered = cv::countNonZero(on_top) / total;
        t.in_frame = in.empty() ? 0.0 : cv::countNonZero(layer.mask(in)) / total;
        t.visible = in.empty() ? 0.0 : cv::countNonZero(seen(in)) / total;
      }
    }
    out.truth.push_back(t);
  }

  // Lighting gradient across the frame.
  cv::Mat ramp(frame, CV_32FC1);
  const double dir = rng.uniform(0, 2 * CV_PI), lo = rng.uniform(0.65, 0.95),
               hi = rng.uniform(1.0, 1.25);
  const double cx = std::cos(dir), cy = std::sin(dir);
  const double span = std::abs(cx) * frame.width + std::abs(cy) * frame.height;
  const double start = std::min(0.0, cx * frame.width) + std::min(0.0, cy * frame.height);
  for (int y = 0; y < frame.height; ++y) {
    float* row = ramp.ptr<float>(y);
    for (int x = 0; x < frame.width; ++x)
      row[x] = static_cast<float>(lo + (hi - lo) * ((cx * x + cy * y - start) / span));
  }
  cv::Mat ramp3;
  cv::merge(std::vector<cv::Mat>{ramp, ramp, ramp}, ramp3);
  bg = bg.mul(ramp3);
  if (extras.glare > 0)
    add_glare(bg, models, placed, extras.glare, *extras.glare_rng);
  // Optics and sensor.
  const double sigma = rng.uniform(0.0, 1.3);
  if (sigma > 0.3)
    cv::GaussianBlur(bg, bg, cv::Size(0, 0), sigma);
  if (rng.chance(0.3)) {
    const int length = rng.integer(3, 9);
    cv::Mat kernel(length, length, CV_32FC1, cv::Scalar(0));
    const double a = rng.uniform(0, CV_PI);
    const cv::Point2d c((length - 1) / 2.0, (length - 1) / 2.0), d(std::cos(a), std::sin(a));
    cv::line(kernel, c - d * (length / 2.0), c + d * (length / 2.0), cv::Scalar(1.0), 1);
    kernel /= cv::sum(kernel)[0];
    if (!extras.fixed_blur)
      cv::filter2D(bg, bg, -1, kernel);
  }
  cv::Mat noise(frame, CV_32FC3);
  cv::randn(noise, 0.0, rng.uniform(1.5, 5.0));
  bg += noise;
  bg.convertTo(out.image, CV_8UC3);
  return out;
}

/// Places instances for one scene of the given kind.
std::vector<Placed> place(const std::string& kind, const std::vector<ModelPicture>& models,
                          const std::vector<int>& allowed, const Settings& s, Random& rng) {
  const int n = rng.integer(s.min_instances, s.max_instances);
  const double w = s.size.width, h = s.size.height;
  const cv::Point2d heap(rng.uniform(0.35 * w, 0.65 * w), rng.uniform(0.35 * h, 0.65 * h));
  std::vector<Placed> out;
  for (int i = 0; i < n; ++i) {
    Placed p;
    p.model = allowed[static_cast<size_t>(rng.integer(0, static_cast<int>(allowed.size()) - 1))];
    const ModelPicture& m = models[static_cast<size_t>(p.model)];
    p.angle = rng.uniform(0, 360);
    p.scale = rng.uniform(s.min_scale, s.max_scale);
    p.tilt = rng.uniform(0, s.max_tilt);
    const double axis = rng.uniform(0, CV_PI);
    cv::Point2d at;
    if (kind == "bin") {
      at = {std::clamp(rng.normal(heap.x, 0.16 * w), 0.05 * w, 0.95 * w),
            std::clamp(rng.normal(heap.y, 0.16 * h), 0.05 * h, 0.95 * h)};
    } else {
      // Along the belt, spread out, some entering or leaving at the sides.
      at = {(i + rng.uniform(0.1, 0.9)) * (w * 1.1 / n) - 0.05 * w,
            rng.uniform(0.25 * h, 0.75 * h)};
    }
    p.homography = placement(m, p.angle, p.scale, p.tilt, axis, at);
    p.brightness = rng.uniform(0.75, 1.2);
    p.highlight = rng.chance(0.35);
    p.highlight_at = {rng.uniform(0, m.bgr.cols), rng.uniform(0, m.bgr.rows)};
    out.push_back(p);
  }
  return out;
}

int margin_for(const std::vector<ModelPicture>& models, const Settings& s) {
  double diag = 0;
  for (const ModelPicture& m : models)
    diag = std::max(diag, std::hypot(m.bgr.cols, m.bgr.rows));
  return static_cast<int>(std::ceil(diag * s.max_scale * 1.2)) + 4;
}

} // namespace synth
