// SPDX-License-Identifier: LGPL-2.1-or-later
// FLANN's kd-tree read from its saveIndex into a flat array (kd_tree_search.hpp).
#include "kd_tree_search.hpp"

#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace pickdetect::detail {
namespace {

/// A node as cvflann::KDTreeIndex<ByteL2>::saveIndex writes it (its struct Node, written whole):
/// the cut's dimension (a leaf: its row), the cut's value, and the children's addresses in the
/// saving process, of which only whether they are null tells anything.
struct SavedNode {
  int divfeat;
  ByteL2::ResultType divval;
  const void* child1;
  const void* child2;
};

/// What open_memstream gathers, freed with it.
struct Saved {
  char* bytes = nullptr;
  size_t size = 0;
  ~Saved() { std::free(bytes); }
};

} // namespace

std::optional<ByteKdTree> ByteKdTree::read(cvflann::KDTreeIndex<ByteL2>& index,
                                           const cv::Mat& rows) {
  const int n = rows.rows;
  if (rows.type() != CV_8UC1 || n < 1 || static_cast<int>(index.size()) != n ||
      static_cast<int>(index.veclen()) != rows.cols)
    return std::nullopt;
  Saved saved;
  std::FILE* stream = open_memstream(&saved.bytes, &saved.size);
  if (!stream)
    return std::nullopt;
  index.saveIndex(stream);
  if (std::fclose(stream) != 0)
    return std::nullopt;
  // One tree, then its 2n - 1 nodes in pre-order, and nothing else.
  const size_t nodes = 2 * static_cast<size_t>(n) - 1;
  int trees = 0;
  if (saved.size != sizeof(int) + nodes * sizeof(SavedNode))
    return std::nullopt;
  std::memcpy(&trees, saved.bytes, sizeof(int));
  if (trees != 1)
    return std::nullopt;
  ByteKdTree tree;
  tree.nodes_.resize(nodes);
  std::vector<char> seen(static_cast<size_t>(n), 0);
  // Inner nodes whose second child is still to come, innermost last.
  std::vector<size_t> open;
  for (size_t i = 0; i < nodes; ++i) {
    SavedNode s;
    std::memcpy(&s, saved.bytes + sizeof(int) + i * sizeof(SavedNode), sizeof(SavedNode));
    // A node after a leaf is the second child of the innermost open inner node.
    if (i > 0 && tree.nodes_[i - 1].second == -1) {
      if (open.empty())
        return std::nullopt;
      tree.nodes_[open.back()].second = static_cast<int>(i);
      open.pop_back();
    }
    Node& node = tree.nodes_[i];
    const bool leaf = s.child1 == nullptr && s.child2 == nullptr;
    if (leaf) {
      if (s.divfeat < 0 || s.divfeat >= n || seen[static_cast<size_t>(s.divfeat)])
        return std::nullopt;
      seen[static_cast<size_t>(s.divfeat)] = 1;
      node = {s.divfeat, 0.f, -1};
    } else {
      if (s.child1 == nullptr || s.child2 == nullptr || s.divfeat < 0 || s.divfeat >= rows.cols)
        return std::nullopt;
      node = {s.divfeat, s.divval, -2}; // -2: its second child not found yet
      open.push_back(i);
    }
  }
  if (!open.empty())
    return std::nullopt;
  tree.rows_ = rows;
  tree.cols_ = static_cast<size_t>(rows.cols);
  return tree;
}

} // namespace pickdetect::detail
