// Step 4 of the segmentation: MergeRegions against a reference merge by brute force on small
// seeded random label images (the same free merges, then a greedy that recomputes every adjacent
// pair's merged residual from the cells' points at each step), and a hand-worked 2 x 2 case.

#include "segment/merge_regions.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <tuple>
#include <vector>

namespace hgrasp::segment {
namespace {

using Eigen::Vector3d;

constexpr double kStep = 0.005;  // grid spacing (m)
constexpr double kInf = std::numeric_limits<double>::infinity();

std::vector<Moments> MomentsOf(const CellGrid& g, const std::vector<int>& label, int n) {
  std::vector<Moments> m(n);
  for (int i = 0; i < g.size(); ++i) {
    if (label[i] >= 0) m[label[i]].Add(g.p[i]);
  }
  return m;
}

// The reference, after MergeRegions' contract: owner[k] is the region that region k's cells
// belong to now, the lowest index of those merged.
class BruteForce {
 public:
  BruteForce(const CellGrid& g, const std::vector<int>& label, int n)
      : g_(g), label_(label), owner_(n) {
    std::iota(owner_.begin(), owner_.end(), 0);
  }

  std::vector<int> Run(double max_cost) {
    // Free merges: the neighbouring cells' pairs (right, then down) in raster order; their
    // current regions merge when they hold at most three cells together.
    for (const auto& [i, j] : CellPairs()) {
      const int a = owner_[label_[i]], b = owner_[label_[j]];
      if (a != b && Sum(a).n() + Sum(b).n() <= 3.0) Join(a, b);
    }
    // Greedy: the cheapest adjacent pair (ties: the lower first region, then the lower second).
    for (;;) {
      std::tuple<double, int, int> best(kInf, -1, -1);
      for (const auto& [i, j] : CellPairs()) {
        const int a = owner_[label_[i]], b = owner_[label_[j]];
        if (a == b) continue;
        Moments m = Sum(std::min(a, b));
        m.Add(Sum(std::max(a, b)));
        best = std::min(best, std::make_tuple(Residual(m), std::min(a, b), std::max(a, b)));
      }
      if (!(std::get<0>(best) <= max_cost)) break;
      Join(std::get<1>(best), std::get<2>(best));
    }
    return owner_;
  }

  // The moment sums of the cells now in region k, from scratch.
  Moments Sum(int k) const {
    Moments m;
    for (int i = 0; i < g_.size(); ++i) {
      if (label_[i] >= 0 && owner_[label_[i]] == k) m.Add(g_.p[i]);
    }
    return m;
  }

 private:
  std::vector<std::pair<int, int>> CellPairs() const {
    std::vector<std::pair<int, int>> pairs;
    for (int i = 0; i < g_.size(); ++i) {
      const int r = i / g_.cols, c = i % g_.cols;
      for (const int j : {c + 1 < g_.cols ? i + 1 : -1, r + 1 < g_.rows ? i + g_.cols : -1}) {
        if (j < 0 || label_[i] < 0 || label_[j] < 0 || label_[i] == label_[j]) continue;
        if (g_.Near(i, j)) pairs.emplace_back(i, j);
      }
    }
    return pairs;
  }
  void Join(int a, int b) {
    const int lo = std::min(a, b), hi = std::max(a, b);
    for (int& o : owner_) {
      if (o == hi) o = lo;
    }
  }

  const CellGrid& g_;
  const std::vector<int>& label_;
  std::vector<int> owner_;
};

struct Case {
  CellGrid grid;
  std::vector<int> label;
  int n_regions = 0;
};

// A small grid over two noisy tilted planes meeting at a random column, with a few invalid cells
// and a few cells lifted 3 cm (no neighbours), cut into regions grown from random seeds;
// the regions are numbered in random order.
Case RandomCase(std::mt19937* rng) {
  std::uniform_int_distribution<int> rows_d(2, 6), cols_d(2, 8);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Case k;
  CellGrid& g = k.grid;
  g.rows = rows_d(*rng);
  g.cols = cols_d(*rng);
  g.max_gap_sq = 0.01 * 0.01;
  const int n = g.size(), crease = std::uniform_int_distribution<int>(0, g.cols)(*rng);
  std::normal_distribution<double> noise(0.0, u(*rng) < 0.5 ? 2e-4 : 1e-3);
  for (int i = 0; i < n; ++i) {
    const int r = i / g.cols, c = i % g.cols;
    const double z =
        c < crease ? 0.2 * c * kStep : 0.2 * crease * kStep + 0.8 * (c - crease) * kStep;
    const double lift = u(*rng) < 0.05 ? 0.03 : 0.0;
    g.p.push_back(Vector3d(c * kStep, r * kStep, z + lift + noise(*rng)));
    g.valid.push_back(u(*rng) < 0.9);
    if (!g.valid.back()) g.p.back().setZero();
  }
  // Regions grown from seeds over valid 4-neighbours, one random step at a time.
  k.label.assign(n, -1);
  const int seeds = std::uniform_int_distribution<int>(1, std::max(1, n / 2))(*rng);
  int next = 0;
  for (int s = 0; s < seeds; ++s) {
    const int i = std::uniform_int_distribution<int>(0, n - 1)(*rng);
    if (g.valid[i] && k.label[i] < 0) k.label[i] = next++;
  }
  for (bool grew = true; grew;) {
    grew = false;
    std::vector<int> order(n);
    std::iota(order.begin(), order.end(), 0);
    std::shuffle(order.begin(), order.end(), *rng);
    for (const int i : order) {
      if (!g.valid[i] || k.label[i] >= 0) continue;
      ForEachNeighbour(g, i, [&](int j) {
        if (k.label[i] < 0 && k.label[j] >= 0 && u(*rng) < 0.5)
          k.label[i] = k.label[j], grew = true;
      });
    }
  }
  for (int i = 0; i < n; ++i) {
    if (g.valid[i] && k.label[i] < 0) k.label[i] = next++;  // cut off from every seed
  }
  std::vector<int> perm(next);
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), *rng);
  for (int& l : k.label) {
    if (l >= 0) l = perm[l];
  }
  k.n_regions = next;
  return k;
}

TEST(MergeRegions, MatchesBruteForceGreedyOnRandomSmallImages) {
  std::mt19937 rng(37);
  const double max_costs[] = {0.0, 1e-8, 1e-7, 1e-6, 1e-5, 1.0};  // 1 m^2: no limit
  int merges = 0, cases = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const Case k = RandomCase(&rng);
    const double max_cost = max_costs[trial % 6];
    std::vector<Moments> moments = MomentsOf(k.grid, k.label, k.n_regions);
    const std::vector<int> into = MergeRegions(k.label, k.grid, max_cost, &moments);
    BruteForce reference(k.grid, k.label, k.n_regions);
    const std::vector<int> expected = reference.Run(max_cost);
    ASSERT_EQ(into, expected) << "trial " << trial << " max_cost " << max_cost;
    for (int r = 0; r < k.n_regions; ++r) {
      if (into[r] != r) {
        ++merges;
        continue;
      }
      const Moments m = reference.Sum(r);
      for (int c = 0; c < 10; ++c) {
        ASSERT_NEAR(moments[r].v[c], m.v[c], 1e-12 * (1.0 + std::abs(m.v[c]))) << trial;
      }
    }
    ++cases;
  }
  EXPECT_EQ(cases, 600);
  EXPECT_GT(merges, 1000);  // the cases do merge
}

TEST(MergeRegions, HandWorkedTwoByTwo) {
  // Four one-cell regions (5 mm grid), the last 1 mm up. Free merges in raster order: 0 + 1
  // (right of cell 0), then 0 + 2 (below cell 0: 3 cells together); 3 would make four. The four
  // points' residual is 6.1e-8 m^2 (h^2 / 16 for a small lift h, less a little).
  CellGrid g;
  g.rows = g.cols = 2;
  g.max_gap_sq = 0.01 * 0.01;
  g.p = {Vector3d(0, 0, 0), Vector3d(kStep, 0, 0), Vector3d(0, kStep, 0),
         Vector3d(kStep, kStep, 0.001)};
  g.valid.assign(4, 1);
  const std::vector<int> label = {0, 1, 2, 3};
  std::vector<Moments> m = MomentsOf(g, label, 4);
  EXPECT_EQ(MergeRegions(label, g, 6e-8, &m), (std::vector<int>{0, 0, 0, 3}));
  EXPECT_EQ(m[0].n(), 3.0);
  EXPECT_EQ(m[3].n(), 1.0);
  m = MomentsOf(g, label, 4);
  EXPECT_EQ(MergeRegions(label, g, 6.2e-8, &m), (std::vector<int>{0, 0, 0, 0}));
  EXPECT_EQ(m[0].n(), 4.0);
  // Cell 3 lifted beyond the gap: no neighbour, no merge at any cost.
  g.p[3].z() = 0.02;
  m = MomentsOf(g, label, 4);
  EXPECT_EQ(MergeRegions(label, g, 1.0, &m), (std::vector<int>{0, 0, 0, 3}));
}

}  // namespace
}  // namespace hgrasp::segment
