#include "segment/connectivity.h"

#include <algorithm>
#include <cmath>

#include "segment/union_find.h"

namespace hgrasp::segment {

bool Coplanar(const Eigen::Vector3d& n1, const Eigen::Vector3d& m1, const Eigen::Vector3d& n2,
              const Eigen::Vector3d& m2, double alpha1, double alpha2) {
  // Compare the normals up to sign.
  if (std::abs(n1.dot(n2)) <= alpha1) return false;
  // max(|r12 . n1|, |r12 . n2|) < alpha2 for the unit r12 = d / |d|, squared.
  const Eigen::Vector3d d = m1 - m2;
  const double d_sq = d.squaredNorm();
  if (d_sq == 0.0) return true;
  const double d1 = d.dot(n1), d2 = d.dot(n2);
  return std::max(d1 * d1, d2 * d2) < alpha2 * alpha2 * d_sq;
}

bool CellsConnect(const CellGrid& grid, const PatchPlanes& patches, int i, int j, double alpha1,
                  double alpha2) {
  if (!patches.has_normal[i] || !patches.has_normal[j]) return false;
  if (!grid.Near(i, j)) return false;
  return Coplanar(patches.normal[i], patches.mean[i], patches.normal[j], patches.mean[j], alpha1,
                  alpha2);
}

InitialRegions ConnectRegions(const CellGrid& grid, const PatchPlanes& patches, double alpha1,
                              double alpha2) {
  const int rows = grid.rows, cols = grid.cols, n_cells = grid.size();
  auto connect = [&](int i, int j) { return CellsConnect(grid, patches, i, j, alpha1, alpha2); };
  std::vector<int> label(n_cells, -1);
  int n_labels = 0;
  UnionFind uf(n_cells);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const int i = r * cols + c;
      if (!patches.has_normal[i]) continue;
      const int up = r > 0 && connect(i, i - cols) ? label[i - cols] : -1;
      const int left = c > 0 && connect(i, i - 1) ? label[i - 1] : -1;
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
  InitialRegions out;
  std::vector<int> compact(n_labels, -1);
  for (int i = 0; i < n_cells; ++i) {
    if (label[i] < 0) continue;
    const int root = uf.Find(label[i]);
    if (compact[root] < 0) compact[root] = out.n_regions++;
    label[i] = compact[root];
  }
  out.label = std::move(label);
  return out;
}

std::vector<Moments> RegionMoments(const CellGrid& grid, const std::vector<int>& label,
                                   int n_regions) {
  std::vector<Moments> moments(n_regions);
  for (int i = 0; i < grid.size(); ++i) {
    if (label[i] >= 0) moments[label[i]].Add(grid.p[i]);
  }
  return moments;
}

}  // namespace hgrasp::segment
