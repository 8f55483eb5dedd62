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

void set_grasp(Instance& inst, const Model& model) {
  inst.grasp = inst.points[static_cast<size_t>(model.grasp_point)];
  inst.grasp_angle = inst.angle;
}

std::vector<cv::Point2f> scene_points(const ModelScene& ms, const std::vector<int>& idx) {
  std::vector<cv::Point2f> out;
  out.reserve(idx.size());
  for (int i : idx)
    out.push_back(ms.scene.keypoints[ms.matches[i].scene_point].pt);
  return out;
}

std::vector<cv::Point2f> model_points(const ModelScene& ms, const std::vector<int>& idx) {
  std::vector<cv::Point2f> out;
  out.reserve(idx.size());
  for (int i : idx)
    out.push_back(ms.model_features.keypoints[ms.matches[i].model_point].pt);
  return out;
}

void index_matches(ModelScene& ms) {
  std::vector<cv::Point2f> at;
  at.reserve(ms.matches.size());
  for (const Match& m : ms.matches)
    at.push_back(ms.scene.keypoints[m.scene_point].pt);
  // Cells of half the model's side, at least 8 px: a pose's box spans a few of them.
  ms.match_grid = PointGrid(std::move(at), std::max(8.0, 0.5 * model_side(ms.model)));
}

std::vector<Cluster> centre_clusters(const ModelScene& ms) {
  std::vector<cv::Point2f> centres;
  centres.reserve(ms.votes.size());
  for (const Vote& v : ms.votes)
    centres.push_back(v.points[0]);
  return mean_shift_clusters(centres, ms.bandwidth);
}

} // namespace pickdetect::detail
