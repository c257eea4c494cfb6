#include "segment/refine.h"

#include <cmath>
#include <utility>

namespace hgrasp::segment {
namespace {

/// Whether region k takes part in refinement and is kept at the end.
bool Kept(const std::vector<int>& merged_into, const std::vector<Moments>& moments, int k,
          int min_region_cells) {
  return merged_into[k] == k && moments[k].n() >= min_region_cells;
}

/// The moves of one refinement pass: (cell, region it moves to).
std::vector<std::pair<int, int>> RefineMoves(const CellGrid& grid,
                                             const std::vector<int>& merged_into,
                                             int min_region_cells, const std::vector<int>& label,
                                             const std::vector<Moments>& moments) {
  const int n_regions = static_cast<int>(moments.size());
  const std::vector<Eigen::Vector3d>& p = grid.p;
  // Plane normals, zero for the regions that do not take part.
  std::vector<Eigen::Vector3d> plane_normal(n_regions, Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> plane_mean(n_regions, Eigen::Vector3d::Zero());
  for (int k = 0; k < n_regions; ++k) {
    if (!Kept(merged_into, moments, k, min_region_cells)) continue;
    double residual;
    FitPlane(moments[k], &plane_normal[k], &residual);
    plane_mean[k] = moments[k].Mean();
  }
  auto dist = [&](int i, int k) { return std::abs(plane_normal[k].dot(p[i] - plane_mean[k])); };
  std::vector<std::pair<int, int>> moves;
  for (int i = 0; i < grid.size(); ++i) {
    const int k = label[i];
    if (k < 0 || plane_normal[k].isZero()) continue;
    double best = dist(i, k);
    int best_k = k;
    ForEachNeighbour(grid, i, [&](int j) {
      if (label[j] < 0 || label[j] == k || !grid.Near(i, j)) return;
      const int other = label[j];
      if (plane_normal[other].isZero()) return;
      const double d = dist(i, other);
      if (d < best) best = d, best_k = other;
    });
    if (best_k != k) moves.emplace_back(i, best_k);
  }
  return moves;
}

}  // namespace

void RefineBoundaries(const CellGrid& grid, const std::vector<int>& merged_into, int passes,
                      int min_region_cells, std::vector<int>* label,
                      std::vector<Moments>* moments) {
  for (int pass = 0; pass < passes; ++pass) {
    const std::vector<std::pair<int, int>> moves =
        RefineMoves(grid, merged_into, min_region_cells, *label, *moments);
    if (moves.empty()) break;
    for (const auto& [i, k] : moves) {
      (*moments)[(*label)[i]].Remove(grid.p[i]);
      (*moments)[k].Add(grid.p[i]);
      (*label)[i] = k;
    }
  }
}

void CollectRegions(const CellGrid& grid, const std::vector<int>& label,
                    const std::vector<int>& merged_into, const std::vector<Moments>& moments,
                    int min_region_cells, SegmentResult* result) {
  const int n_regions = static_cast<int>(moments.size());
  std::vector<int> final_id(n_regions, -1);
  for (int k = 0; k < n_regions; ++k) {
    if (!Kept(merged_into, moments, k, min_region_cells)) continue;
    final_id[k] = static_cast<int>(result->regions.size());
    PlaneRegion region;
    region.id = final_id[k];
    region.cells = static_cast<int>(moments[k].n());
    region.centroid_W = moments[k].Mean() + grid.origin_W;
    FitPlane(moments[k], &region.normal_W, &region.residual_m2);
    result->regions.push_back(region);
  }
  for (int i = 0; i < grid.size(); ++i) {
    if (label[i] >= 0) result->labels[i] = final_id[label[i]];
  }
}

}  // namespace hgrasp::segment
