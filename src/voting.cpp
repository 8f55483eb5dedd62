// SPDX-License-Identifier: LGPL-2.1-or-later
// Voting: each match carries every principal point into the scene through the roto-translation
// (and scaling) given by its two keypoints.
#include <pickdetect/voting.hpp>

#include <cmath>

namespace pickdetect {

std::vector<Vote> cast_votes(const std::vector<Match>& matches,
                             const std::vector<cv::KeyPoint>& model_keypoints,
                             const std::vector<cv::KeyPoint>& scene_keypoints,
                             const std::vector<cv::Point2f>& principal_points, bool allow_scale) {
  std::vector<Vote> votes;
  votes.reserve(matches.size());
  for (const Match& m : matches) {
    const cv::KeyPoint& km = model_keypoints[m.model_point];
    const cv::KeyPoint& ks = scene_keypoints[m.scene_point];
    Vote v;
    // SIFT angles grow clockwise on screen (image y axis down), like our instance angles.
    double angle = std::fmod(static_cast<double>(ks.angle) - km.angle, 360.0);
    if (angle < 0.0)
      angle += 360.0;
    v.angle = static_cast<float>(angle);
    v.scale = allow_scale && km.size > 0.f ? ks.size / km.size : 1.f;
    const double rad = angle * CV_PI / 180.0;
    const double c = std::cos(rad) * v.scale, s = std::sin(rad) * v.scale;
    v.points.reserve(principal_points.size());
    for (const cv::Point2f& p : principal_points) {
      const double dx = p.x - km.pt.x, dy = p.y - km.pt.y;
      v.points.emplace_back(static_cast<float>(ks.pt.x + c * dx - s * dy),
                            static_cast<float>(ks.pt.y + s * dx + c * dy));
    }
    votes.push_back(std::move(v));
  }
  return votes;
}

} // namespace pickdetect
