#pragma once
/// @file A binary min-heap of costs keyed by id (0 <= id < n), at most one entry per id, whose
/// cost can be changed in place; ties go to the lower id. Region merging orders the regions by
/// their cheapest merge with it.

#include <vector>

namespace hgrasp::segment {

class IndexedHeap {
 public:
  explicit IndexedHeap(int n) : pos_(n, -1) {}
  bool empty() const { return nodes_.empty(); }
  /// The id of the lowest cost (ties: the lowest id); the heap must not be empty.
  int top() const { return nodes_[0].id; }
  /// Inserts id with this cost, or changes its cost.
  void Set(int id, double cost) {
    int i = pos_[id];
    if (i < 0) {
      i = static_cast<int>(nodes_.size());
      nodes_.push_back({cost, id});
      Up(i);
    } else if (Less({cost, id}, nodes_[i])) {
      nodes_[i].cost = cost;
      Up(i);
    } else {
      nodes_[i].cost = cost;
      Down(i);
    }
  }
  /// Removes id if present.
  void Remove(int id) {
    const int i = pos_[id];
    if (i < 0) return;
    pos_[id] = -1;
    const Node last = nodes_.back();
    nodes_.pop_back();
    if (i == static_cast<int>(nodes_.size())) return;
    nodes_[i] = last;
    Up(i);
    Down(pos_[last.id]);
  }

 private:
  struct Node {
    double cost;
    int id;
  };
  static bool Less(const Node& a, const Node& b) {
    return a.cost < b.cost || (a.cost == b.cost && a.id < b.id);
  }
  void Place(int i, const Node& x) {
    nodes_[i] = x;
    pos_[x.id] = i;
  }
  void Up(int i) {
    const Node x = nodes_[i];
    while (i > 0 && Less(x, nodes_[(i - 1) / 2])) {
      Place(i, nodes_[(i - 1) / 2]);
      i = (i - 1) / 2;
    }
    Place(i, x);
  }
  void Down(int i) {
    const Node x = nodes_[i];
    const int n = static_cast<int>(nodes_.size());
    for (int c = 2 * i + 1; c < n; c = 2 * i + 1) {
      if (c + 1 < n && Less(nodes_[c + 1], nodes_[c])) ++c;
      if (!Less(nodes_[c], x)) break;
      Place(i, nodes_[c]);
      i = c;
    }
    Place(i, x);
  }

  std::vector<Node> nodes_;
  std::vector<int> pos_;  // per id: its index in nodes_, -1 if absent
};

}  // namespace hgrasp::segment
