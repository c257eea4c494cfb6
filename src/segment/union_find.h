#pragma once
/// @file Union-find over 0..n-1 with path halving; Union keeps the first argument's root, so the
/// callers' choice of root (the lower label, the first region) is deterministic.

#include <numeric>
#include <vector>

namespace hgrasp::segment {

class UnionFind {
 public:
  explicit UnionFind(int n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0); }
  int Find(int a) {
    while (parent_[a] != a) {
      parent_[a] = parent_[parent_[a]];
      a = parent_[a];
    }
    return a;
  }
  /// Joins the sets of a and b; returns the root kept (a's).
  int Union(int a, int b) {
    a = Find(a);
    b = Find(b);
    if (a != b) parent_[b] = a;
    return a;
  }

 private:
  std::vector<int> parent_;
};

}  // namespace hgrasp::segment
