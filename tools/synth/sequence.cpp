// SPDX-License-Identifier: LGPL-2.1-or-later
// Video sequences (the benchmark's FORMAT.md, "Video sequences"): the frames of one video with
// the identity (`track`) of each physical object. A conveyor: lanes of objects riding right at
// a set speed, arriving from the left, some with another lying partly on them and riding with
// them, blurred along the belt by the exposure. A bin: a still heap from which the top free
// object is taken away every N frames. Light, shadows and focus stay those of the first frame;
// the sensor noise is new in every frame.
#include "synth.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace synth {
namespace {

/// The largest extent of a model at a scale, whatever its rotation.
double reach(const ModelPicture& m, double scale) {
  return std::hypot(m.bgr.cols, m.bgr.rows) * scale;
}

BeltItem random_item(const std::vector<ModelPicture>& models, const Settings& s, Random& rng) {
  BeltItem it;
  it.model = rng.integer(0, static_cast<int>(models.size()) - 1);
  draw_look(it, models, s, rng);
  return it;
}

/// The lanes of a belt and the items riding on them, from far left (arriving last) to the
/// right edge of the frame at frame 0.
std::vector<BeltItem> belt_items(const std::vector<ModelPicture>& models, const Settings& s,
                                 const SequenceOptions& o, int margin, Random& rng) {
  double largest = 0;
  for (const ModelPicture& m : models)
    largest = std::max(largest, reach(m, s.max_scale));
  const double usable = s.size.height * (1.0 - 2.0 / 12.0); // Between the rails.
  const int lanes = std::max(1, static_cast<int>(usable / (largest * 1.05)));
  const double lane_height = usable / lanes;
  const double start = -margin - o.speed * o.frames, end = s.size.width + margin;
  std::vector<BeltItem> items;
  int track = 1;
  for (int lane = 0; lane < lanes; ++lane) {
    const double y = s.size.height / 12.0 + lane_height * (lane + 0.5);
    double x = end - rng.uniform(0, largest);
    while (x > start) {
      BeltItem it = random_item(models, s, rng);
      it.x = x;
      it.y = y + rng.uniform(-0.15, 0.15) *
                     std::max(0.0,
                              lane_height - reach(models[static_cast<size_t>(it.model)], it.scale));
      it.track = track++;
      items.push_back(it);
      const double size = reach(models[static_cast<size_t>(it.model)], it.scale);
      if (rng.chance(o.riders)) {
        // Partly on it, turned, riding with it.
        BeltItem r = random_item(models, s, rng);
        r.rider = true;
        r.x = it.x + rng.uniform(-0.3, 0.3) * size;
        r.y = it.y + rng.uniform(-0.15, 0.15) * size;
        r.track = track++;
        items.push_back(r);
      }
      x -= size * rng.uniform(1.1, 1.9) + o.gap * rng.uniform(0.0, 1.0);
    }
  }
  return items;
}

/// A motion blur along x of `length` pixels (box kernel).
void belt_blur(cv::Mat& image, double length) {
  const int n = static_cast<int>(std::round(length));
  if (n < 2)
    return;
  cv::Mat kernel(1, n, CV_32FC1, cv::Scalar(1.0 / n));
  cv::filter2D(image, image, -1, kernel);
}

} // namespace

void draw_look(BeltItem& it, const std::vector<ModelPicture>& models, const Settings& s,
               Random& rng) {
  it.angle = rng.uniform(0, 360);
  it.scale = rng.uniform(s.min_scale, s.max_scale);
  it.tilt = rng.uniform(0, s.max_tilt);
  it.axis = rng.uniform(0, CV_PI);
  it.brightness = rng.uniform(0.8, 1.15);
  it.highlight = rng.chance(0.3);
  const ModelPicture& m = models[static_cast<size_t>(it.model)];
  it.highlight_at = {rng.uniform(0, m.bgr.cols), rng.uniform(0, m.bgr.rows)};
}

Placed place_item(const std::vector<ModelPicture>& models, const BeltItem& it, cv::Point2d at) {
  Placed p;
  p.model = it.model;
  p.track = it.track;
  p.angle = it.angle;
  p.scale = it.scale;
  p.tilt = it.tilt;
  p.brightness = it.brightness;
  p.highlight = it.highlight;
  p.highlight_at = it.highlight_at;
  p.homography =
      placement(models[static_cast<size_t>(it.model)], it.angle, it.scale, it.tilt, it.axis, at);
  return p;
}

void drop_off_frame(Rendered& r) {
  r.truth.erase(std::remove_if(r.truth.begin(), r.truth.end(),
                               [](const Rendered::Truth& t) { return t.in_frame <= 0.0; }),
                r.truth.end());
}

std::vector<Rendered> make_sequence(const std::vector<ModelPicture>& models, const Settings& s,
                                    const SequenceOptions& o, Random& rng, int margin,
                                    const Extras& extras, void (*progress)(int done, int total)) {
  std::vector<Rendered> frames;
  const uint64_t look_seed = rng.next(); // Light, shadows and focus of every frame.
  if (o.kind == "conveyor") {
    const std::vector<BeltItem> items = belt_items(models, s, o, margin, rng);
    Random scenery(look_seed ^ 0x5eedull);
    const cv::Mat belt = background("conveyor", s.size, scenery);
    for (int f = 0; f < o.frames; ++f) {
      std::vector<Placed> placed, riders;
      for (const BeltItem& it : items) {
        const double x = it.x + o.speed * f;
        if (x < -margin || x > s.size.width + margin)
          continue;
        (it.rider ? riders : placed).push_back(place_item(models, it, {x, it.y}));
      }
      placed.insert(placed.end(), riders.begin(), riders.end());
      Random look(look_seed);
      Extras blur = extras;
      blur.fixed_blur = true;
      Rendered r = render(belt.clone(), models, placed, look, margin, blur);
      belt_blur(r.image, o.speed * o.exposure);
      drop_off_frame(r);
      frames.push_back(std::move(r));
      if (progress)
        progress(f + 1, o.frames);
    }
    return frames;
  }

  // A bin: a heap, the top free object taken away every `pick_every` frames.
  std::vector<int> all(models.size());
  for (size_t i = 0; i < all.size(); ++i)
    all[i] = static_cast<int>(i);
  std::vector<Placed> placed = place("bin", models, all, s, rng);
  for (size_t i = 0; i < placed.size(); ++i)
    placed[i].track = static_cast<int>(i) + 1;
  Random scenery(look_seed ^ 0x5eedull);
  cv::Mat bg = background("bin", s.size, scenery);
  cv::Mat floor;
  bg.convertTo(floor, CV_8UC3);
  draw_distractors(floor, s.distractors, scenery);
  floor.convertTo(bg, CV_32FC3);
  Rendered last;
  for (int f = 0; f < o.frames; ++f) {
    if (f > 0 && o.pick_every > 0 && f % o.pick_every == 0) {
      // The top free object: the highest one nothing lies on (the topmost always qualifies).
      int top = -1;
      for (size_t i = 0; i < last.truth.size(); ++i)
        if (last.truth[i].covered < 0.02 && last.truth[i].in_frame > 0.0)
          top = static_cast<int>(i);
      if (top >= 0)
        placed.erase(placed.begin() + top);
    }
    Random look(look_seed);
    Extras still = extras;
    still.fixed_blur = true;
    last = render(bg.clone(), models, placed, look, margin, still);
    Rendered r = last;
    drop_off_frame(r);
    frames.push_back(std::move(r));
    if (progress)
      progress(f + 1, o.frames);
  }
  return frames;
}

} // namespace synth
