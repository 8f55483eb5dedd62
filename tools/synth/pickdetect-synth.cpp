// SPDX-License-Identifier: LGPL-2.1-or-later
// pickdetect-synth: makes annotated scenes (the benchmark's FORMAT.md) or a video clip from
// model pictures: bin heaps and conveyor belts with rotation, small out-of-plane tilt, overlap,
// drop shadows, highlights, lighting gradients, blur, motion blur and sensor noise.
//
//   pickdetect-synth --scenes 20 --out data box.png
//   pickdetect-synth --video belt.avi --scenes 100 --out belt-frames pack.png flyer.png
//
// Ground truth is exact with respect to the rendering: each instance is drawn through one
// homography, whose images of the model's principal points and outline are the annotations;
// `covered`, `visible` and `in_frame` are pixel counts of the rendered layers (the instance's
// warped alpha at >= 50%, over a canvas large enough to hold the parts outside the frame).
// Distractor objects lie on the floor under every instance, so they never cover one; --covers
// lays foreign objects (no model's) over instances, and `covered` counts what they hide too.
// The output depends only on the inputs and --seed (own random generator, no std::
// distributions, whose results differ between standard libraries).
#include <glib.h>
#include <glib/gstdio.h>
#include <json-glib/json-glib.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include <unistd.h>

namespace {

class Failure : public std::runtime_error {
public:
  explicit Failure(const std::string& what) : std::runtime_error(what) {}
};

/// SplitMix64: small, fast, and the same everywhere.
class Random {
public:
  explicit Random(uint64_t seed) : state_(seed) {}
  uint64_t next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// Uniform in [a, b).
  double uniform(double a, double b) {
    return a + (b - a) * static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0);
  }
  /// Uniform integer in [a, b].
  int integer(int a, int b) {
    return a + static_cast<int>(next() % static_cast<uint64_t>(b - a + 1));
  }
  bool chance(double p) { return uniform(0.0, 1.0) < p; }
  /// Normal (Box-Muller).
  double normal(double mean, double sigma) {
    const double u1 = uniform(1e-12, 1.0), u2 = uniform(0.0, 1.0);
    return mean + sigma * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * CV_PI * u2);
  }

private:
  uint64_t state_;
};

struct ModelPicture {
  std::string name;
  std::string source;
  cv::Mat bgr;   ///< CV_8UC3.
  cv::Mat alpha; ///< CV_8UC1.
  bool has_alpha = false;
  std::vector<cv::Point2d> principal_points;
  std::vector<cv::Point2d> polygon;
};

struct Placed {
  int model = 0;
  cv::Matx33d homography; ///< Model pixels -> frame pixels.
  double angle = 0, scale = 1, tilt = 0;
  double brightness = 1.0;
  bool highlight = false;
  cv::Point2d highlight_at; ///< Model pixels.
};

struct Rendered {
  cv::Mat image;
  struct Truth {
    int model = 0;
    std::vector<cv::Point2d> points, polygon;
    double angle = 0, scale = 1, tilt = 0, in_frame = 0, visible = 0, covered = 0;
    int z = 0;
  };
  std::vector<Truth> truth;
};

struct Settings {
  cv::Size size{1280, 960};
  int min_instances = 4, max_instances = 9;
  double min_scale = 0.9, max_scale = 1.1;
  double max_tilt = 8.0;
  bool mixed = false;
  std::string kind = "mixed";
  int distractors = 3;
  int covers = 0; ///< Foreign objects lying on instances, per scene.
};

std::string sanitize(const std::string& stem) {
  std::string out;
  for (char c : stem)
    out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-') ? c : '_';
  return out.empty() ? "model" : out;
}

ModelPicture load_model(const std::string& path) {
  cv::Mat raw = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (raw.empty())
    throw Failure("model picture '" + path + "' cannot be read as a picture");
  if (raw.depth() != CV_8U)
    raw.convertTo(raw, CV_8U, raw.depth() == CV_16U ? 1.0 / 257.0 : 1.0);
  ModelPicture m;
  m.source = path;
  gchar* base = g_path_get_basename(path.c_str());
  std::string stem(base);
  g_free(base);
  if (const size_t dot = stem.rfind('.'); dot != std::string::npos && dot > 0)
    stem.resize(dot);
  m.name = sanitize(stem);
  switch (raw.channels()) {
  case 1:
    cv::cvtColor(raw, m.bgr, cv::COLOR_GRAY2BGR);
    break;
  case 3:
    m.bgr = raw;
    break;
  case 4:
    cv::cvtColor(raw, m.bgr, cv::COLOR_BGRA2BGR);
    cv::extractChannel(raw, m.alpha, 3);
    m.has_alpha = cv::countNonZero(m.alpha < 255) > 0;
    break;
  default:
    throw Failure("model picture '" + path + "' has " + std::to_string(raw.channels()) +
                  " channels");
  }
  if (!m.has_alpha)
    m.alpha = cv::Mat(m.bgr.size(), CV_8UC1, cv::Scalar(255));
  if (cv::countNonZero(m.alpha >= 128) == 0)
    throw Failure("model picture '" + path + "' is fully transparent");
  const double w = m.bgr.cols, h = m.bgr.rows;
  if (!m.has_alpha) {
    m.polygon = {{0, 0}, {w, 0}, {w, h}, {0, h}};
    m.principal_points = {{w / 2, h / 2}, {0, 0}, {w, 0}, {w, h}, {0, h}};
  } else {
    // The alpha outline (pixel centres of the boundary), simplified to within a pixel; an
    // alpha in several pieces is outlined by the convex hull of them all.
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(m.alpha >= 128, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
    std::vector<cv::Point> outline;
    if (contours.size() == 1) {
      outline = contours[0];
    } else {
      std::vector<cv::Point> all;
      for (const auto& c : contours)
        all.insert(all.end(), c.begin(), c.end());
      cv::convexHull(all, outline);
    }
    std::vector<cv::Point> simple;
    cv::approxPolyDP(outline, simple, 1.0, true);
    for (const cv::Point& p : simple)
      m.polygon.emplace_back(p.x, p.y);
    const cv::Rect box = cv::boundingRect(m.alpha >= 128);
    const double x0 = box.x, y0 = box.y, x1 = box.x + box.width, y1 = box.y + box.height;
    m.principal_points = {{(x0 + x1) / 2, (y0 + y1) / 2}, {x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
  }
  return m;
}

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

/// Draws the instances in order (z = index) over `bg` (CV_32FC3, frame size) and measures the
/// layers on a canvas with `margin` pixels around the frame.
Rendered render(cv::Mat bg, const std::vector<ModelPicture>& models,
                const std::vector<Placed>& placed, Random& rng, int margin, int covers,
                Random& cover_rng) {
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
  for (int k = 0; k < covers && !placed.empty(); ++k)
    draw_cover(bg, owner, margin, models, placed, cover_rng);
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
    const Layer& layer = layers[i];
    if (!layer.mask.empty()) {
      const cv::Mat mine = owner(layer.rect) == static_cast<short>(i);
      const double total = cv::countNonZero(layer.mask);
      const cv::Mat on_top = layer.mask & ~mine;
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

void add_points(JsonBuilder* b, const char* key, const std::vector<cv::Point2d>& pts) {
  json_builder_set_member_name(b, key);
  json_builder_begin_array(b);
  for (const cv::Point2d& p : pts) {
    json_builder_begin_array(b);
    json_builder_add_double_value(b, std::round(p.x * 1e4) / 1e4);
    json_builder_add_double_value(b, std::round(p.y * 1e4) / 1e4);
    json_builder_end_array(b);
  }
  json_builder_end_array(b);
}

void add_double(JsonBuilder* b, const char* key, double v) {
  json_builder_set_member_name(b, key);
  json_builder_add_double_value(b, std::round(v * 1e6) / 1e6);
}

std::string join(const std::string& a, const std::string& b) {
  gchar* p = g_build_filename(a.c_str(), b.c_str(), nullptr);
  std::string out(p);
  g_free(p);
  return out;
}

void make_dir(const std::string& dir) {
  if (g_mkdir_with_parents(dir.c_str(), 0755) != 0)
    throw Failure("cannot create folder '" + dir + "'");
}

void write_image(const std::string& path, const cv::Mat& image) {
  if (!cv::imwrite(path, image))
    throw Failure("cannot write '" + path + "'");
}

bool parse_range(const char* text, double& lo, double& hi) {
  if (!text)
    return true;
  char* end = nullptr;
  lo = g_ascii_strtod(text, &end);
  if (end == text)
    return false;
  if (*end == '\0') {
    hi = lo;
    return true;
  }
  if (*end != '-')
    return false;
  const char* second = end + 1;
  hi = g_ascii_strtod(second, &end);
  return end != second && *end == '\0' && lo <= hi;
}

/// Progress on stderr when it is a terminal.
void progress(const char* what, int done, int total) {
  if (!isatty(STDERR_FILENO))
    return;
  std::fprintf(stderr, "\rpickdetect-synth: %s %d/%d%s", what, done, total,
               done == total ? "\n" : "");
  std::fflush(stderr);
}

/// A family of look-alike products: the first picture's top `share` of its height (a brand's
/// design) over each further picture in turn, squeezed into the rest. Named first_other; the
/// first picture's outline, alpha and principal points are kept.
std::vector<ModelPicture> make_family(const std::vector<ModelPicture>& pictures, double share) {
  const ModelPicture& design = pictures[0];
  const int top = static_cast<int>(std::lround(share * design.bgr.rows));
  if (top < 1 || top >= design.bgr.rows)
    throw Failure("--family leaves no shared design or no own part of '" + design.name + "'");
  const cv::Rect own(0, top, design.bgr.cols, design.bgr.rows - top);
  std::vector<ModelPicture> family;
  for (size_t i = 1; i < pictures.size(); ++i) {
    ModelPicture product = design;
    product.bgr = design.bgr.clone();
    product.alpha = design.alpha.clone();
    product.name = design.name + "_" + pictures[i].name;
    product.source = pictures[i].source;
    cv::resize(pictures[i].bgr, product.bgr(own), own.size(), 0, 0, cv::INTER_AREA);
    family.push_back(std::move(product));
  }
  return family;
}

int run(int argc, char** argv) {
  gint scenes = 10;
  gchar* size = nullptr;
  gchar* instances = nullptr;
  gchar* scale = nullptr;
  gchar* kind = nullptr;
  gchar* out_dir = nullptr;
  gchar* video = nullptr;
  gchar* format = nullptr;
  gchar* name = nullptr;
  gdouble tilt = 8.0;
  gdouble fps = 10.0;
  gdouble family = 0.0;
  gint64 seed = 1;
  gint distractors = 3;
  gint covers = 0;
  gboolean mixed = FALSE;
  gchar** pictures = nullptr;
  const GOptionEntry entries[] = {
      {"scenes", 'n', 0, G_OPTION_ARG_INT, &scenes, "Scenes (or video frames) to make (10)", "N"},
      {"size", 0, 0, G_OPTION_ARG_STRING, &size, "Frame size (1280x960)", "WxH"},
      {"instances", 0, 0, G_OPTION_ARG_STRING, &instances, "Instances per scene (4-9)", "MIN-MAX"},
      {"scale", 0, 0, G_OPTION_ARG_STRING, &scale, "Scale of the instances (0.9-1.1)", "MIN-MAX"},
      {"tilt", 0, 0, G_OPTION_ARG_DOUBLE, &tilt, "Largest out-of-plane tilt in degrees (8)", "DEG"},
      {"kind", 0, 0, G_OPTION_ARG_STRING, &kind, "bin, conveyor or mixed (mixed)", "KIND"},
      {"mixed-products", 0, 0, G_OPTION_ARG_NONE, &mixed,
       "Mix the models within a scene (default: one model per scene, in turn)", nullptr},
      {"distractors", 0, 0, G_OPTION_ARG_INT, &distractors,
       "Distractor objects on the floor per scene (3)", "N"},
      {"covers", 0, 0, G_OPTION_ARG_INT, &covers,
       "Foreign objects lying on instances per scene (0); they count in 'covered'", "N"},
      {"family", 0, 0, G_OPTION_ARG_DOUBLE, &family,
       "Look-alike products: the first picture's top SHARE of its height (0 < SHARE < 1) is "
       "their common design, each further picture fills the rest of one product",
       "SHARE"},
      {"seed", 0, 0, G_OPTION_ARG_INT64, &seed, "Random seed (1)", "N"},
      {"out", 'o', 0, G_OPTION_ARG_FILENAME, &out_dir,
       "Write an annotated dataset here (dataset.json, models/, scenes/)", "DIR"},
      {"format", 0, 0, G_OPTION_ARG_STRING, &format, "Scene pictures: jpg or png (jpg)", "EXT"},
      {"name", 0, 0, G_OPTION_ARG_STRING, &name, "Dataset name (synth-seedN)", "NAME"},
      {"video", 0, 0, G_OPTION_ARG_FILENAME, &video,
       "Write a conveyor clip (MJPEG AVI) instead of independent scenes; with --out its frames "
       "are annotated too",
       "FILE"},
      {"fps", 0, 0, G_OPTION_ARG_DOUBLE, &fps, "Frames per second of the clip (10)", "FPS"},
      {G_OPTION_REMAINING, 0, 0, G_OPTION_ARG_FILENAME_ARRAY, &pictures, nullptr, "PICTURE..."},
      {nullptr, 0, 0, G_OPTION_ARG_NONE, nullptr, nullptr, nullptr}};
  GOptionContext* context = g_option_context_new(nullptr);
  g_option_context_set_summary(context,
                               "Makes annotated bin and conveyor scenes (or a conveyor clip) from "
                               "model pictures; a PNG's alpha marks the object.");
  g_option_context_add_main_entries(context, entries, nullptr);
  GError* error = nullptr;
  const bool parsed = g_option_context_parse(context, &argc, &argv, &error);
  g_option_context_free(context);
  struct Free {
    std::vector<gchar*> strings;
    gchar** array;
    ~Free() {
      for (gchar* s : strings)
        g_free(s);
      g_strfreev(array);
    }
  } cleanup{{size, instances, scale, kind, out_dir, video, format, name}, pictures};
  if (!parsed) {
    const std::string message = error->message;
    g_clear_error(&error);
    throw Failure(message);
  }
  if (!pictures || !pictures[0])
    throw Failure("give one or more model pictures (see --help)");
  if (!out_dir && !video)
    throw Failure("give --out DIR and/or --video FILE");
  Settings s;
  if (size && std::sscanf(size, "%dx%d", &s.size.width, &s.size.height) != 2)
    throw Failure("--size wants WxH, got '" + std::string(size) + "'");
  if (s.size.width < 64 || s.size.height < 64 || s.size.width > 8192 || s.size.height > 8192)
    throw Failure("--size must lie between 64x64 and 8192x8192");
  double lo = s.min_instances, hi = s.max_instances;
  if (!parse_range(instances, lo, hi) || lo < 0 || hi > 200 || lo != std::floor(lo) ||
      hi != std::floor(hi))
    throw Failure("--instances wants MIN-MAX (whole numbers, at most 200)");
  s.min_instances = static_cast<int>(lo);
  s.max_instances = static_cast<int>(hi);
  if (!parse_range(scale, s.min_scale, s.max_scale) || s.min_scale <= 0.05 || s.max_scale > 10)
    throw Failure("--scale wants MIN-MAX between 0.05 and 10");
  if (tilt < 0 || tilt > 60)
    throw Failure("--tilt must lie between 0 and 60 degrees");
  s.max_tilt = tilt;
  s.kind = kind ? kind : "mixed";
  if (s.kind != "bin" && s.kind != "conveyor" && s.kind != "mixed")
    throw Failure("--kind must be bin, conveyor or mixed");
  if (scenes < 1 || scenes > 100000)
    throw Failure("--scenes must be at least 1");
  s.distractors = std::max(0, distractors);
  if (covers < 0 || covers > 200)
    throw Failure("--covers must lie between 0 and 200");
  s.covers = covers;
  const std::string ext = format ? format : "jpg";
  if (ext != "jpg" && ext != "png")
    throw Failure("--format must be jpg or png");

  std::vector<ModelPicture> models;
  for (gchar** p = pictures; *p; ++p) {
    models.push_back(load_model(*p));
    for (size_t i = 0; i + 1 < models.size(); ++i)
      if (models[i].name == models.back().name)
        models.back().name += "_" + std::to_string(models.size());
  }
  if (family != 0.0) {
    if (!(family > 0.0 && family < 1.0))
      throw Failure("--family wants a share of the height between 0 and 1, got " +
                    std::to_string(family));
    if (models.size() < 2)
      throw Failure("--family needs the design picture and at least one more");
    models = make_family(models, family);
  }
  const int margin = margin_for(models, s);
  Random rng(static_cast<uint64_t>(seed));
  // The covers draw from their own stream: the same seed gives the same scenes with or
  // without objects lying on them.
  Random cover_rng(static_cast<uint64_t>(seed) ^ 0x9e3779b97f4a7c15ULL);
  cv::theRNG().state = static_cast<uint64_t>(seed) * 2654435761u + 1;

  std::vector<Rendered> frames;
  std::vector<std::string> kinds;
  if (video) {
    // One long belt moving right: instances keep their pose and move by `speed` per frame.
    const double speed = s.size.width / 40.0;
    const double length = s.size.width + speed * scenes + 2.0 * margin;
    const int count = std::max(
        1, static_cast<int>(length / s.size.width * (s.min_instances + s.max_instances) / 2.0));
    std::vector<int> all(models.size());
    for (size_t i = 0; i < all.size(); ++i)
      all[i] = static_cast<int>(i);
    struct Item {
      int model;
      double x, y, angle, scale, tilt, axis, brightness;
      bool highlight;
      cv::Point2d highlight_at;
    };
    std::vector<Item> items;
    for (int i = 0; i < count; ++i) {
      Item it;
      it.model = all[static_cast<size_t>(rng.integer(0, static_cast<int>(all.size()) - 1))];
      it.x = -margin - speed * scenes + rng.uniform(0, length);
      it.y = rng.uniform(0.25, 0.75) * s.size.height;
      it.angle = rng.uniform(0, 360);
      it.scale = rng.uniform(s.min_scale, s.max_scale);
      it.tilt = rng.uniform(0, s.max_tilt);
      it.axis = rng.uniform(0, CV_PI);
      it.brightness = rng.uniform(0.8, 1.15);
      it.highlight = rng.chance(0.3);
      const ModelPicture& m = models[static_cast<size_t>(it.model)];
      it.highlight_at = {rng.uniform(0, m.bgr.cols), rng.uniform(0, m.bgr.rows)};
      items.push_back(it);
    }
    Random scenery(static_cast<uint64_t>(seed) ^ 0x5eedull);
    cv::Mat belt = background("conveyor", s.size, scenery);
    for (int f = 0; f < scenes; ++f) {
      std::vector<Placed> placed;
      for (const Item& it : items) {
        const double x = it.x + speed * f;
        if (x < -margin || x > s.size.width + margin)
          continue;
        Placed p;
        p.model = it.model;
        p.angle = it.angle;
        p.scale = it.scale;
        p.tilt = it.tilt;
        p.brightness = it.brightness;
        p.highlight = it.highlight;
        p.highlight_at = it.highlight_at;
        p.homography = placement(models[static_cast<size_t>(it.model)], it.angle, it.scale, it.tilt,
                                 it.axis, {x, it.y});
        placed.push_back(p);
      }
      Rendered r = render(belt.clone(), models, placed, rng, margin, s.covers, cover_rng);
      // Instances wholly off the frame are not part of this frame's ground truth.
      r.truth.erase(std::remove_if(r.truth.begin(), r.truth.end(),
                                   [](const Rendered::Truth& t) { return t.in_frame <= 0.0; }),
                    r.truth.end());
      frames.push_back(std::move(r));
      kinds.push_back("conveyor");
      progress("frame", f + 1, scenes);
    }
    cv::VideoWriter writer(video, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps, s.size, true);
    if (!writer.isOpened())
      throw Failure("cannot write the clip '" + std::string(video) +
                    "' (MJPEG AVI; use a .avi name)");
    for (const Rendered& r : frames)
      writer.write(r.image);
    writer.release();
  } else {
    for (int i = 0; i < scenes; ++i) {
      const std::string k =
          s.kind == "mixed" ? (i % 2 == 0 ? std::string("bin") : std::string("conveyor")) : s.kind;
      std::vector<int> allowed;
      if (mixed)
        for (size_t m = 0; m < models.size(); ++m)
          allowed.push_back(static_cast<int>(m));
      else
        allowed.push_back(i % static_cast<int>(models.size()));
      cv::Mat bg = background(k, s.size, rng);
      cv::Mat floor;
      bg.convertTo(floor, CV_8UC3);
      draw_distractors(floor, s.distractors, rng);
      floor.convertTo(bg, CV_32FC3);
      const std::vector<Placed> placed = place(k, models, allowed, s, rng);
      frames.push_back(render(bg, models, placed, rng, margin, s.covers, cover_rng));
      kinds.push_back(k);
      progress("scene", i + 1, scenes);
    }
  }

  if (!out_dir)
    return 0;
  const std::string dir(out_dir);
  make_dir(join(dir, "models"));
  make_dir(join(dir, "scenes"));
  JsonBuilder* b = json_builder_new();
  json_builder_begin_object(b);
  json_builder_set_member_name(b, "name");
  const std::string dataset_name =
      name ? std::string(name) : "synth-seed" + std::to_string(static_cast<long long>(seed));
  json_builder_add_string_value(b, dataset_name.c_str());
  json_builder_set_member_name(b, "models");
  json_builder_begin_object(b);
  for (const ModelPicture& m : models) {
    const std::string file = "models/" + m.name + ".png";
    cv::Mat picture;
    if (m.has_alpha) {
      std::vector<cv::Mat> split;
      cv::split(m.bgr, split);
      split.push_back(m.alpha);
      cv::merge(split, picture);
    } else {
      picture = m.bgr;
    }
    write_image(join(dir, file), picture);
    json_builder_set_member_name(b, m.name.c_str());
    json_builder_begin_object(b);
    json_builder_set_member_name(b, "image");
    json_builder_add_string_value(b, file.c_str());
    add_points(b, "principal_points", m.principal_points);
    add_points(b, "polygon", m.polygon);
    json_builder_end_object(b);
  }
  json_builder_end_object(b);
  json_builder_set_member_name(b, "scenes");
  json_builder_begin_array(b);
  for (size_t i = 0; i < frames.size(); ++i) {
    char file[64];
    std::snprintf(file, sizeof file, "scenes/%04zu.%s", i, ext.c_str());
    if (ext == "jpg")
      cv::imwrite(join(dir, file), frames[i].image, {cv::IMWRITE_JPEG_QUALITY, 92});
    else
      write_image(join(dir, file), frames[i].image);
    json_builder_begin_object(b);
    json_builder_set_member_name(b, "image");
    json_builder_add_string_value(b, file);
    json_builder_set_member_name(b, "kind");
    json_builder_add_string_value(b, kinds[i].c_str());
    json_builder_set_member_name(b, "width");
    json_builder_add_int_value(b, s.size.width);
    json_builder_set_member_name(b, "height");
    json_builder_add_int_value(b, s.size.height);
    json_builder_set_member_name(b, "instances");
    json_builder_begin_array(b);
    for (const Rendered::Truth& t : frames[i].truth) {
      json_builder_begin_object(b);
      json_builder_set_member_name(b, "model");
      json_builder_add_string_value(b, models[static_cast<size_t>(t.model)].name.c_str());
      add_points(b, "points", t.points);
      add_points(b, "polygon", t.polygon);
      add_double(b, "angle", t.angle);
      add_double(b, "scale", t.scale);
      add_double(b, "tilt", t.tilt);
      json_builder_set_member_name(b, "z");
      json_builder_add_int_value(b, t.z);
      add_double(b, "in_frame", t.in_frame);
      add_double(b, "visible", t.visible);
      add_double(b, "covered", t.covered);
      json_builder_end_object(b);
    }
    json_builder_end_array(b);
    json_builder_end_object(b);
  }
  json_builder_end_array(b);
  json_builder_end_object(b);
  JsonGenerator* gen = json_generator_new();
  JsonNode* root = json_builder_get_root(b);
  json_generator_set_root(gen, root);
  json_generator_set_pretty(gen, TRUE);
  json_generator_set_indent(gen, 1);
  const std::string json_path = join(dir, "dataset.json");
  const gboolean ok = json_generator_to_file(gen, json_path.c_str(), &error);
  json_node_unref(root);
  g_object_unref(gen);
  g_object_unref(b);
  if (!ok) {
    const std::string message = error->message;
    g_clear_error(&error);
    throw Failure("cannot write '" + json_path + "': " + message);
  }
  std::fprintf(stderr, "pickdetect-synth: wrote %zu scenes to %s\n", frames.size(), dir.c_str());
  return 0;
}

} // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const Failure& e) {
    std::cerr << "pickdetect-synth: " << e.what() << "\n";
    return 1;
  } catch (const cv::Exception& e) {
    std::cerr << "pickdetect-synth: " << e.what() << "\n";
    return 1;
  }
}
