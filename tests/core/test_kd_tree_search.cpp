// SPDX-License-Identifier: LGPL-2.1-or-later
// FLANN's kd-tree over byte descriptors, read into a flat array and searched as FLANN searches
// it: the same leaves in the same order.
#include "../../src/kd_tree_search.hpp"
#include "../support/box.hpp"
#include "common/scene.hpp"

#include <pickdetect/pickdetect.hpp>

#include <gtest/gtest.h>
#include <opencv2/flann.hpp>

#include <cstdlib>
#include <limits>
#include <utility>
#include <vector>

using namespace pickdetect;

namespace {

/// The k nearest so far (FLANN's result-set calls), and every distance and row offered, in the
/// order offered: which leaves a search visits, and when.
class Recorder final : public cvflann::ResultSet<float> {
public:
  explicit Recorder(size_t k) : k_(k) {}
  bool full() const override { return best_.size() == k_; }
  float worstDist() const override {
    return full() ? best_.back().first : std::numeric_limits<float>::max();
  }
  void addPoint(float distance, int row) override {
    offered.emplace_back(distance, row);
    if (distance >= worstDist())
      return;
    auto at = best_.begin();
    while (at != best_.end() && at->first <= distance)
      ++at;
    best_.insert(at, {distance, row});
    if (best_.size() > k_)
      best_.pop_back();
  }
  std::vector<std::pair<float, int>> offered;

private:
  size_t k_;
  std::vector<std::pair<float, int>> best_;
};

/// The box model's SIFT descriptors as bytes (OpenCV's SIFT gives whole numbers 0-255).
cv::Mat box_rows() {
  cv::Mat rows;
  test_scene::box_model().sift.descriptors.convertTo(rows, CV_8U);
  return rows;
}

/// A scene's descriptors as bytes: the box turned and shrunk on a plain background.
cv::Mat scene_rows() {
  cv::Mat scene = test_scene::plain_background({640, 480});
  test_scene::paste(scene, test_scene::box_picture(), {{{320.f, 240.f}, 35.0, 0.8}});
  cv::Mat rows;
  extract_features(scene).descriptors.convertTo(rows, CV_8U);
  return rows;
}

std::unique_ptr<cvflann::KDTreeIndex<detail::ByteL2>> build(const cv::Mat& rows, int trees) {
  std::srand(7);
  auto index = std::make_unique<cvflann::KDTreeIndex<detail::ByteL2>>(
      cvflann::Matrix<uchar>(const_cast<uchar*>(rows.ptr<uchar>()), rows.rows, rows.cols),
      cvflann::KDTreeIndexParams(trees));
  index->buildIndex();
  return index;
}

} // namespace

TEST(ByteKdTree, VisitsTheLeavesFlannVisitsInItsOrder) {
  const cv::Mat rows = box_rows(), queries = scene_rows();
  ASSERT_GT(rows.rows, 200);
  ASSERT_GT(queries.rows, 100);
  auto index = build(rows, 1);
  const std::optional<detail::ByteKdTree> tree = detail::ByteKdTree::read(*index, rows);
  ASSERT_TRUE(tree.has_value());
  std::vector<detail::ByteKdTree::Branch> heap;
  size_t offered = 0;
  // Few and many neighbours, few and many leaves (all of them: the exact nearest), and more
  // neighbours than leaves (the search goes on until it holds them).
  for (const auto& [k, checks] : std::vector<std::pair<size_t, int>>{
           {2, 32}, {17, 32}, {2, 256}, {64, 128}, {40, 8}, {3, rows.rows}}) {
    for (int q = 0; q < queries.rows; ++q) {
      Recorder flann(k), ours(k);
      index->findNeighbors(flann, queries.ptr<uchar>(q), cvflann::SearchParams(checks));
      tree->search(queries.ptr<uchar>(q), ours, checks, heap);
      ASSERT_EQ(ours.offered, flann.offered)
          << "query " << q << ", k " << k << ", checks " << checks;
      offered += ours.offered.size();
    }
  }
  EXPECT_GT(offered, static_cast<size_t>(queries.rows) * 32);
}

TEST(ByteKdTree, ReadsOnlyOneTreeOverItsOwnRows) {
  const cv::Mat rows = box_rows();
  // Several trees are searched with a record of the leaves seen: FLANN's own search.
  EXPECT_FALSE(detail::ByteKdTree::read(*build(rows, 4), rows).has_value());
  // Rows that are not the index's.
  auto index = build(rows, 1);
  EXPECT_FALSE(detail::ByteKdTree::read(*index, rows.rowRange(0, rows.rows - 1)).has_value());
  cv::Mat floats;
  rows.convertTo(floats, CV_32F);
  EXPECT_FALSE(detail::ByteKdTree::read(*index, floats).has_value());
  EXPECT_TRUE(detail::ByteKdTree::read(*index, rows).has_value());
}
