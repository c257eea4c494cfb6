#include "segment/segment.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <queue>
#include <string>
#include <utility>

#include "common/error.h"

namespace hgrasp::segment {
namespace {

/// A symmetric 3x3 matrix by its upper triangle: xx, xy, xz, yy, yz, zz.
using Sym3 = std::array<double, 6>;

/// Moment sums of a point set, relative to a common reference point to limit cancellation:
/// v = n, sum x, sum y, sum z, then sum p p^T's upper triangle (xx, xy, xz, yy, yz, zz).
struct Moments {
  std::array<double, 10> v{};

  void Add(const Eigen::Vector3d& p) {
    const double x = p.x(), y = p.y(), z = p.z();
    const std::array<double, 10> q = {1.0, x, y, z, x * x, x * y, x * z, y * y, y * z, z * z};
    for (int k = 0; k < 10; ++k) v[k] += q[k];
  }
  void Add(const Moments& o) {
    for (int k = 0; k < 10; ++k) v[k] += o.v[k];
  }
  void Remove(const Eigen::Vector3d& p) {
    const double x = p.x(), y = p.y(), z = p.z();
    const std::array<double, 10> q = {1.0, x, y, z, x * x, x * y, x * z, y * y, y * z, z * z};
    for (int k = 0; k < 10; ++k) v[k] -= q[k];
  }
  double n() const { return v[0]; }
  Eigen::Vector3d Mean() const { return Eigen::Vector3d(v[1], v[2], v[3]) / v[0]; }
};

/// Covariance (upper triangle) of the points whose moment sums are v (layout of Moments::v); w:
/// 1 / v[0].
Sym3 Covariance(const double* v, double w) {
  const double mx = v[1] * w, my = v[2] * w, mz = v[3] * w;
  return {v[4] * w - mx * mx, v[5] * w - mx * my, v[6] * w - mx * mz,
          v[7] * w - my * my, v[8] * w - my * mz, v[9] * w - mz * mz};
}

Eigen::Matrix3d Full(const Sym3& m) {
  Eigen::Matrix3d a;
  a << m[0], m[1], m[2], m[1], m[3], m[4], m[2], m[4], m[5];
  return a;
}

/// Whether a Halley step `step` (from the left of the smallest root of x^3 - c2 x^2 + c1 x - c0,
/// to x, where the derivative is dp) leaves x within 1e-15 x of the root: the next error is
/// about |step|^3 |p''^2 / (4 p'^2) - p''' / (6 p')|, with |p''| <= 2 c2 there and p''' = 6.
bool Converged(double c2, double dp, double step, double x) {
  const double s = std::abs(step);
  return (c2 * c2 + dp) * s * s * s <= 1e-15 * x * dp * dp;
}

/// Smallest eigenvalue of a symmetric positive semi-definite (up to rounding) matrix, clamped at
/// 0, by Halley's method on the characteristic polynomial from `start`, which must not exceed
/// it (0 always qualifies; a lower bound near it saves steps): the polynomial's roots are all
/// real, so from the left of the smallest one the iterates rise to it, cubically for a plane-like
/// point set (smallest eigenvalue far below the others), and no trigonometric function is needed
/// (unlike the closed form). Returns a value above `stop_above` as soon as an iterate exceeds it.
double SmallestEigenvalue(const Sym3& m, double start = 0.0,
                          double stop_above = std::numeric_limits<double>::infinity()) {
  const double a = m[0], d = m[1], f = m[2], b = m[3], e = m[4], c = m[5];
  // det(x I - m) = x^3 - c2 x^2 + c1 x - c0.
  const double c2 = a + b + c;
  const double c1 = a * b - d * d + a * c - f * f + b * c - e * e;
  const double c0 = a * (b * c - e * e) - d * (d * c - e * f) + f * (d * e - b * f);
  if (!(c0 > 0.0)) return 0.0;  // a zero (or, by rounding, negative) eigenvalue
  double x = std::max(0.0, start);
  for (int k = 0; k < 100; ++k) {
    const double p = ((x - c2) * x + c1) * x - c0;
    const double dp = (3.0 * x - 2.0 * c2) * x + c1;
    const double den = 2.0 * dp * dp - p * (6.0 * x - 2.0 * c2);
    if (!(dp > 0.0 && den > 0.0)) break;  // past the smallest root or at a double one
    const double step = 2.0 * p * dp / den;
    x -= step;
    if (x > stop_above) return x;
    // The next error is about |step|^3 |p''^2 / (4 p'^2) - p''' / (6 p')|, with |p''| <= 2 c2
    // left of the root and p''' = 6.
    if (Converged(c2, dp, step, x)) return std::max(0.0, x);
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(Full(m), Eigen::EigenvaluesOnly);
  return std::max(0.0, es.eigenvalues()(0));
}

/// Unit eigenvector of m for its smallest eigenvalue lambda (up to sign): the largest cross
/// product of two rows of m - lambda I, which span the other eigenvectors; Eigen's solver where
/// those rows are (nearly) parallel, i.e. the smallest eigenvalue is not simple.
Eigen::Vector3d SmallestEigenvector(const Sym3& m, double lambda) {
  const Eigen::Vector3d r0(m[0] - lambda, m[1], m[2]);
  const Eigen::Vector3d r1(m[1], m[3] - lambda, m[4]);
  const Eigen::Vector3d r2(m[2], m[4], m[5] - lambda);
  const Eigen::Vector3d c[3] = {r0.cross(r1), r0.cross(r2), r1.cross(r2)};
  const double n2[3] = {c[0].squaredNorm(), c[1].squaredNorm(), c[2].squaredNorm()};
  const int k = n2[0] >= n2[1] ? (n2[0] >= n2[2] ? 0 : 2) : (n2[1] >= n2[2] ? 1 : 2);
  const double scale = std::max({r0.squaredNorm(), r1.squaredNorm(), r2.squaredNorm()});
  if (n2[k] > 1e-20 * scale * scale) return c[k] / std::sqrt(n2[k]);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(Full(m));
  return es.eigenvectors().col(0).normalized();
}

/// Smallest eigenvalue of a moment set's covariance (m^2); 0 for at most 3 points (which always
/// lie in a plane). `start`: a lower bound (see SmallestEigenvalue).
double Residual(const Moments& m, double start = 0.0) {
  if (m.n() <= 3.0) return 0.0;
  return SmallestEigenvalue(Covariance(m.v.data(), 1.0 / m.n()), start);
}

/// Orients a unit normal after PlaneRegion::normal_W's convention.
Eigen::Vector3d Orient(Eigen::Vector3d n) {
  constexpr double kHorizontal = 0.70710678118654752;
  bool flip;
  if (std::abs(n.z()) >= kHorizontal) {
    flip = n.z() < 0.0;
  } else if (n.x() != 0.0) {
    flip = n.x() > 0.0;
  } else {
    flip = n.y() > 0.0;
  }
  return flip ? Eigen::Vector3d(-n) : n;
}

/// Plane fit of a moment set: unit normal (oriented) and smallest eigenvalue, by Eigen's
/// iterative solver (for the few regions, where accuracy matters more than time).
void FitPlane(const Moments& m, Eigen::Vector3d* normal, double* residual) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(Full(Covariance(m.v.data(), 1.0 / m.n())));
  *normal = Orient(es.eigenvectors().col(0).normalized());
  *residual = std::max(0.0, es.eigenvalues()(0));
}

void CheckConfig(const SegmentConfig& c) {
  auto bad = [](const std::string& field, double v, const std::string& expected) {
    throw InputError("", "SegmentConfig." + field, std::to_string(v), expected);
  };
  if (c.patch < 3 || c.patch % 2 == 0) bad("patch", c.patch, "an odd integer >= 3");
  if (!(c.max_patch_residual_m2 > 0.0))
    bad("max_patch_residual_m2", c.max_patch_residual_m2, "> 0");
  if (!(c.alpha1 > -1.0 && c.alpha1 < 1.0)) bad("alpha1", c.alpha1, "in (-1, 1)");
  if (!(c.alpha2 > 0.0 && c.alpha2 <= 1.0)) bad("alpha2", c.alpha2, "in (0, 1]");
  if (!(c.max_merge_residual_m2 >= 0.0))
    bad("max_merge_residual_m2", c.max_merge_residual_m2, ">= 0");
  if (c.min_region_cells < 1) bad("min_region_cells", c.min_region_cells, ">= 1");
  if (!(c.max_neighbour_gap_m > 0.0)) bad("max_neighbour_gap_m", c.max_neighbour_gap_m, "> 0");
}

/// Union-find over region labels.
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
  /// Joins the sets of a and b; returns the root kept.
  int Union(int a, int b) {
    a = Find(a);
    b = Find(b);
    if (a != b) parent_[b] = a;
    return a;
  }

 private:
  std::vector<int> parent_;
};

/// A binary min-heap of costs keyed by id (0 <= id < n), at most one per id, whose cost can be
/// changed in place; ties go to the lower id.
class IndexedHeap {
 public:
  explicit IndexedHeap(int n) : pos_(n, -1) {}
  bool empty() const { return nodes_.empty(); }
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

/// Whether cells i and j are both valid and their 3-D points closer than the gap.
bool Connected(const scan::RangeCell& a, const scan::RangeCell& b, double gap) {
  return a.valid && b.valid && (a.p_W - b.p_W).squaredNorm() < gap * gap;
}

/// Region merging by boundary-cost minimisation (SegmentPlanes' step 4): repeatedly merges the
/// adjacent pair of regions whose merged plane fit has the smallest residual, until that exceeds
/// max_cost. label: the region of each cell (-1: none); regions are adjacent where two of their
/// cells are 4-neighbours with near(i, j). moments: per region; the merged regions' sums on return.
/// Returns, per region, the region it was merged into (itself for the regions left), which is
/// the merged regions' lowest index.
///
/// First, adjacent regions of at most three cells together are merged in raster order of their
/// cells: such a merge costs exactly 0, i.e. is a cheapest one. Then each region keeps its
/// neighbours with the cost of merging with each (recomputed whenever either changes) and its
/// cheapest merge, which an indexed heap orders. Ties go to the lower region index.
template <typename Near>
std::vector<int> MergeRegions(const std::vector<int>& label, const Near& near, int rows, int cols,
                              double max_cost, std::vector<Moments>* moments) {
  const int n_regions = static_cast<int>(moments->size());
  // Neighbouring cells of different regions (right and down), as region pairs.
  std::vector<std::pair<int, int>> pairs;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const int i = r * cols + c;
      if (label[i] < 0) continue;
      for (int j : {c + 1 < cols ? i + 1 : -1, r + 1 < rows ? i + cols : -1}) {
        if (j < 0 || label[j] < 0 || label[j] == label[i]) continue;
        if (near(i, j)) pairs.emplace_back(label[i], label[j]);
      }
    }
  }

  // Free merges. into[k]: the region k was merged into, k while it is not.
  std::vector<int> into(n_regions);
  std::iota(into.begin(), into.end(), 0);
  auto root = [&](int k) {
    while (into[k] != k) k = into[k] = into[into[k]];
    return k;
  };
  for (auto& [a, b] : pairs) {
    a = root(a);
    b = root(b);
    if (a == b || (*moments)[a].n() + (*moments)[b].n() > 3.0) continue;
    if (a > b) std::swap(a, b);
    (*moments)[a].Add((*moments)[b]);
    into[b] = a;
  }

  // The regions left, renumbered densely in the same order, with the data that one merge
  // touches together.
  struct alignas(64) Region {
    Moments m;
    double residual = 0.0;                                       // of its own plane fit
    double best_cost = std::numeric_limits<double>::infinity();  // its cheapest merge ...
    int best_to = -1;                                            // ... with this region
    int mark = -1;                                               // scratch
    int begin = 0, size = 0, capacity = 0;  // its neighbour list: edges[begin, begin + size)
    int original = 0;                       // its index in `moments`
    int into = -1;                          // the region it was merged into; -1 while alive
  };
  struct Edge {
    int to;       // the neighbouring region
    double cost;  // residual of the two merged
  };
  std::vector<int> dense(n_regions, -1);
  int n = 0;
  for (int k = 0; k < n_regions; ++k) {
    if (into[k] == k) dense[k] = n++;
  }
  std::vector<Region> region(n);
  for (int k = 0; k < n_regions; ++k) {
    if (dense[k] < 0) continue;
    Region& r = region[dense[k]];
    r.m = (*moments)[k];
    r.original = k;
    r.residual = Residual(r.m);
  }

  // Each region's distinct neighbours (CSR, then deduplicated) with the merge costs.
  // `scaled_bound`: a lower bound of the cost times the pair's points, if known.
  auto merge_cost = [&](const Region& a, const Region& b, double scaled_bound) {
    Moments m = a.m;
    m.Add(b.m);
    if (m.n() <= 3.0) return 0.0;
    // The merged residual is at least the mean of the two (the smallest eigenvalue is concave).
    const double w = 1.0 / m.n();
    const double start = w * std::max(scaled_bound, a.m.n() * a.residual + b.m.n() * b.residual);
    return SmallestEigenvalue(Covariance(m.v.data(), w), start);
  };
  std::vector<Edge> edges;
  {
    std::vector<int> start(n + 1, 0);
    for (auto& [a, b] : pairs) {
      a = dense[root(a)];
      b = dense[root(b)];
      if (a != b) ++start[a + 1], ++start[b + 1];
    }
    for (int k = 0; k < n; ++k) start[k + 1] += start[k];
    std::vector<int> fill(start.begin(), start.end() - 1), nb(start[n]);
    for (const auto& [a, b] : pairs) {
      if (a != b) nb[fill[a]++] = b, nb[fill[b]++] = a;
    }
    std::vector<std::pair<int, int>>().swap(pairs);
    int total = 0;
    for (int a = 0; a < n; ++a) {
      region[a].begin = total;
      for (int e = start[a]; e < start[a + 1]; ++e) {
        if (region[nb[e]].mark != a) region[nb[e]].mark = a, ++total;
      }
      region[a].capacity = total - region[a].begin;
    }
    edges.resize(total);
    for (Region& r : region) r.mark = -1;
    for (int a = 0; a < n; ++a) {
      Region& ra = region[a];
      for (int e = start[a]; e < start[a + 1]; ++e) {
        const int b = nb[e];
        Region& rb = region[b];
        if (b < a || rb.mark == a) continue;  // each pair once, from its lower region
        rb.mark = a;
        const double cost = merge_cost(ra, rb, 0.0);
        edges[ra.begin + ra.size++] = {b, cost};
        edges[rb.begin + rb.size++] = {a, cost};
      }
    }
  }

  IndexedHeap queue(n);  // each region's cheapest merge, if at most max_cost
  // Keys region a by its cheapest merge.
  auto set_key = [&](int a) {
    if (region[a].best_cost <= max_cost) {
      queue.Set(a, region[a].best_cost);
    } else {
      queue.Remove(a);
    }
  };
  // Sets a's cheapest merge from its list (ties: the lower neighbour).
  auto update_best = [&](int a) {
    Region& ra = region[a];
    ra.best_cost = std::numeric_limits<double>::infinity();
    ra.best_to = -1;
    for (int e = ra.begin; e < ra.begin + ra.size; ++e) {
      const Edge& x = edges[e];
      if (x.cost < ra.best_cost || (x.cost == ra.best_cost && x.to < ra.best_to)) {
        ra.best_cost = x.cost;
        ra.best_to = x.to;
      }
    }
    set_key(a);
  };
  for (int a = 0; a < n; ++a) update_best(a);
  std::vector<Edge> joined;
  int step = n;  // marks: above the region indices used while building the lists
  while (!queue.empty()) {
    const int t = queue.top();
    const int a = std::min(t, region[t].best_to), b = std::max(t, region[t].best_to);
    Region& ra = region[a];
    Region& rb = region[b];
    const double n_a = ra.m.n(), n_b = rb.m.n();
    ra.residual = region[t].best_cost;
    ra.m.Add(rb.m);
    rb.into = a;
    queue.Remove(b);
    // a's neighbours: those of a and b, each once, with new costs; their lists follow. A pair's
    // covariance is at least (old points / new points) times that of the pair before, so the old
    // costs give lower bounds of the new ones (kept times the new points, in j.cost, at first).
    ++step;
    ra.mark = rb.mark = step;
    joined.clear();
    for (const Region* x : {&ra, &rb}) {
      const double n_x = x == &ra ? n_a : n_b;
      for (int e = x->begin; e < x->begin + x->size; ++e) {
        Region& rc = region[edges[e].to];
        const double n_c = rc.m.n();
        const double bound = edges[e].cost * (n_x + n_c);
        if (rc.mark == step) {  // a neighbour of both
          for (Edge& j : joined) {
            if (j.to == edges[e].to) j.cost = std::max(j.cost, bound);
          }
          continue;
        }
        rc.mark = step;
        joined.push_back({edges[e].to, bound});
      }
    }
    for (Edge& j : joined) {
      const int c = j.to;
      Region& rc = region[c];
      j.cost = merge_cost(ra, rc, j.cost);
      // c's edges to a and b become one edge to a; its cheapest merge follows.
      bool found = false;
      for (int e = rc.begin; e < rc.begin + rc.size;) {
        if (edges[e].to != a && edges[e].to != b) {
          ++e;
        } else if (!found) {
          edges[e++] = {a, j.cost};
          found = true;
        } else {
          edges[e] = edges[rc.begin + --rc.size];
        }
      }
      if (rc.best_to == a || rc.best_to == b) {
        update_best(c);
      } else if (j.cost < rc.best_cost || (j.cost == rc.best_cost && a < rc.best_to)) {
        rc.best_cost = j.cost;
        rc.best_to = a;
        set_key(c);
      }
    }
    if (static_cast<int>(joined.size()) > ra.capacity) {
      ra.begin = static_cast<int>(edges.size());
      ra.capacity = 2 * static_cast<int>(joined.size());
      edges.resize(edges.size() + ra.capacity);
    }
    std::copy(joined.begin(), joined.end(), edges.begin() + ra.begin);
    ra.size = static_cast<int>(joined.size());
    rb.size = 0;
    update_best(a);
  }

  for (int k = n - 1; k >= 0; --k) {  // survivors have lower indices than what they took in
    const Region& r = region[k];
    if (r.into < 0) {
      (*moments)[r.original] = r.m;
    } else {
      into[r.original] = region[r.into].original;
    }
  }
  for (int k = 0; k < n_regions; ++k) into[k] = root(k);
  return into;
}

/// Unit normals of the plane fits to each cell's patch x patch window (clipped at the image
/// border; invalid cells skipped) whose residual is at most max_residual_m2; has_normal marks
/// them. The windows' moment sums come from a separable box filter, O(1) per cell: running sums
/// down the columns (over a ring of rows), then running sums along each row.
void PatchNormals(const std::vector<Eigen::Vector3d>& p, const std::vector<char>& valid, int rows,
                  int cols, int patch, double max_residual_m2, std::vector<Eigen::Vector3d>* normal,
                  std::vector<Eigen::Vector3d>* mean, std::vector<char>* has_normal) {
  constexpr int kCh = 10;  // channels of Moments::v
  const int half = patch / 2;
  const int min_points = std::max(3, (patch * patch + 1) / 2);
  // Rows of cells' moments (kCh values per cell), with `half` empty cells on either side.
  const int width = (cols + 2 * half) * kCh;
  const int ring_rows = patch + 1;  // the window's rows and the one that just left it
  std::vector<double> ring(static_cast<size_t>(ring_rows) * width, 0.0);
  std::vector<double> column(width, 0.0);  // per cell: sums over the window's rows
  auto ring_row = [&](int r) { return &ring[static_cast<size_t>(r % ring_rows) * width]; };
  // Adds row r (sign +1) to the column sums, or removes it (-1); fills its ring row first.
  auto add_row = [&](int r, double sign) {
    double* __restrict row = ring_row(r);
    if (sign > 0.0) {
      for (int c = 0; c < cols; ++c) {
        const int i = r * cols + c;
        Moments m;
        if (valid[i]) m.Add(p[i]);
        std::copy(m.v.begin(), m.v.end(), row + (c + half) * kCh);
      }
    }
    double* __restrict sum = column.data();
    for (int k = 0; k < width; ++k) sum[k] += sign * row[k];
  };
  for (int r = 0; r < std::min(half, rows); ++r) add_row(r, 1.0);
  for (int r = 0; r < rows; ++r) {
    if (r + half < rows) add_row(r + half, 1.0);
    if (r - half - 1 >= 0) add_row(r - half - 1, -1.0);
    double win[kCh] = {};  // sums over the window of cell (r, c)
    for (int k = 0; k < patch - 1; ++k) {
      for (int ch = 0; ch < kCh; ++ch) win[ch] += column[k * kCh + ch];
    }
    for (int c = 0; c < cols; ++c) {
      const double* enter = &column[(c + patch - 1) * kCh];
      for (int ch = 0; ch < kCh; ++ch) win[ch] += enter[ch];
      if (c > 0) {
        const double* leave = &column[(c - 1) * kCh];
        for (int ch = 0; ch < kCh; ++ch) win[ch] -= leave[ch];
      }
      const int i = r * cols + c;
      if (!valid[i] || win[0] < min_points) continue;
      const Sym3 cov = Covariance(win, 1.0 / win[0]);
      const double residual = SmallestEigenvalue(cov, 0.0, max_residual_m2);
      if (residual > max_residual_m2) continue;
      (*normal)[i] = SmallestEigenvector(cov, residual);
      (*mean)[i] = Eigen::Vector3d(win[1], win[2], win[3]) / win[0];
      (*has_normal)[i] = 1;
    }
  }
}

}  // namespace

SegmentResult SegmentPlanes(const scan::RangeImage& range, const SegmentConfig& config) {
  CheckConfig(config);
  const int rows = range.rows(), cols = range.cols(), n_cells = rows * cols;
  SegmentResult result;
  result.rows = rows;
  result.cols = cols;
  result.labels.assign(n_cells, -1);
  if (n_cells == 0) return result;
  const scan::RangeCell* const cells = &range.at(0, 0);  // row-major, contiguous

  // Reference point for all moment sums (the first valid point).
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  for (int i = 0; i < n_cells; ++i) {
    if (cells[i].valid) {
      origin = cells[i].p_W;
      break;
    }
  }
  std::vector<Eigen::Vector3d> p(n_cells, Eigen::Vector3d::Zero());
  std::vector<char> valid(n_cells, 0);
  for (int i = 0; i < n_cells; ++i) {
    if (!cells[i].valid) continue;
    valid[i] = 1;
    p[i] = cells[i].p_W - origin;
  }
  // Whether cells i and j are both valid and their points closer than max_neighbour_gap_m.
  const double gap2 = config.max_neighbour_gap_m * config.max_neighbour_gap_m;
  auto near = [&](int i, int j) {
    return valid[i] && valid[j] && (p[i] - p[j]).squaredNorm() < gap2;
  };

  // 1. Patch normals (unoriented: every use below is insensitive to their sign).
  std::vector<Eigen::Vector3d> normal(n_cells, Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> mean(n_cells, Eigen::Vector3d::Zero());
  std::vector<char> has_normal(n_cells, 0);
  PatchNormals(p, valid, rows, cols, config.patch, config.max_patch_residual_m2, &normal, &mean,
               &has_normal);

  // 2. Initial segmentation: sequential binary connectivity (raster scan + union-find).
  const double alpha2_sq = config.alpha2 * config.alpha2;
  auto coplanar = [&](int i, int j) {
    if (!has_normal[i] || !has_normal[j]) return false;
    if (!near(i, j)) return false;
    const Eigen::Vector3d& n1 = normal[i];
    const Eigen::Vector3d& n2 = normal[j];
    // Compare the normals up to sign.
    if (std::abs(n1.dot(n2)) <= config.alpha1) return false;
    // max(|r12 . n1|, |r12 . n2|) < alpha2 for the unit r12 = d / |d|, squared; m1, m2 are the
    // patches' means (the paper's m_i: the points the patch planes pass through).
    const Eigen::Vector3d d = mean[i] - mean[j];
    const double d_sq = d.squaredNorm();
    if (d_sq == 0.0) return true;
    const double d1 = d.dot(n1), d2 = d.dot(n2);
    return std::max(d1 * d1, d2 * d2) < alpha2_sq * d_sq;
  };
  std::vector<int> label(n_cells, -1);
  int n_labels = 0;
  UnionFind uf(n_cells);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const int i = r * cols + c;
      if (!has_normal[i]) continue;
      const int up = r > 0 && coplanar(i, i - cols) ? label[i - cols] : -1;
      const int left = c > 0 && coplanar(i, i - 1) ? label[i - 1] : -1;
      if (up < 0 && left < 0) {
        label[i] = n_labels++;
      } else if (up >= 0 && left >= 0) {
        label[i] = uf.Union(up, left);
      } else {
        label[i] = std::max(up, left);
      }
    }
  }
  // Compact the roots to 0..n_regions-1 (in raster order of their first cell).
  std::vector<int> compact(n_labels, -1);
  int n_regions = 0;
  for (int i = 0; i < n_cells; ++i) {
    if (label[i] < 0) continue;
    const int root = uf.Find(label[i]);
    if (compact[root] < 0) compact[root] = n_regions++;
    label[i] = compact[root];
  }
  std::vector<Moments> moments(n_regions);
  for (int i = 0; i < n_cells; ++i) {
    if (label[i] >= 0) moments[label[i]].Add(p[i]);
  }

  // 3. Cells without a valid normal join the neighbouring region whose plane they satisfy,
  // best first: of all (cell, neighbouring region) pairs, the one whose plane the cell lies
  // nearest is taken next, and the cell's own neighbours become candidates. At a crease, the
  // band of cells without normals then goes to the planes the cells lie on, not to whichever
  // region reaches them first. A region of fewer than patch^2 cells has no reliable plane of its
  // own; the neighbouring cell's patch plane (its normal through its point) is used.
  {
    const double max_dist = 3.0 * std::sqrt(config.max_patch_residual_m2);
    std::vector<Eigen::Vector3d> region_normal(n_regions, Eigen::Vector3d::UnitZ());
    std::vector<Eigen::Vector3d> region_mean(n_regions, Eigen::Vector3d::Zero());
    std::vector<char> region_plane(n_regions, 0);
    for (int k = 0; k < n_regions; ++k) {
      if (moments[k].n() >= config.patch * config.patch) {
        double residual;
        FitPlane(moments[k], &region_normal[k], &residual);
        region_mean[k] = moments[k].Mean();
        region_plane[k] = 1;
      }
    }
    // Distance of cell i to the plane of region label[j], reached from its neighbour j.
    auto distance = [&](int i, int j) {
      const int k = label[j];
      if (region_plane[k]) return std::abs(region_normal[k].dot(p[i] - region_mean[k]));
      if (has_normal[j]) return std::abs(normal[j].dot(p[i] - p[j]));
      return (p[i] - p[j]).norm();
    };
    struct Claim {
      double dist;
      int cell, from;  // the cell, and its labelled neighbour
      bool operator>(const Claim& o) const {
        if (dist != o.dist) return dist > o.dist;
        return cell != o.cell ? cell > o.cell : from > o.from;
      }
    };
    std::priority_queue<Claim, std::vector<Claim>, std::greater<Claim>> claims;
    auto claim_neighbours = [&](int j) {  // j: a labelled cell
      const int r = j / cols, c = j % cols;
      for (const int i : {r > 0 ? j - cols : -1, r + 1 < rows ? j + cols : -1, c > 0 ? j - 1 : -1,
                          c + 1 < cols ? j + 1 : -1}) {
        if (i < 0 || !valid[i] || label[i] >= 0 || !near(i, j)) continue;
        const double d = distance(i, j);
        if (d < max_dist) claims.push({d, i, j});
      }
    };
    for (int j = 0; j < n_cells; ++j) {
      if (label[j] >= 0) claim_neighbours(j);
    }
    while (!claims.empty()) {
      const Claim top = claims.top();
      claims.pop();
      if (label[top.cell] >= 0) continue;  // taken by a nearer plane
      label[top.cell] = label[top.from];
      moments[label[top.cell]].Add(p[top.cell]);
      claim_neighbours(top.cell);
    }
  }

  // 4. Region merging.
  const std::vector<int> merged_into =
      MergeRegions(label, near, rows, cols, config.max_merge_residual_m2, &moments);

  // 4b. Boundary refinement: a cell next to another region whose plane it lies nearer moves
  // there. Patches that straddle a crease can pass the connectivity tests with the face across
  // it; a box side then holds a line of table (or top) cells along its bottom (top) edge.
  for (int i = 0; i < n_cells; ++i) {
    if (label[i] >= 0) label[i] = merged_into[label[i]];
  }
  for (int pass = 0; pass < config.refine_passes; ++pass) {
    std::vector<Eigen::Vector3d> plane_normal(n_regions, Eigen::Vector3d::Zero());
    std::vector<Eigen::Vector3d> plane_mean(n_regions, Eigen::Vector3d::Zero());
    for (int k = 0; k < n_regions; ++k) {
      if (merged_into[k] != k || moments[k].n() < config.min_region_cells) continue;
      double residual;
      FitPlane(moments[k], &plane_normal[k], &residual);
      plane_mean[k] = moments[k].Mean();
    }
    auto dist = [&](int i, int k) { return std::abs(plane_normal[k].dot(p[i] - plane_mean[k])); };
    std::vector<std::pair<int, int>> moves;
    for (int i = 0; i < n_cells; ++i) {
      const int k = label[i];
      if (k < 0 || plane_normal[k].isZero()) continue;
      const int r = i / cols, c = i % cols;
      double best = dist(i, k);
      int best_k = k;
      for (const int j : {r > 0 ? i - cols : -1, r + 1 < rows ? i + cols : -1, c > 0 ? i - 1 : -1,
                          c + 1 < cols ? i + 1 : -1}) {
        if (j < 0 || label[j] < 0 || label[j] == k || !near(i, j)) continue;
        const int other = label[j];
        if (plane_normal[other].isZero()) continue;
        const double d = dist(i, other);
        if (d < best) best = d, best_k = other;
      }
      if (best_k != k) moves.emplace_back(i, best_k);
    }
    if (moves.empty()) break;
    for (const auto& [i, k] : moves) {
      moments[label[i]].Remove(p[i]);
      moments[k].Add(p[i]);
      label[i] = k;
    }
  }

  // 5. Final labels and regions; small regions dropped.
  std::vector<int> final_id(n_regions, -1);
  for (int k = 0; k < n_regions; ++k) {
    if (merged_into[k] != k || moments[k].n() < config.min_region_cells) continue;
    final_id[k] = static_cast<int>(result.regions.size());
    PlaneRegion region;
    region.id = final_id[k];
    region.cells = static_cast<int>(moments[k].n());
    region.centroid_W = moments[k].Mean() + origin;
    FitPlane(moments[k], &region.normal_W, &region.residual_m2);
    result.regions.push_back(region);
  }
  for (int i = 0; i < n_cells; ++i) {
    if (label[i] >= 0) result.labels[i] = final_id[label[i]];
  }
  return result;
}

Grouping GroupObjects(const SegmentResult& s, const scan::RangeImage& range,
                      const SegmentConfig& config) {
  CheckConfig(config);
  HGRASP_DEMAND(s.rows == range.rows() && s.cols == range.cols());
  HGRASP_DEMAND(static_cast<int>(s.labels.size()) == s.rows * s.cols);
  Grouping grouping;
  const int n = static_cast<int>(s.regions.size());
  int max_id = -1;
  for (const PlaneRegion& r : s.regions) max_id = std::max(max_id, r.id);
  std::vector<int> index_of(max_id + 1, -1);  // region id -> index in s.regions
  for (int k = 0; k < n; ++k) {
    HGRASP_DEMAND(s.regions[k].id >= 0 && index_of[s.regions[k].id] < 0);
    index_of[s.regions[k].id] = k;
  }
  std::vector<char> removed(n, 0);

  constexpr double kFloorNz = 0.95, kFloorClearance = 0.005;
  constexpr double kWallNz = 0.1, kWallClearance = 0.02;
  // A floor lies below all other planes, and a wall behind them, the removed ones included.
  std::vector<double> floor_z, wall_x;
  for (bool found = true; found;) {
    found = false;
    // Floor: the lowest remaining region, horizontal, all others well above.
    int lowest = -1;
    for (int k = 0; k < n; ++k) {
      if (!removed[k] &&
          (lowest < 0 || s.regions[k].centroid_W.z() < s.regions[lowest].centroid_W.z())) {
        lowest = k;
      }
    }
    if (lowest >= 0 && std::abs(s.regions[lowest].normal_W.z()) > kFloorNz) {
      // Horizontal regions at its height are pieces of the same plane (a line of missing cells
      // can split the table): removed with it.
      const double z0 = s.regions[lowest].centroid_W.z();
      auto same_plane = [&](int k) {
        return std::abs(s.regions[k].normal_W.z()) > kFloorNz &&
               s.regions[k].centroid_W.z() < z0 + kFloorClearance;
      };
      bool below_all = true;
      for (int k = 0; k < n; ++k) {
        if (k != lowest && !removed[k] && !same_plane(k) &&
            s.regions[k].centroid_W.z() < z0 + kFloorClearance) {
          below_all = false;
        }
      }
      for (const double z : floor_z) {
        if (s.regions[lowest].centroid_W.z() > z + kFloorClearance) below_all = false;
      }
      if (below_all) {
        floor_z.push_back(z0);
        for (int k = 0; k < n; ++k) {
          if (!removed[k] && (k == lowest || same_plane(k))) {
            removed[k] = 1;
            grouping.floor_or_wall.push_back(s.regions[k].id);
          }
        }
        found = true;
        continue;
      }
    }
    // Wall: the farthest remaining region in x, vertical, all others well nearer.
    int farthest = -1;
    for (int k = 0; k < n; ++k) {
      if (!removed[k] &&
          (farthest < 0 || s.regions[k].centroid_W.x() > s.regions[farthest].centroid_W.x())) {
        farthest = k;
      }
    }
    if (farthest >= 0 && std::abs(s.regions[farthest].normal_W.z()) < kWallNz) {
      bool behind_all = true;
      for (int k = 0; k < n; ++k) {
        if (k != farthest && !removed[k] &&
            s.regions[k].centroid_W.x() > s.regions[farthest].centroid_W.x() - kWallClearance) {
          behind_all = false;
        }
      }
      for (const double x : wall_x) {
        if (s.regions[farthest].centroid_W.x() < x - kWallClearance) behind_all = false;
      }
      if (behind_all) {
        removed[farthest] = 1;
        wall_x.push_back(s.regions[farthest].centroid_W.x());
        grouping.floor_or_wall.push_back(s.regions[farthest].id);
        found = true;
      }
    }
  }

  // Connected groups of the remaining regions.
  UnionFind uf(std::max(n, 1));
  const int rows = s.rows, cols = s.cols;
  auto region_at = [&](int i) {
    const int id = s.labels[i];
    if (id < 0 || id > max_id) return -1;
    const int k = index_of[id];
    return k >= 0 && !removed[k] ? k : -1;
  };
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const int i = r * cols + c;
      const int a = region_at(i);
      if (a < 0) continue;
      // Cells ahead of this one within the reach (each unordered pair looked at once).
      const int reach = config.group_reach_cells;
      for (int dr = 0; dr <= reach && r + dr < rows; ++dr) {
        for (int dc = dr == 0 ? 1 : -reach; dc <= reach; ++dc) {
          if (c + dc < 0 || c + dc >= cols) continue;
          const int b = region_at(i + dr * cols + dc);
          if (b < 0 || b == a || uf.Find(a) == uf.Find(b)) continue;
          if (Connected(range.at(r, c), range.at(r + dr, c + dc), config.max_group_gap_m)) {
            uf.Union(a, b);
          }
        }
      }
    }
  }
  std::vector<int> group_of(n, -1);
  for (int k = 0; k < n; ++k) {
    if (removed[k]) continue;
    const int root = uf.Find(k);
    if (group_of[root] < 0) {
      group_of[root] = static_cast<int>(grouping.objects.size());
      grouping.objects.emplace_back();
    }
    grouping.objects[group_of[root]].push_back(s.regions[k].id);
  }
  for (auto& object : grouping.objects) std::sort(object.begin(), object.end());
  return grouping;
}

}  // namespace hgrasp::segment
