// SPDX-License-Identifier: LGPL-2.1-or-later
// Packed rows: identical boxes side by side, touching, as they stand in a picking tote or on a
// pallet layer, and (with two layers) a second layer lying on the first at half a box's offset,
// so that each of its boxes covers parts of up to four below.
#include "synth.hpp"

#include <algorithm>

namespace synth {

std::vector<Placed> place_packed(const std::vector<ModelPicture>& models,
                                 const std::vector<int>& allowed, const Settings& s, Random& rng) {
  // One scale for the scene (identical boxes), the cell the largest of the allowed pictures
  // (several faces of one product may differ in size; the smaller sit centred in their cell).
  const double scale = rng.uniform(s.min_scale, s.max_scale);
  double cw = 0, ch = 0;
  for (int m : allowed) {
    cw = std::max(cw, models[static_cast<size_t>(m)].bgr.cols * scale);
    ch = std::max(ch, models[static_cast<size_t>(m)].bgr.rows * scale);
  }
  // The rows run across the frame or down it, a little askew.
  const bool down = rng.chance(0.5);
  const double theta = rng.uniform(-12.0, 12.0) + (down ? 90.0 : 0.0);
  const double w = s.size.width, h = s.size.height;
  const double along = down ? h : w, across = down ? w : h;
  const int cols = std::max(1, static_cast<int>(0.92 * along / cw));
  const int rows = std::max(1, static_cast<int>(0.92 * across / ch));
  const cv::Point2d centre(w / 2 + rng.uniform(-0.04, 0.04) * w,
                           h / 2 + rng.uniform(-0.04, 0.04) * h);
  const double r = theta * CV_PI / 180.0;
  auto box = [&](double col, double row, int level) {
    Placed p;
    p.model = allowed[static_cast<size_t>(rng.integer(0, static_cast<int>(allowed.size()) - 1))];
    p.level = level;
    const ModelPicture& m = models[static_cast<size_t>(p.model)];
    // Boxes lie either way round in a row.
    p.angle = std::fmod(theta + (rng.chance(0.5) ? 180.0 : 0.0) + 360.0, 360.0);
    p.scale = scale;
    p.tilt = 0;
    const double x = (col - (cols - 1) / 2.0) * cw, y = (row - (rows - 1) / 2.0) * ch;
    const cv::Point2d at(centre.x + std::cos(r) * x - std::sin(r) * y,
                         centre.y + std::sin(r) * x + std::cos(r) * y);
    p.homography = placement(m, p.angle, p.scale, 0.0, 0.0, at);
    p.brightness = rng.uniform(0.8, 1.15);
    p.highlight = rng.chance(0.35);
    p.highlight_at = {rng.uniform(0, m.bgr.cols), rng.uniform(0, m.bgr.rows)};
    return p;
  };
  std::vector<Placed> out;
  for (int row = 0; row < rows; ++row)
    for (int col = 0; col < cols; ++col) {
      if (rng.chance(0.08)) // now and then a box already picked
        continue;
      out.push_back(box(col, row, 0));
    }
  if (s.packed >= 2 && cols >= 2) {
    // The second layer on the seams of the first (half a box along, and across when there are
    // two rows or more): its boxes never overlap each other, each covers parts of those below.
    const double shift = rows >= 2 ? 0.5 : 0.0;
    for (int row = 0; row < std::max(1, rows - 1); ++row)
      for (int col = 0; col + 1 < cols; ++col) {
        if (!rng.chance(0.35))
          continue;
        out.push_back(box(col + 0.5, row + shift, 1));
      }
  }
  return out;
}

} // namespace synth
