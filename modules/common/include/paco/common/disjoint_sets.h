#pragma once
// Disjoint sets of the indices 0..n-1 (union-find with path halving), for grouping faces or cells
// that touch: a mesh's components and vertex fans, the clean-up's coplanar faces, the cell
// complex's inside groups.
#include <cstddef>
#include <numeric>
#include <vector>

namespace paco {

template <typename Index>
class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), Index{0}); }

  /// The representative of x's set.
  Index find(Index x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  /// Puts a's set into b's (b's representative stays).
  void join(Index a, Index b) { parent_[find(a)] = find(b); }

 private:
  std::vector<Index> parent_;
};

}  // namespace paco
