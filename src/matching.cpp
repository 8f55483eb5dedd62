// SPDX-License-Identifier: LGPL-2.1-or-later
// Matching: 2NN ratio test of scene descriptors against all models' descriptors at once.
#include <pickdetect/matching.hpp>

#include <opencv2/features2d.hpp>

namespace pickdetect {

Matcher::Matcher(const std::vector<Model>& models) {
  std::vector<cv::Mat> parts;
  for (size_t m = 0; m < models.size(); ++m) {
    offset_.push_back(static_cast<int>(owner_.size()));
    owner_.insert(owner_.end(), models[m].descriptors.rows, static_cast<int>(m));
    if (!models[m].descriptors.empty())
      parts.push_back(models[m].descriptors);
  }
  if (!parts.empty())
    cv::vconcat(parts, descriptors_);
}

std::vector<Match> Matcher::match(const cv::Mat& scene_descriptors, double ratio) const {
  std::vector<Match> matches;
  if (descriptors_.rows < 2 || scene_descriptors.empty())
    return matches;
  cv::BFMatcher bf(cv::NORM_L2);
  std::vector<std::vector<cv::DMatch>> knn;
  bf.knnMatch(scene_descriptors, descriptors_, knn, 2);
  for (const auto& pair : knn) {
    if (pair.size() < 2)
      continue;
    const cv::DMatch& best = pair[0];
    const float r = pair[1].distance > 0.f ? best.distance / pair[1].distance : 1.f;
    if (r >= ratio)
      continue;
    Match m;
    m.model = owner_[best.trainIdx];
    m.model_point = best.trainIdx - offset_[m.model];
    m.scene_point = best.queryIdx;
    m.distance = best.distance;
    m.ratio = r;
    matches.push_back(m);
  }
  return matches;
}

} // namespace pickdetect
