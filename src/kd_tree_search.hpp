// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: FLANN's kd-tree over byte descriptors, searched without FLANN's
// per-search costs.
//
// cvflann::KDTreeIndex::findNeighbors takes, for every query, a lock shared by all threads (its
// pool of heaps, cvflann::Heap::getPooledInstance, with a walk over the pool), allocates and
// clears a bitset of one bit per indexed row (which leaves were seen, needed only with several
// trees), and calls the result set through virtual functions at every node. ByteKdTree reads the
// tree FLANN built (its saveIndex) into a flat array and runs the same search over it: the same
// nodes in the same order (the same heap of branches, through the same std::push_heap and
// std::pop_heap), the same distances, so the same neighbours.
#pragma once

#include "byte_descriptors.hpp"

#include <opencv2/core.hpp>
#include <opencv2/flann.hpp>

#include <algorithm>
#include <optional>
#include <vector>

namespace pickdetect::detail {

class ByteKdTree {
public:
  /// A branch not taken: the node it starts at and the least squared distance below it.
  struct Branch {
    int node;
    float mindist;
  };

  /// The tree of `index` (built, over `rows`, CV_8U, the rows it indexes), or nothing when the
  /// index does not hold exactly one tree of the layout this reads (then search with FLANN).
  static std::optional<ByteKdTree> read(cvflann::KDTreeIndex<ByteL2>& index, const cv::Mat& rows);

  /// The rows nearest to `query` (rows.cols bytes) into `result` (FLANN's result-set calls:
  /// full(), worstDist(), addPoint(distance, row)), visiting at most `checks` leaves once
  /// `result` is full, as cvflann::KDTreeIndex::findNeighbors with one tree, `checks` and no
  /// eps. `heap`: room for the branches, kept by the caller between searches.
  template <typename Result>
  void search(const uchar* query, Result& result, int checks, std::vector<Branch>& heap) const {
    heap.clear();
    int visited = 0;
    descend(0, 0.f, query, result, checks, visited, heap);
    // FLANN takes the next branch, then stops once enough leaves are visited and the result is
    // full.
    while (!heap.empty()) {
      const Branch next = heap.front();
      std::pop_heap(heap.begin(), heap.end(), Later());
      heap.pop_back();
      if (visited >= checks && result.full())
        break;
      descend(next.node, next.mindist, query, result, checks, visited, heap);
    }
  }

private:
  /// Pre-order: an inner node's first child is the next node. `second` < 0 marks a leaf, whose
  /// `feature` is the row it holds; an inner node cuts `feature` at `value`.
  struct Node {
    int feature;
    float value;
    int second;
  };

  /// FLANN's heap order (cvflann::greater over BranchStruct's operator<): a min-heap by
  /// mindist. A type, not a function, so that the heap's calls to it are inlined.
  struct Later {
    bool operator()(const Branch& a, const Branch& b) const { return b.mindist < a.mindist; }
  };

  /// cvflann::KDTreeIndex::searchLevel, its tail call as a loop.
  template <typename Result>
  void descend(int node, float mindist, const uchar* query, Result& result, int checks,
               int& visited, std::vector<Branch>& heap) const {
    const ByteL2 distance;
    for (;;) {
      if (result.worstDist() < mindist)
        return;
      const Node& n = nodes_[static_cast<size_t>(node)];
      if (n.second < 0) {
        if (visited >= checks && result.full())
          return;
        ++visited;
        result.addPoint(distance(rows_.ptr<uchar>(n.feature), query, cols_), n.feature);
        return;
      }
      const uchar value = query[n.feature];
      const float diff = value - n.value;
      const int best = diff < 0 ? node + 1 : n.second;
      const int other = diff < 0 ? n.second : node + 1;
      const float below = mindist + distance.accum_dist(value, n.value, n.feature);
      if (below < result.worstDist() || !result.full()) {
        heap.push_back({other, below});
        std::push_heap(heap.begin(), heap.end(), Later());
      }
      node = best;
    }
  }

  std::vector<Node> nodes_;
  cv::Mat rows_;
  size_t cols_ = 0;
};

} // namespace pickdetect::detail
