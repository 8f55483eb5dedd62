// SPDX-License-Identifier: LGPL-2.1-or-later
// Matching: 2NN ratio test of scene descriptors against all models' descriptors at once.
#include <pickdetect/matching.hpp>

#include <opencv2/core/utility.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/flann.hpp>

#include <mutex>

namespace pickdetect {
namespace {

/// FLANN kd-trees: how many, and how many leaves a search visits (more: closer to exact).
constexpr int kKdTrees = 1;
constexpr int kKdChecks = 32;
/// FLANN draws the trees' split dimensions from the C library's rand(): seeding it right before
/// the build, under a lock, makes the same models give the same trees in every run.
constexpr unsigned kKdSeed = 20240101u;
/// Scene descriptors are searched in blocks of this many rows, in parallel.
constexpr int kSearchBlock = 256;

std::mutex& flann_build_lock() {
  static std::mutex lock;
  return lock;
}

} // namespace

Matcher::Matcher(const std::vector<Model>& models, FeatureKind kind) : kind_(kind) {
  std::vector<cv::Mat> parts;
  for (size_t m = 0; m < models.size(); ++m) {
    const cv::Mat& d = models[m].features(kind).descriptors;
    offset_.push_back(static_cast<int>(owner_.size()));
    owner_.insert(owner_.end(), d.rows, static_cast<int>(m));
    if (!d.empty())
      parts.push_back(d);
  }
  if (!parts.empty())
    cv::vconcat(parts, descriptors_);
  if (kind == FeatureKind::Sift && descriptors_.rows >= 2) {
    std::lock_guard<std::mutex> hold(flann_build_lock());
    cvflann::seed_random(kKdSeed);
    index_ = std::make_shared<cv::flann::Index>(
        descriptors_, cv::flann::KDTreeIndexParams(kKdTrees), cvflann::FLANN_DIST_L2);
  }
}

std::vector<Match> Matcher::match(const cv::Mat& scene_descriptors, double ratio,
                                  Search search) const {
  std::vector<Match> matches;
  if (descriptors_.rows < 2 || scene_descriptors.empty() ||
      scene_descriptors.type() != descriptors_.type() ||
      scene_descriptors.cols != descriptors_.cols)
    return matches;
  const int n = scene_descriptors.rows;
  // Nearest two per scene row: indices and distances (squared L2 from FLANN).
  cv::Mat indices(n, 2, CV_32S), distances(n, 2, CV_32F);
  if (kind_ == FeatureKind::Sift && search == Search::KdTree && index_) {
    cv::parallel_for_(cv::Range(0, (n + kSearchBlock - 1) / kSearchBlock), [&](const cv::Range& r) {
      for (int b = r.start; b < r.end; ++b) {
        const cv::Range rows(b * kSearchBlock, std::min(n, (b + 1) * kSearchBlock));
        cv::Mat idx = indices.rowRange(rows), dist = distances.rowRange(rows);
        index_->knnSearch(scene_descriptors.rowRange(rows), idx, dist, 2,
                          cv::flann::SearchParams(kKdChecks));
      }
    });
    cv::sqrt(distances, distances);
  } else {
    cv::BFMatcher bf(kind_ == FeatureKind::Orb ? cv::NORM_HAMMING : cv::NORM_L2);
    std::vector<std::vector<cv::DMatch>> knn;
    bf.knnMatch(scene_descriptors, descriptors_, knn, 2);
    for (int i = 0; i < n; ++i) {
      const bool two = knn[i].size() == 2;
      indices.at<int>(i, 0) = two ? knn[i][0].trainIdx : -1;
      indices.at<int>(i, 1) = two ? knn[i][1].trainIdx : -1;
      distances.at<float>(i, 0) = two ? knn[i][0].distance : 0.f;
      distances.at<float>(i, 1) = two ? knn[i][1].distance : 0.f;
    }
  }
  for (int i = 0; i < n; ++i) {
    const int best = indices.at<int>(i, 0);
    const float d1 = distances.at<float>(i, 0), d2 = distances.at<float>(i, 1);
    if (best < 0 || indices.at<int>(i, 1) < 0 || best >= descriptors_.rows)
      continue;
    const float r = d2 > 0.f ? d1 / d2 : 1.f;
    if (r >= ratio)
      continue;
    Match m;
    m.model = owner_[best];
    m.model_point = best - offset_[m.model];
    m.scene_point = i;
    m.distance = d1;
    m.ratio = r;
    matches.push_back(m);
  }
  return matches;
}

} // namespace pickdetect
