// SPDX-License-Identifier: LGPL-2.1-or-later
#pragma once

#include <pickdetect/features.hpp>
#include <pickdetect/model.hpp>

#include <opencv2/core.hpp>

#include <memory>
#include <vector>

namespace pickdetect {

/// What the matching does with a scene feature that fits several models about equally well
/// (look-alike products share parts of their design).
enum class Ambiguity {
  /// The two nearest neighbours are searched over all models together: such a feature fails
  /// the ratio test and decides for none (the paper's matching). The views of one product
  /// (models of one name) are no rivals: the second neighbour is searched beyond them.
  Reject,
  /// The models whose nearest descriptor fits nearly as well as the best of all are the
  /// feature's look-alikes. Each of their nearest is tested against the nearest descriptor
  /// that is none of theirs, and each that passes gets a match, marked `shared` when the
  /// look-alikes are of several products (views of one product, models of one name, are no
  /// rivals for which product it is). Which product the object is must then be decided from the
  /// instances. Without look-alikes this is the same test as Reject.
  Share,
};

/// Matches scene descriptors against the descriptors of every model at once (one search index
/// over all of them); a scene feature that fits several models about equally well is rejected
/// or shared, as asked (Ambiguity). A model picture whose design repeats a part (a bundle of
/// identical packs) is matched against itself when the matcher is built: a scene feature on
/// such a part gets one match for each copy, so that it votes for every place it could mean,
/// and the copies are not each other's rivals in the ratio test. Immutable once built; copies
/// share the search index.
class Matcher {
public:
  /// A part with more copies than this is a texture, not a design repeated a few times (a bundle
  /// of four packs: up to 32 places for a part of its print, its packs' own repeats and tilted
  /// views included). A match there would vote for every place it could mean and say little of
  /// any: a picture of hand-drawn strokes of one width (opencv-doc's pic3.png, 243 places for a
  /// quarter of its keypoints) made 10,000 matches of a belt frame's 3,500 keypoints and 1,300
  /// hypotheses. A texture's keypoints are matched as any other: the ratio test, their copies
  /// its rivals.
  static constexpr size_t kMaxCopies = 32;

  Matcher() = default;
  /// Matches against the models' features of the given kind. SIFT descriptors are searched
  /// with a kd-tree or by brute force; ORB's binary ones by brute force (Hamming distance).
  /// The kd-tree holds SIFT's descriptors as bytes (OpenCV's SIFT gives whole numbers from 0 to
  /// 255); scene descriptors that are not such whole numbers, against models whose are, are
  /// searched by brute force instead.
  explicit Matcher(const std::vector<Model>& models, FeatureKind kind = FeatureKind::Sift);

  /// Matches with the 2NN ratio test: nearest / second nearest distance below `ratio`.
  /// The result is ordered by scene keypoint (then model) and does not depend on threads or
  /// timing.
  std::vector<Match> match(const cv::Mat& scene_descriptors, double ratio,
                           Search search = Search::KdTree,
                           Ambiguity ambiguity = Ambiguity::Reject) const;

  bool empty() const { return descriptors_.empty(); }

  /// Repeated designs: the shifts, in model picture pixels, that carry a printed part of model
  /// `model` onto a copy of it (each copy's offset, both ways: a bundle of four packs side by
  /// side has three each way), found when the matcher was built. Empty when nothing repeats.
  const std::vector<cv::Point2f>& repeat_shifts(int model) const;

private:
  /// The k nearest model descriptors of each query row (indices, -1 where none; L2 or Hamming
  /// distances); `checks`: the leaves a kd-tree search visits.
  void nearest(const cv::Mat& queries, int k, Search search, cv::Mat& indices, cv::Mat& distances,
               int checks) const;
  Match make_match(int row, int scene_point, float distance, float ratio) const;
  /// Repeated designs: groups the rows that are copies of one printed part of their model
  /// picture (the picture matched against itself).
  void find_repeats(const std::vector<Model>& models);
  /// Designs shared by look-alike products: marks the rows with a twin among another
  /// product's descriptors, where that product shares a part of the picture only (a family's
  /// brand panel), not the whole of it (an edition in other colours).
  void find_shared_designs();
  /// Appends the match of a scene feature to `row`, or, when `row` is a copy of a repeated
  /// part, one match to each of its copies.
  void push_match(std::vector<Match>& matches, int row, int scene_point, float distance,
                  float ratio, bool shared) const;

  FeatureKind kind_ = FeatureKind::Sift;
  cv::Mat descriptors_;                ///< All models' descriptors, stacked.
  std::vector<int> owner_;             ///< Row -> model index.
  std::vector<cv::KeyPoint> keypoint_; ///< Row -> its model keypoint.
  /// Whether two rows (of one model) lie at one place of the picture: views of one keypoint.
  bool same_place(int a, int b) const;
  std::vector<int> offset_; ///< Model index -> first row.
  /// Model index -> its product (the first model of its name): a feature that fits only views
  /// of one product is no look-alike's, and its matches are not `shared`.
  std::vector<int> product_;
  struct KdTree; ///< FLANN's kd-tree over descriptors_ (SIFT only), as bytes when they are.
  std::shared_ptr<const KdTree> index_;
  std::vector<int> group_;               ///< Row -> its repeat group (itself when unrepeated).
  std::vector<std::vector<int>> copies_; ///< Row -> the rows of its group (empty: none).
  std::vector<std::vector<cv::Point2f>> shifts_; ///< Model index -> repeat_shifts.
  int largest_group_ = 1;                        ///< Rows of the largest repeated design's group.
  int largest_texture_ = 0; ///< Rows of the largest texture's group (kMaxCopies).
  /// Row -> whether its keypoint lies on a design another product shares (find_shared_designs):
  /// its matches are `shared`, whichever of the products the scene feature lies nearest.
  std::vector<char> shared_design_;
};

} // namespace pickdetect
