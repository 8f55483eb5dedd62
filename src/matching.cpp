// SPDX-License-Identifier: LGPL-2.1-or-later
// Matching: the 2NN ratio test of scene descriptors against all models' descriptors at once,
// rejecting or sharing the features that fit several models (look-alikes) about equally well.
#include <pickdetect/matching.hpp>

#include "byte_descriptors.hpp"
#include "kd_tree_search.hpp"

#include <opencv2/core/utility.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/flann.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <utility>

namespace pickdetect {
namespace {

/// FLANN kd-trees: how many, and how many leaves a search visits (more: closer to exact).
constexpr int kKdTrees = 1;
constexpr int kKdChecks = 32;
/// FLANN draws the trees' split dimensions from the C library's rand(): seeding it right before
/// the build, under a lock, makes the same models give the same trees in every run.
constexpr unsigned kKdSeed = 20240101u;
/// Repeat shifts: offsets between copies are gathered in square bins of this side (model
/// pixels), and an offset counts as a shift of the design when the bin and its eight
/// neighbours hold at least kMinShiftShare of the model's keypoints (its views' included) and
/// at least kMinShiftPairs pairs: a few letters or motifs printed twice are no repeated design.
constexpr float kShiftBinPx = 6.f;
constexpr double kMinShiftShare = 0.05;
constexpr int kMinShiftPairs = 20;
/// Scene descriptors are searched in blocks of this many rows, in parallel: small enough that
/// the few hundred keypoints extracted around a change in a reused frame (feature_reuse.cpp)
/// take both cores. A search costs about a tenth of a millisecond (four models and their tilted
/// views), so a block is some milliseconds of work and a whole frame's hundred-odd blocks cost
/// nothing to share out.
constexpr int kSearchBlock = 32;
/// Ambiguity::Share: neighbours searched per scene descriptor (two per model, at most this).
constexpr int kMaxNeighbours = 16;
/// Neighbours searched per scene descriptor on account of a texture's group (kMaxCopies), at
/// most: the search visits at least as many leaves. A picture of hand-drawn strokes (beltA's
/// pic3, a group of 243) keeps its count; bundles of seven packs with their tilted views (a
/// group of 479 in `HappyFish`'s) made the search 668 ms of a 1280x720 frame's 920
/// (docs/performance.md).
constexpr int kMaxTextureNeighbours = 256;
/// Ambiguity::Share: a model's nearest descriptor within 1 / kNearlyAsGood of the nearest of
/// all fits about as well as the best.
constexpr float kNearlyAsGood = 0.9f;
/// Repeated designs: two keypoints of one model picture are copies of one printed part when
/// their descriptors lie within this distance (L2 for SIFT, whose descriptors OpenCV scales to
/// a norm of 512; Hamming bits for ORB's 256)...
constexpr float kRepeatSiftDistance = 100.f;
constexpr float kRepeatOrbDistance = 20.f;
/// ...and their positions at least this many keypoint sizes (and kMinRepeatGapPx) apart, so that
/// two keypoints of one spot at other orientations are not taken for copies.
constexpr float kRepeatGapSizes = 2.f;
constexpr float kMinRepeatGapPx = 8.f;
/// Shared designs: a row's twins are the descriptors of other products within the SIFT
/// repeat distance above, among its kTwinNeighbours nearest. A product whose twins cover at least
/// kEditionShare of a model's rows is an edition of it (one design in other colours: the
/// frame's colour tells them apart, or nothing does); below, it shares a part (a family's
/// panel), and matches there say nothing of which product an object is.
constexpr int kTwinNeighbours = 8;
constexpr double kEditionShare = 0.5;
/// Leaves the twins' kd-tree search visits: four times the matching's, as twins lie farther
/// apart than the matches the ratio test keeps (32 missed some at 73-98 of the 100).
constexpr int kTwinChecks = 128;

/// The k nearest descriptors FLANN's search has found, kept in the caller's row, ordered by
/// distance and, at equal distance, by row: the order of FLANN's own KNNUniqueResultSet, which
/// cv::flann::Index::knnSearch uses and which allocates a node of a std::set for each
/// candidate (a seventh of the matching stage at 17 neighbours and 32 leaves,
/// docs/performance.md). FLANN's array-based KNNResultSet would not allocate either, but it
/// orders equal distances by arrival, so a tie could pick another nearest row than before.
/// Until the row is full the search drops nothing (worstDist is the largest float): the first k
/// rows offered are gathered as they come and put in that order once, when the k-th comes (a
/// texture's search asks for up to 256 neighbours, which inserted one by one in order cost a
/// shift of half the row each). `order` is room for that, kept by the caller between searches.
/// finish() puts the row in order when fewer than k rows were offered.
class NearestRows final : public cvflann::ResultSet<float> {
public:
  NearestRows(int k, int* rows, float* distances, std::vector<std::pair<float, int>>& order)
      : k_(k), rows_(rows), distances_(distances), order_(order) {}
  bool full() const override { return count_ == k_; }
  float worstDist() const override {
    return count_ == k_ ? distances_[k_ - 1] : std::numeric_limits<float>::max();
  }
  void addPoint(float distance, int row) override {
    if (count_ < k_) {
      distances_[count_] = distance;
      rows_[count_] = row;
      if (++count_ == k_)
        put_in_order();
      return;
    }
    if (distance >= distances_[k_ - 1])
      return;
    int j = k_ - 1;
    for (; j > 0 &&
           (distances_[j - 1] > distance || (distances_[j - 1] == distance && rows_[j - 1] > row));
         --j) {
      distances_[j] = distances_[j - 1];
      rows_[j] = rows_[j - 1];
    }
    distances_[j] = distance;
    rows_[j] = row;
  }
  void finish() {
    if (count_ < k_)
      put_in_order();
  }

private:
  /// By distance, then by row (rows are unique: a strict order, the one insertion keeps). A
  /// distance that is not a number (a caller's own descriptors may hold one) goes last: the
  /// order stays strict, as std::sort needs.
  void put_in_order() {
    order_.resize(static_cast<size_t>(count_));
    for (int i = 0; i < count_; ++i)
      order_[static_cast<size_t>(i)] = {distances_[i], rows_[i]};
    std::sort(order_.begin(), order_.end(), [](const auto& a, const auto& b) {
      const bool a_nan = std::isnan(a.first), b_nan = std::isnan(b.first);
      if (a_nan != b_nan)
        return b_nan;
      if (!a_nan && a.first != b.first)
        return a.first < b.first;
      return a.second < b.second;
    });
    for (int i = 0; i < count_; ++i) {
      distances_[i] = order_[static_cast<size_t>(i)].first;
      rows_[i] = order_[static_cast<size_t>(i)].second;
    }
  }

  int k_;
  int* rows_;
  float* distances_;
  std::vector<std::pair<float, int>>& order_;
  int count_ = 0;
};

int find_root(std::vector<int>& parent, int i) {
  while (parent[i] != i)
    i = parent[i] = parent[parent[i]];
  return i;
}

/// Calls `take(i, j)` for every pair of distinct rows i < j of `rows` whose distance is at most
/// `limit`, in order: what BFMatcher::radiusMatch of the rows against themselves finds. SIFT
/// rows held as bytes (byte_descriptors.hpp) are compared once each way round, in parallel, at
/// the float distance radiusMatch computes (the square root of the same whole number): a bundle
/// of seven packs with its tilted views (16 000 rows) in a fraction of radiusMatch's time. Other
/// rows (ORB's, or SIFT's held as floats) go through radiusMatch. Either way in blocks of rows,
/// a few at a time: a picture of one fine repeated texture has most of its descriptors within
/// the limit of each other, and its pairs are not all held at once.
template <typename Take>
void for_pairs_within(const cv::Mat& rows, float limit, FeatureKind kind, Take take) {
  constexpr int kBlocksAtOnce = 8;
  const int n = rows.rows;
  const int blocks = (n + kSearchBlock - 1) / kSearchBlock;
  const bool bytes = rows.type() == CV_8U && kind == FeatureKind::Sift;
  // The largest squared distance whose float square root, as radiusMatch takes it, is within
  // the limit.
  int within = static_cast<int>(limit * limit);
  while (std::sqrt(static_cast<float>(within + 1)) <= limit)
    ++within;
  while (within > 0 && std::sqrt(static_cast<float>(within)) > limit)
    --within;
  cv::BFMatcher bf(kind == FeatureKind::Orb ? cv::NORM_HAMMING : cv::NORM_L2);
  for (int first = 0; first < blocks; first += kBlocksAtOnce) {
    const int last = std::min(blocks, first + kBlocksAtOnce);
    std::vector<std::vector<std::pair<int, int>>> found(static_cast<size_t>(last - first));
    auto search = [&](int b) {
      std::vector<std::pair<int, int>>& out = found[static_cast<size_t>(b - first)];
      const int start = b * kSearchBlock;
      const int end = std::min(n, start + kSearchBlock);
      if (bytes) {
        for (int i = start; i < end; ++i)
          for (int j = i + 1; j < n; ++j)
            if (detail::squared_distance_until(rows.ptr<uchar>(i), rows.ptr<uchar>(j),
                                               static_cast<size_t>(rows.cols), within) <= within)
              out.emplace_back(i, j);
        return;
      }
      std::vector<std::vector<cv::DMatch>> near;
      bf.radiusMatch(rows.rowRange(start, end), rows, near, limit);
      for (int i = start; i < end; ++i)
        for (const cv::DMatch& d : near[static_cast<size_t>(i - start)])
          if (d.trainIdx > i)
            out.emplace_back(i, d.trainIdx);
      std::sort(out.begin(), out.end());
    };
    if (bytes)
      cv::parallel_for_(cv::Range(first, last), [&](const cv::Range& r) {
        for (int b = r.start; b < r.end; ++b)
          search(b);
      });
    else
      for (int b = first; b < last; ++b)
        search(b);
    for (const auto& block : found)
      for (const auto& [i, j] : block)
        take(i, j);
  }
}

std::mutex& flann_build_lock() {
  static std::mutex lock;
  return lock;
}

/// The offsets between copies (`pairs`, model pixels) that many pairs share, strongest first
/// (see kShiftBinPx): the mean offset around each peak bin, peaks at least two bins apart.
std::vector<cv::Point2f> shifts_of(const std::vector<cv::Point2f>& pairs, int rows) {
  std::map<std::pair<int, int>, std::vector<int>> bins;
  for (size_t i = 0; i < pairs.size(); ++i)
    bins[{cvFloor(pairs[i].x / kShiftBinPx), cvFloor(pairs[i].y / kShiftBinPx)}].push_back(
        static_cast<int>(i));
  struct Peak {
    std::pair<int, int> bin;
    size_t count;
    cv::Point2f mean;
  };
  std::vector<Peak> peaks;
  for (const auto& [bin, members] : bins) {
    size_t count = 0;
    cv::Point2f sum(0.f, 0.f);
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        auto near = bins.find({bin.first + dx, bin.second + dy});
        if (near == bins.end())
          continue;
        count += near->second.size();
        for (int i : near->second)
          sum += pairs[static_cast<size_t>(i)];
      }
    if (count >= static_cast<size_t>(kMinShiftPairs) && count >= kMinShiftShare * rows)
      peaks.push_back({bin, count, sum / static_cast<float>(count)});
  }
  std::stable_sort(peaks.begin(), peaks.end(),
                   [](const Peak& a, const Peak& b) { return a.count > b.count; });
  std::vector<cv::Point2f> out;
  std::vector<std::pair<int, int>> taken;
  for (const Peak& p : peaks) {
    bool apart = true;
    for (const auto& t : taken)
      apart =
          apart && (std::abs(t.first - p.bin.first) > 2 || std::abs(t.second - p.bin.second) > 2);
    if (!apart)
      continue;
    taken.push_back(p.bin);
    out.push_back(p.mean);
  }
  return out;
}

} // namespace

/// One kd-tree over the models' descriptors: over bytes when they are SIFT's whole numbers
/// (byte_descriptors.hpp: the same neighbours, found sooner), over the floats otherwise.
struct Matcher::KdTree {
  cv::Mat data; ///< The descriptors the tree indexes (FLANN keeps only a pointer to them).
  std::unique_ptr<cvflann::KDTreeIndex<detail::ByteL2>> bytes;
  /// The tree of `bytes`, searched as FLANN does without its costs per search.
  std::optional<detail::ByteKdTree> byte_tree;
  std::unique_ptr<cvflann::KDTreeIndex<cvflann::L2<float>>> floats;
};

Matcher::Matcher(const std::vector<Model>& models, FeatureKind kind) : kind_(kind) {
  std::vector<cv::Mat> parts;
  for (size_t m = 0; m < models.size(); ++m) {
    const cv::Mat& d = models[m].features(kind).descriptors;
    offset_.push_back(static_cast<int>(owner_.size()));
    product_.push_back(static_cast<int>(m));
    for (size_t p = 0; p < m; ++p)
      if (models[p].name == models[m].name) {
        product_.back() = static_cast<int>(p);
        break;
      }
    owner_.insert(owner_.end(), d.rows, static_cast<int>(m));
    const auto& kps = models[m].features(kind).keypoints;
    keypoint_.insert(keypoint_.end(), kps.begin(),
                     kps.begin() + std::min<size_t>(kps.size(), d.rows));
    keypoint_.resize(owner_.size());
    if (!d.empty())
      parts.push_back(d);
  }
  if (!parts.empty())
    cv::vconcat(parts, descriptors_);
  if (kind == FeatureKind::Sift && descriptors_.rows >= 2) {
    std::lock_guard<std::mutex> hold(flann_build_lock());
    cvflann::seed_random(kKdSeed);
    auto index = std::make_shared<KdTree>();
    const cvflann::KDTreeIndexParams params(kKdTrees);
    if (detail::whole_bytes(descriptors_)) {
      descriptors_.convertTo(index->data, CV_8U);
      const cvflann::Matrix<uchar> rows(index->data.ptr<uchar>(), index->data.rows,
                                        index->data.cols);
      index->bytes = std::make_unique<cvflann::KDTreeIndex<detail::ByteL2>>(rows, params);
      index->bytes->buildIndex();
      index->byte_tree = detail::ByteKdTree::read(*index->bytes, index->data);
    } else {
      index->data = descriptors_;
      const cvflann::Matrix<float> rows(index->data.ptr<float>(), index->data.rows,
                                        index->data.cols);
      index->floats = std::make_unique<cvflann::KDTreeIndex<cvflann::L2<float>>>(rows, params);
      index->floats->buildIndex();
    }
    index_ = std::move(index);
  }
  find_repeats(models);
  find_shared_designs();
}

void Matcher::find_shared_designs() {
  const int n = descriptors_.rows;
  shared_design_.assign(static_cast<size_t>(n), 0);
  const size_t n_models = offset_.size();
  // SIFT's kd-tree finds the twins in about a quarter of a second for three models with their
  // tilted views (17 000 descriptors). ORB's matcher is built beside SIFT's for every detector:
  // its exhaustive search would cost as much again at every start, whatever the features used.
  if (n < 2 || n_models < 2 || kind_ != FeatureKind::Sift || !index_)
    return;
  const int k = std::min(kTwinNeighbours, n);
  cv::Mat indices, distances;
  nearest(descriptors_, k, Search::KdTree, indices, distances, kTwinChecks);
  // Row -> the other products it has a twin in; per model, how many of its rows have one there.
  std::vector<std::vector<int>> twin_in(static_cast<size_t>(n));
  std::vector<std::vector<int>> rows_with_twin(n_models, std::vector<int>(n_models, 0));
  for (int i = 0; i < n; ++i) {
    const int own = product_[static_cast<size_t>(owner_[i])];
    std::vector<int>& in = twin_in[static_cast<size_t>(i)];
    for (int j = 0; j < k; ++j) {
      const int other = indices.at<int>(i, j);
      if (other < 0 || distances.at<float>(i, j) >= kRepeatSiftDistance)
        continue;
      const int product = product_[static_cast<size_t>(owner_[other])];
      if (product != own && std::find(in.begin(), in.end(), product) == in.end())
        in.push_back(product);
    }
    for (int product : in)
      ++rows_with_twin[static_cast<size_t>(owner_[i])][static_cast<size_t>(product)];
  }
  for (int i = 0; i < n; ++i) {
    const size_t m = static_cast<size_t>(owner_[i]);
    const int rows = (m + 1 < n_models ? offset_[m + 1] : n) - offset_[m];
    for (int product : twin_in[static_cast<size_t>(i)])
      if (rows_with_twin[m][static_cast<size_t>(product)] < kEditionShare * rows)
        shared_design_[static_cast<size_t>(i)] = 1;
  }
}

void Matcher::find_repeats(const std::vector<Model>& models) {
  const int n = descriptors_.rows;
  std::vector<int> parent(n);
  for (int i = 0; i < n; ++i)
    parent[i] = i;
  // Each model's picture matched against itself, exhaustively (the groups must not depend on
  // the kd-tree's approximations), every descriptor within the limit: copies are found however
  // many views of one spot lie nearer, and other models' descriptors cost nothing.
  const float limit = kind_ == FeatureKind::Orb ? kRepeatOrbDistance : kRepeatSiftDistance;
  const cv::Mat& all = index_ && index_->bytes ? index_->data : descriptors_;
  for (size_t m = 0; m < models.size(); ++m) {
    const int first = offset_[m];
    const int rows = (m + 1 < offset_.size() ? offset_[m + 1] : n) - first;
    if (rows < 2)
      continue;
    const auto& kps = models[m].features(kind_).keypoints;
    for_pairs_within(all.rowRange(first, first + rows), limit, kind_, [&](int i, int j) {
      const cv::KeyPoint& a = kps[i];
      const cv::KeyPoint& b = kps[j];
      const float gap = std::max(kMinRepeatGapPx, kRepeatGapSizes * std::max(a.size, b.size));
      const cv::Point2f apart = a.pt - b.pt;
      if (apart.dot(apart) >= gap * gap)
        parent[find_root(parent, first + i)] = find_root(parent, first + j);
    });
  }
  group_.resize(n);
  std::vector<std::vector<int>> members(n);
  for (int i = 0; i < n; ++i) {
    group_[i] = find_root(parent, i);
    members[group_[i]].push_back(i);
  }
  copies_.assign(n, {});
  std::vector<char> texture(n, 0); // Group root -> a texture, no repeated design (kMaxCopies).
  for (int i = 0; i < n; ++i) {
    const std::vector<int>& group = members[group_[i]];
    if (group.size() < 2)
      continue;
    // One copy per place: the row itself, then each member farther than the gap from those
    // taken (members at one spot are views of one keypoint, not copies).
    const int m = owner_[i];
    const auto& kps = models[m].features(kind_).keypoints;
    std::vector<int> taken = {i};
    for (int other : group) {
      const cv::KeyPoint& b = kps[other - offset_[m]];
      bool apart = true;
      for (int t : taken) {
        const cv::KeyPoint& a = kps[t - offset_[m]];
        const float gap = std::max(kMinRepeatGapPx, kRepeatGapSizes * std::max(a.size, b.size));
        const cv::Point2f d = a.pt - b.pt;
        apart = apart && d.dot(d) >= gap * gap;
      }
      if (apart)
        taken.push_back(other);
    }
    if (taken.size() > kMaxCopies)
      texture[group_[i]] = 1;
    else if (taken.size() > 1)
      copies_[i] = std::move(taken);
  }
  // A texture's rows are each their own: matched by the plain ratio test, its copies their
  // rivals, one match each. The neighbours searched still count its group, up to
  // kMaxTextureNeighbours (match): searching fewer changed the other models' matches too (a
  // bin of four other pictures lost 2 % of its recall and gained four false instances).
  largest_group_ = 1;
  largest_texture_ = 0;
  for (int i = 0; i < n; ++i) {
    const int root = group_[i];
    const int size = static_cast<int>(members[root].size());
    if (texture[root]) {
      largest_texture_ = std::max(largest_texture_, size);
      copies_[i].clear();
      group_[i] = i;
    } else {
      largest_group_ = std::max(largest_group_, size);
    }
  }
  shifts_.assign(models.size(), {});
  for (size_t m = 0; m < models.size(); ++m) {
    const int first = offset_[m];
    const int rows = (m + 1 < offset_.size() ? offset_[m + 1] : n) - first;
    std::vector<cv::Point2f> pairs;
    for (int i = first; i < first + rows; ++i)
      for (int c : copies_[i])
        if (c != i)
          for (float way : {1.f, -1.f}) // both ways: the copies of a row are not symmetric
            pairs.push_back(way * (keypoint_[c].pt - keypoint_[i].pt));
    shifts_[m] = shifts_of(pairs, rows);
  }
}

const std::vector<cv::Point2f>& Matcher::repeat_shifts(int model) const {
  static const std::vector<cv::Point2f> none;
  return model >= 0 && static_cast<size_t>(model) < shifts_.size()
             ? shifts_[static_cast<size_t>(model)]
             : none;
}

bool Matcher::same_place(int a, int b) const {
  if (owner_[a] != owner_[b])
    return false;
  const cv::KeyPoint& p = keypoint_[a];
  const cv::KeyPoint& q = keypoint_[b];
  const float gap = std::max(kMinRepeatGapPx, kRepeatGapSizes * std::max(p.size, q.size));
  const cv::Point2f d = p.pt - q.pt;
  return d.dot(d) < gap * gap;
}

void Matcher::push_match(std::vector<Match>& matches, int row, int scene_point, float distance,
                         float ratio, bool shared) const {
  // A repeated part could be any of its copies: one match (one vote) for each.
  shared = shared || shared_design_[static_cast<size_t>(row)];
  if (copies_[row].empty()) {
    matches.push_back(make_match(row, scene_point, distance, ratio));
    matches.back().shared = shared;
    return;
  }
  for (int copy : copies_[row]) {
    matches.push_back(make_match(copy, scene_point, distance, ratio));
    matches.back().shared = shared;
  }
}

void Matcher::nearest(const cv::Mat& queries, int k, Search search, cv::Mat& indices,
                      cv::Mat& distances, int checks) const {
  const int n = queries.rows;
  indices.create(n, k, CV_32S);
  distances.create(n, k, CV_32F);
  // A tree over bytes takes queries that bytes hold exactly; others (a caller's own
  // descriptors against SIFT's) are searched exhaustively below.
  cv::Mat query_bytes;
  const bool by_tree = kind_ == FeatureKind::Sift && search == Search::KdTree && index_ &&
                       (index_->floats || detail::whole_bytes(queries));
  if (by_tree) {
    if (index_->bytes)
      queries.convertTo(query_bytes, CV_8U);
    const cvflann::SearchParams params(checks);
    cv::parallel_for_(cv::Range(0, (n + kSearchBlock - 1) / kSearchBlock), [&](const cv::Range& r) {
      std::vector<detail::ByteKdTree::Branch> heap;
      std::vector<std::pair<float, int>> order;
      for (int i = r.start * kSearchBlock; i < std::min(n, r.end * kSearchBlock); ++i) {
        NearestRows found(k, indices.ptr<int>(i), distances.ptr<float>(i), order);
        if (index_->byte_tree)
          index_->byte_tree->search(query_bytes.ptr<uchar>(i), found, checks, heap);
        else if (index_->bytes)
          index_->bytes->findNeighbors(found, query_bytes.ptr<uchar>(i), params);
        else
          index_->floats->findNeighbors(found, queries.ptr<float>(i), params);
        found.finish();
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
  // Copies of a repeated part are no rivals of each other: the ratio test's second neighbour is
  // searched beyond them. A texture's group is counted too, up to kMaxTextureNeighbours: what
  // its rows cost the kd-tree's search grows with them, not what they are worth.
  auto neighbours = [&](int group) {
    return ambiguity == Ambiguity::Share ? std::clamp(2 * n_models, 2, kMaxNeighbours) + group - 1
                                         : 1 + group;
  };
  const int k = std::min(descriptors_.rows,
                         std::max(neighbours(largest_group_),
                                  std::min(neighbours(std::max(largest_group_, largest_texture_)),
                                           kMaxTextureNeighbours)));
  cv::Mat indices, distances;
  nearest(scene_descriptors, k, search, indices, distances, kKdChecks);
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
      // Another view of the same product is no rival for which product it is.
      auto other_view = [&](int j) {
        return owner_[idx[j]] != owner_[idx[0]] &&
               product_[owner_[idx[j]]] == product_[owner_[idx[0]]];
      };
      float second = dist[valid - 1];
      for (int j = 1; j < valid; ++j)
        if (group_[idx[j]] != group_[idx[0]] && !same_place(idx[j], idx[0]) && !other_view(j)) {
          second = dist[j];
          break;
        }
      const float r = second > 0.f ? dist[0] / second : 1.f;
      if (r < ratio)
        push_match(matches, idx[0], i, dist[0], r, false);
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
    for (int j = 0; j < valid; ++j) {
      const int f = first[owner_[idx[j]]];
      if (f != j && (f < 0 || (group_[idx[f]] != group_[idx[j]] && !same_place(idx[f], idx[j])))) {
        second = dist[j];
        break;
      }
    }
    // Look-alikes of several products (the views of one are no rivals for the product).
    int product = -1;
    bool several = false;
    for (int m = 0; m < n_models; ++m)
      if (first[m] >= 0) {
        several = several || (product >= 0 && product_[m] != product);
        product = product_[m];
      }
    for (int m = 0; m < n_models; ++m) {
      if (first[m] < 0)
        continue;
      const float d = dist[first[m]];
      const float r = second > 0.f ? d / second : 1.f;
      if (r >= ratio)
        continue;
      push_match(matches, idx[first[m]], i, d, r, several);
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
