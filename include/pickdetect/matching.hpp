// SPDX-License-Identifier: LGPL-2.1-or-later
#pragma once

#include <pickdetect/features.hpp>
#include <pickdetect/model.hpp>

#include <opencv2/core.hpp>

#include <memory>
#include <vector>

namespace cv::flann {
class Index;
}

namespace pickdetect {

/// How the two nearest model descriptors of each scene descriptor are searched.
enum class Search {
  KdTree,     ///< FLANN's randomised kd-trees, built with a fixed seed: fast, deterministic.
  BruteForce, ///< Every pair compared: exact, several times slower on large frames.
};

/// Matches scene descriptors against the descriptors of every model at once: the two nearest
/// neighbours of a scene descriptor are searched over all models together, so a scene feature
/// that fits two models about equally well fails the ratio test and decides for neither.
/// Immutable once built; copies share the search index.
class Matcher {
public:
  Matcher() = default;
  /// Matches against the models' features of the given kind. SIFT descriptors are searched
  /// with a kd-tree or by brute force; ORB's binary ones by brute force (Hamming distance).
  explicit Matcher(const std::vector<Model>& models, FeatureKind kind = FeatureKind::Sift);

  /// Matches with the 2NN ratio test: nearest / second nearest distance below `ratio`.
  /// The result is ordered by scene keypoint and does not depend on threads or timing.
  std::vector<Match> match(const cv::Mat& scene_descriptors, double ratio,
                           Search search = Search::KdTree) const;

  bool empty() const { return descriptors_.empty(); }

private:
  FeatureKind kind_ = FeatureKind::Sift;
  cv::Mat descriptors_;     ///< All models' descriptors, stacked.
  std::vector<int> owner_;  ///< Row -> model index.
  std::vector<int> offset_; ///< Model index -> first row.
  std::shared_ptr<cv::flann::Index> index_;
};

} // namespace pickdetect
