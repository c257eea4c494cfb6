#include "segment/merge_regions.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <utility>

#include "segment/indexed_heap.h"

namespace hgrasp::segment {
namespace {

using RegionPairs = std::vector<std::pair<int, int>>;

/// Neighbouring cells of different regions (right and down), as region pairs, in raster order.
RegionPairs AdjacentPairs(const std::vector<int>& label, const CellGrid& grid) {
  const int rows = grid.rows, cols = grid.cols;
  RegionPairs pairs;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const int i = r * cols + c;
      if (label[i] < 0) continue;
      for (int j : {c + 1 < cols ? i + 1 : -1, r + 1 < rows ? i + cols : -1}) {
        if (j < 0 || label[j] < 0 || label[j] == label[i]) continue;
        if (grid.Near(i, j)) pairs.emplace_back(label[i], label[j]);
      }
    }
  }
  return pairs;
}

/// The region k was merged into, by into[k] (k while it is not), halving the paths.
int Root(std::vector<int>* into, int k) {
  std::vector<int>& v = *into;
  while (v[k] != k) k = v[k] = v[v[k]];
  return k;
}

/// The free merges: adjacent regions of at most three cells together, in the order of pairs
/// (whose regions become their roots at the time).
void MergeFree(RegionPairs* pairs, std::vector<Moments>* moments, std::vector<int>* into) {
  for (auto& [a, b] : *pairs) {
    a = Root(into, a);
    b = Root(into, b);
    if (a == b || (*moments)[a].n() + (*moments)[b].n() > 3.0) continue;
    if (a > b) std::swap(a, b);
    (*moments)[a].Add((*moments)[b]);
    (*into)[b] = a;
  }
}

/// The regions left after the free merges, renumbered densely in the same order, with each
/// region's neighbours and merge costs, merged by cost.
class Merger {
 public:
  /// The regions k with into[k] == k.
  Merger(const std::vector<Moments>& moments, const std::vector<int>& into);
  /// Each region's distinct neighbours from the region pairs (original indices, mapped by
  /// `root`), with the merge costs; consumes pairs.
  template <typename Root>
  void Connect(RegionPairs* pairs, const Root& root);
  /// Merges the cheapest pair while its cost is at most max_cost.
  void Run(double max_cost);
  /// The merged sums of the regions left into moments, and into[k] for the regions merged away
  /// (the original index of the region that took them in).
  void Write(std::vector<Moments>* moments, std::vector<int>* into) const;

 private:
  // The data that one merge touches together.
  struct alignas(64) Region {
    Moments m;
    double residual = 0.0;                                       // of its own plane fit
    double best_cost = std::numeric_limits<double>::infinity();  // its cheapest merge ...
    int best_to = -1;                                            // ... with this region
    int mark = -1;                                               // scratch
    int begin = 0, size = 0, capacity = 0;  // its neighbour list: edges_[begin, begin + size)
    int original = 0;                       // its index in `moments`
    int into = -1;                          // the region it was merged into; -1 while alive
  };
  struct Edge {
    int to;       // the neighbouring region
    double cost;  // residual of the two merged
  };

  void BuildEdges(const std::vector<int>& start, const std::vector<int>& nb);
  double MergeCost(const Region& a, const Region& b, double scaled_bound) const;
  void SetKey(int a);
  void UpdateBest(int a);
  void Merge(int a, int b, double cost);
  void CollectJoined(int a, int b, double n_a, double n_b);
  void Relink(int c, int a, int b, double cost);

  std::vector<int> dense_;  // per original region: its dense index, -1 if merged away
  std::vector<Region> region_;
  std::vector<Edge> edges_;
  IndexedHeap queue_;  // each region's cheapest merge, if at most max_cost_
  double max_cost_ = 0.0;
  std::vector<Edge> joined_;  // scratch of Merge
  int step_ = 0;              // marks: above the region indices used while building the lists
};

Merger::Merger(const std::vector<Moments>& moments, const std::vector<int>& into)
    : dense_(moments.size(), -1), queue_(0) {
  const int n_regions = static_cast<int>(moments.size());
  int n = 0;
  for (int k = 0; k < n_regions; ++k) {
    if (into[k] == k) dense_[k] = n++;
  }
  region_.resize(n);
  for (int k = 0; k < n_regions; ++k) {
    if (dense_[k] < 0) continue;
    Region& r = region_[dense_[k]];
    r.m = moments[k];
    r.original = k;
    r.residual = Residual(r.m);
  }
  queue_ = IndexedHeap(n);
  step_ = n;
}

// Each region's distinct neighbours (CSR, then deduplicated).
template <typename Root>
void Merger::Connect(RegionPairs* pairs, const Root& root) {
  const int n = static_cast<int>(region_.size());
  std::vector<int> start(n + 1, 0);
  for (auto& [a, b] : *pairs) {
    a = dense_[root(a)];
    b = dense_[root(b)];
    if (a != b) ++start[a + 1], ++start[b + 1];
  }
  for (int k = 0; k < n; ++k) start[k + 1] += start[k];
  std::vector<int> fill(start.begin(), start.end() - 1), nb(start[n]);
  for (const auto& [a, b] : *pairs) {
    if (a != b) nb[fill[a]++] = b, nb[fill[b]++] = a;
  }
  RegionPairs().swap(*pairs);
  BuildEdges(start, nb);
}

// The neighbour lists from the CSR lists (start, nb), each neighbour once, with the merge costs.
void Merger::BuildEdges(const std::vector<int>& start, const std::vector<int>& nb) {
  const int n = static_cast<int>(region_.size());
  int total = 0;
  for (int a = 0; a < n; ++a) {
    region_[a].begin = total;
    for (int e = start[a]; e < start[a + 1]; ++e) {
      if (region_[nb[e]].mark != a) region_[nb[e]].mark = a, ++total;
    }
    region_[a].capacity = total - region_[a].begin;
  }
  edges_.resize(total);
  for (Region& r : region_) r.mark = -1;
  for (int a = 0; a < n; ++a) {
    Region& ra = region_[a];
    for (int e = start[a]; e < start[a + 1]; ++e) {
      const int b = nb[e];
      Region& rb = region_[b];
      if (b < a || rb.mark == a) continue;  // each pair once, from its lower region
      rb.mark = a;
      const double cost = MergeCost(ra, rb, 0.0);
      edges_[ra.begin + ra.size++] = {b, cost};
      edges_[rb.begin + rb.size++] = {a, cost};
    }
  }
}

// The residual of a and b merged. `scaled_bound`: a lower bound of it times the pair's points,
// if known.
double Merger::MergeCost(const Region& a, const Region& b, double scaled_bound) const {
  Moments m = a.m;
  m.Add(b.m);
  if (m.n() <= 3.0) return 0.0;
  // The merged residual is at least the mean of the two (the smallest eigenvalue is concave).
  const double w = 1.0 / m.n();
  const double start = w * std::max(scaled_bound, a.m.n() * a.residual + b.m.n() * b.residual);
  return SmallestEigenvalue(Covariance(m.v.data(), w), start);
}

// Keys region a by its cheapest merge.
void Merger::SetKey(int a) {
  if (region_[a].best_cost <= max_cost_) {
    queue_.Set(a, region_[a].best_cost);
  } else {
    queue_.Remove(a);
  }
}

// Sets a's cheapest merge from its list (ties: the lower neighbour).
void Merger::UpdateBest(int a) {
  Region& ra = region_[a];
  ra.best_cost = std::numeric_limits<double>::infinity();
  ra.best_to = -1;
  for (int e = ra.begin; e < ra.begin + ra.size; ++e) {
    const Edge& x = edges_[e];
    if (x.cost < ra.best_cost || (x.cost == ra.best_cost && x.to < ra.best_to)) {
      ra.best_cost = x.cost;
      ra.best_to = x.to;
    }
  }
  SetKey(a);
}

void Merger::Run(double max_cost) {
  max_cost_ = max_cost;
  const int n = static_cast<int>(region_.size());
  for (int a = 0; a < n; ++a) UpdateBest(a);
  while (!queue_.empty()) {
    const int t = queue_.top();
    Merge(std::min(t, region_[t].best_to), std::max(t, region_[t].best_to), region_[t].best_cost);
  }
}

// Merges b into a (a < b) at this cost.
void Merger::Merge(int a, int b, double cost) {
  Region& ra = region_[a];
  Region& rb = region_[b];
  const double n_a = ra.m.n(), n_b = rb.m.n();
  ra.residual = cost;
  ra.m.Add(rb.m);
  rb.into = a;
  queue_.Remove(b);
  CollectJoined(a, b, n_a, n_b);
  for (Edge& j : joined_) {
    j.cost = MergeCost(ra, region_[j.to], j.cost);
    Relink(j.to, a, b, j.cost);
  }
  if (static_cast<int>(joined_.size()) > ra.capacity) {
    ra.begin = static_cast<int>(edges_.size());
    ra.capacity = 2 * static_cast<int>(joined_.size());
    edges_.resize(edges_.size() + ra.capacity);
  }
  std::copy(joined_.begin(), joined_.end(), edges_.begin() + ra.begin);
  ra.size = static_cast<int>(joined_.size());
  rb.size = 0;
  UpdateBest(a);
}

// a's neighbours after b merged into it (n_a and n_b points before): those of a and b, each once,
// into joined_, with lower bounds of their new costs times the new pair's points. A pair's
// covariance is at least (old points / new points) times that of the pair before, so the old
// costs give lower bounds of the new ones.
void Merger::CollectJoined(int a, int b, double n_a, double n_b) {
  Region& ra = region_[a];
  Region& rb = region_[b];
  ++step_;
  ra.mark = rb.mark = step_;
  joined_.clear();
  for (const Region* x : {&ra, &rb}) {
    const double n_x = x == &ra ? n_a : n_b;
    for (int e = x->begin; e < x->begin + x->size; ++e) {
      Region& rc = region_[edges_[e].to];
      const double n_c = rc.m.n();
      const double bound = edges_[e].cost * (n_x + n_c);
      if (rc.mark == step_) {  // a neighbour of both
        for (Edge& j : joined_) {
          if (j.to == edges_[e].to) j.cost = std::max(j.cost, bound);
        }
        continue;
      }
      rc.mark = step_;
      joined_.push_back({edges_[e].to, bound});
    }
  }
}

// c's edges to a and b (b just merged into a) become one edge to a at this cost; its cheapest
// merge follows.
void Merger::Relink(int c, int a, int b, double cost) {
  Region& rc = region_[c];
  bool found = false;
  for (int e = rc.begin; e < rc.begin + rc.size;) {
    if (edges_[e].to != a && edges_[e].to != b) {
      ++e;
    } else if (!found) {
      edges_[e++] = {a, cost};
      found = true;
    } else {
      edges_[e] = edges_[rc.begin + --rc.size];
    }
  }
  if (rc.best_to == a || rc.best_to == b) {
    UpdateBest(c);
  } else if (cost < rc.best_cost || (cost == rc.best_cost && a < rc.best_to)) {
    rc.best_cost = cost;
    rc.best_to = a;
    SetKey(c);
  }
}

void Merger::Write(std::vector<Moments>* moments, std::vector<int>* into) const {
  const int n = static_cast<int>(region_.size());
  for (int k = n - 1; k >= 0; --k) {  // survivors have lower indices than what they took in
    const Region& r = region_[k];
    if (r.into < 0) {
      (*moments)[r.original] = r.m;
    } else {
      (*into)[r.original] = region_[r.into].original;
    }
  }
}

}  // namespace

std::vector<int> MergeRegions(const std::vector<int>& label, const CellGrid& grid, double max_cost,
                              std::vector<Moments>* moments) {
  RegionPairs pairs = AdjacentPairs(label, grid);
  // into[k]: the region k was merged into, k while it is not.
  std::vector<int> into(moments->size());
  std::iota(into.begin(), into.end(), 0);
  MergeFree(&pairs, moments, &into);
  Merger merger(*moments, into);
  merger.Connect(&pairs, [&](int k) { return Root(&into, k); });
  merger.Run(max_cost);
  merger.Write(moments, &into);
  for (int k = 0; k < static_cast<int>(into.size()); ++k) into[k] = Root(&into, k);
  return into;
}

}  // namespace hgrasp::segment
