// SPDX-License-Identifier: LGPL-2.1-or-later
// Matching: the 2NN ratio test of scene descriptors against all models' descriptors at once,
// rejecting or sharing the features that fit several models (look-alikes) about equally well.
#include <pickdetect/matching.hpp>

#include <opencv2/core/utility.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/flann.hpp>

#include <algorithm>
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
/// Ambiguity::Share: neighbours searched per scene descriptor (two per model, at most this).
constexpr int kMaxNeighbours = 16;
/// Ambiguity::Share: a model's nearest descriptor within 1 / kNearlyAsGood of the nearest of
/// all fits about as well as the best.
constexpr float kNearlyAsGood = 0.9f;

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

void Matcher::nearest(const cv::Mat& queries, int k, Search search, cv::Mat& indices,
                      cv::Mat& distances) const {
  const int n = queries.rows;
  indices.create(n, k, CV_32S);
  distances.create(n, k, CV_32F);
  if (kind_ == FeatureKind::Sift && search == Search::KdTree && index_) {
    cv::parallel_for_(cv::Range(0, (n + kSearchBlock - 1) / kSearchBlock), [&](const cv::Range& r) {
      for (int b = r.start; b < r.end; ++b) {
        const cv::Range rows(b * kSearchBlock, std::min(n, (b + 1) * kSearchBlock));
        cv::Mat idx = indices.rowRange(rows), dist = distances.rowRange(rows);
        index_->knnSearch(queries.rowRange(rows), idx, dist, k, cv::flann::SearchParams(kKdChecks));
      }
    });
    cv::sqrt(distances, distances); // FLANN gives squared L2
    return;
  }
  cv::BFMatcher bf(kind_ == FeatureKind::Orb ? cv::NORM_HAMMING : cv::NORM_L2);
  std::vector<std::vector<cv::DMatch>> knn;
  bf.knnMatch(queries, descriptors_, knn, k);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < k; ++j) {
      const bool have = j < static_cast<int>(knn[i].size());
      indices.at<int>(i, j) = have ? knn[i][j].trainIdx : -1;
      distances.at<float>(i, j) = have ? knn[i][j].distance : 0.f;
    }
}

std::vector<Match> Matcher::match(const cv::Mat& scene_descriptors, double ratio, Search search,
                                  Ambiguity ambiguity) const {
  std::vector<Match> matches;
  if (descriptors_.rows < 2 || scene_descriptors.empty() ||
      scene_descriptors.type() != descriptors_.type() ||
      scene_descriptors.cols != descriptors_.cols)
    return matches;
  const int n = scene_descriptors.rows;
  // Sharing needs a few neighbours per model (each model's nearest, and the nearest that is
  // none of the look-alikes'); the plain test needs two.
  const int n_models = static_cast<int>(offset_.size());
  const int k = ambiguity == Ambiguity::Share
                    ? std::min(descriptors_.rows, std::clamp(2 * n_models, 2, kMaxNeighbours))
                    : 2;
  cv::Mat indices, distances;
  nearest(scene_descriptors, k, search, indices, distances);
  std::vector<int> first(n_models);
  for (int i = 0; i < n; ++i) {
    const int* idx = indices.ptr<int>(i);
    const float* dist = distances.ptr<float>(i);
    int valid = 0;
    while (valid < k && idx[valid] >= 0 && idx[valid] < descriptors_.rows)
      ++valid;
    if (valid < 2)
      continue;
    if (ambiguity == Ambiguity::Reject) {
      const float r = dist[1] > 0.f ? dist[0] / dist[1] : 1.f;
      if (r < ratio)
        matches.push_back(make_match(idx[0], i, dist[0], r));
      continue;
    }
    // The look-alikes of this feature: the models whose nearest descriptor fits nearly as
    // well as the best of all (first[m]: that neighbour's rank, -1 for the other models).
    std::fill(first.begin(), first.end(), -1);
    for (int j = 0; j < valid; ++j) {
      const int m = owner_[idx[j]];
      if (first[m] < 0 && dist[j] * kNearlyAsGood <= dist[0])
        first[m] = j;
    }
    // The ratio test's second neighbour: the nearest that is none of those (without one among
    // the neighbours, the farthest bounds it below).
    float second = dist[valid - 1];
    for (int j = 0; j < valid; ++j)
      if (first[owner_[idx[j]]] != j) {
        second = dist[j];
        break;
      }
    const long look_alikes =
        std::count_if(first.begin(), first.end(), [](int j) { return j >= 0; });
    for (int m = 0; m < n_models; ++m) {
      if (first[m] < 0)
        continue;
      const float d = dist[first[m]];
      const float r = second > 0.f ? d / second : 1.f;
      if (r >= ratio)
        continue;
      matches.push_back(make_match(idx[first[m]], i, d, r));
      matches.back().shared = look_alikes > 1;
    }
  }
  return matches;
}

Match Matcher::make_match(int row, int scene_point, float distance, float ratio) const {
  Match m;
  m.model = owner_[row];
  m.model_point = row - offset_[m.model];
  m.scene_point = scene_point;
  m.distance = distance;
  m.ratio = ratio;
  return m;
}

} // namespace pickdetect
