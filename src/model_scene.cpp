// SPDX-License-Identifier: LGPL-2.1-or-later
// One model's view of a frame: placing instances, centre clusters.
#include "model_scene.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace pickdetect::detail {

double model_side(const Model& model) {
  const cv::Rect2f box = cv::boundingRect(model.outline);
  return std::max(1.0f, std::min(box.width, box.height));
}

/// Fills an instance's geometry from a similarity pose.
void place(Instance& inst, const Model& model, const Similarity& pose) {
  const double rad = pose.angle * CV_PI / 180.0;
  const double c = std::cos(rad) * pose.scale, sn = std::sin(rad) * pose.scale;
  inst.homography = cv::Matx33d(c, -sn, pose.translation.x, sn, c, pose.translation.y, 0, 0, 1);
  inst.points = pose.apply(model.principal_points);
  inst.outline = pose.apply(model.outline);
  inst.center = inst.points[0];
  inst.angle = pose.angle;
  inst.scale = pose.scale;
}

/// Fills an instance's geometry from a homography (the RANSAC baselines).
void place(Instance& inst, const Model& model, const cv::Matx33d& h) {
  inst.homography = h;
  cv::perspectiveTransform(model.principal_points, inst.points, cv::Mat(h));
  cv::perspectiveTransform(model.outline, inst.outline, cv::Mat(h));
  inst.center = inst.points[0];
  const Similarity local = similarity_near(h, model.principal_points[0]);
  inst.angle = local.angle;
  inst.scale = local.scale;
}

std::vector<cv::Point2f> scene_points(const ModelScene& ms, const std::vector<int>& idx) {
  std::vector<cv::Point2f> out;
  out.reserve(idx.size());
  for (int i : idx)
    out.push_back(ms.scene_keypoints[ms.matches[i].scene_point].pt);
  return out;
}

std::vector<cv::Point2f> model_points(const ModelScene& ms, const std::vector<int>& idx) {
  std::vector<cv::Point2f> out;
  out.reserve(idx.size());
  for (int i : idx)
    out.push_back(ms.model_keypoints[ms.matches[i].model_point].pt);
  return out;
}

void index_matches(ModelScene& ms) {
  ms.grid.clear();
  if (ms.matches.empty())
    return;
  const cv::Point2f first = ms.scene_keypoints[ms.matches[0].scene_point].pt;
  float x0 = first.x, y0 = first.y, x1 = first.x, y1 = first.y;
  for (const Match& m : ms.matches) {
    const cv::Point2f p = ms.scene_keypoints[m.scene_point].pt;
    x0 = std::min(x0, p.x), y0 = std::min(y0, p.y), x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
  }
  // Cells of half the model's side, at least 8 px, and at most 256 on a side of the grid
  // (a small model on a huge frame).
  ms.cell = std::max(
      {8.f, static_cast<float>(0.5 * model_side(ms.model)), (x1 - x0) / 256.f, (y1 - y0) / 256.f});
  ms.grid_origin = cv::Point2f(x0, y0);
  ms.grid_cols = static_cast<int>((x1 - x0) / ms.cell) + 1;
  ms.grid_rows = static_cast<int>((y1 - y0) / ms.cell) + 1;
  ms.grid.assign(static_cast<size_t>(ms.grid_cols) * ms.grid_rows, {});
  for (size_t i = 0; i < ms.matches.size(); ++i) {
    const cv::Point2f p = ms.scene_keypoints[ms.matches[i].scene_point].pt - ms.grid_origin;
    const int c = static_cast<int>(p.x / ms.cell), r = static_cast<int>(p.y / ms.cell);
    ms.grid[static_cast<size_t>(r) * ms.grid_cols + c].push_back(static_cast<int>(i));
  }
}

std::vector<int> matches_in(const ModelScene& ms, const cv::Rect2f& box) {
  std::vector<int> out;
  if (ms.grid.empty() || !(box.width >= 0.f) || !(box.height >= 0.f))
    return out;
  auto clamp_cell = [](float v, int n) {
    return static_cast<int>(std::clamp(v, 0.f, static_cast<float>(n - 1)));
  };
  const cv::Point2f a = box.tl() - ms.grid_origin, b = box.br() - ms.grid_origin;
  if (b.x < 0.f || b.y < 0.f || a.x / ms.cell >= ms.grid_cols || a.y / ms.cell >= ms.grid_rows)
    return out;
  const int c0 = clamp_cell(a.x / ms.cell, ms.grid_cols),
            c1 = clamp_cell(b.x / ms.cell, ms.grid_cols);
  const int r0 = clamp_cell(a.y / ms.cell, ms.grid_rows),
            r1 = clamp_cell(b.y / ms.cell, ms.grid_rows);
  for (int r = r0; r <= r1; ++r)
    for (int c = c0; c <= c1; ++c)
      for (int i : ms.grid[static_cast<size_t>(r) * ms.grid_cols + c]) {
        const cv::Point2f p = ms.scene_keypoints[ms.matches[i].scene_point].pt;
        if (p.x >= box.x && p.y >= box.y && p.x <= box.x + box.width && p.y <= box.y + box.height)
          out.push_back(i);
      }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<Cluster> centre_clusters(const ModelScene& ms) {
  std::vector<cv::Point2f> centres;
  centres.reserve(ms.votes.size());
  for (const Vote& v : ms.votes)
    centres.push_back(v.points[0]);
  return mean_shift_clusters(centres, ms.bandwidth);
}

} // namespace pickdetect::detail
