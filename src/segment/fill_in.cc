#include "segment/fill_in.h"

#include <cmath>
#include <functional>
#include <queue>

namespace hgrasp::segment {
namespace {

/// A labelled cell's claim on an unlabelled 4-neighbour, at the neighbour's distance to its plane.
struct Claim {
  double dist;
  int cell, from;  // the cell, and its labelled neighbour
  bool operator>(const Claim& o) const {
    if (dist != o.dist) return dist > o.dist;
    return cell != o.cell ? cell > o.cell : from > o.from;
  }
};

}  // namespace

// At a crease, the band of cells without normals goes to the planes the cells lie on, not to
// whichever region reaches them first. A region of fewer than patch^2 cells has no reliable plane
// of its own; the neighbouring cell's patch plane is used.
void FillUnlabelled(const CellGrid& grid, const PatchPlanes& patches, int min_plane_cells,
                    double max_dist, std::vector<int>* label_out, std::vector<Moments>* moments) {
  std::vector<int>& label = *label_out;
  const std::vector<Eigen::Vector3d>& p = grid.p;
  const int n_regions = static_cast<int>(moments->size());
  std::vector<Eigen::Vector3d> region_normal(n_regions, Eigen::Vector3d::UnitZ());
  std::vector<Eigen::Vector3d> region_mean(n_regions, Eigen::Vector3d::Zero());
  std::vector<char> region_plane(n_regions, 0);
  for (int k = 0; k < n_regions; ++k) {
    if ((*moments)[k].n() >= min_plane_cells) {
      double residual;
      FitPlane((*moments)[k], &region_normal[k], &residual);
      region_mean[k] = (*moments)[k].Mean();
      region_plane[k] = 1;
    }
  }
  // Distance of cell i to the plane of region label[j], reached from its neighbour j.
  auto distance = [&](int i, int j) {
    const int k = label[j];
    if (region_plane[k]) return std::abs(region_normal[k].dot(p[i] - region_mean[k]));
    if (patches.has_normal[j]) return std::abs(patches.normal[j].dot(p[i] - p[j]));
    return (p[i] - p[j]).norm();
  };
  std::priority_queue<Claim, std::vector<Claim>, std::greater<Claim>> claims;
  auto claim_neighbours = [&](int j) {  // j: a labelled cell
    ForEachNeighbour(grid, j, [&](int i) {
      if (!grid.valid[i] || label[i] >= 0 || !grid.Near(i, j)) return;
      const double d = distance(i, j);
      if (d < max_dist) claims.push({d, i, j});
    });
  };
  for (int j = 0; j < grid.size(); ++j) {
    if (label[j] >= 0) claim_neighbours(j);
  }
  while (!claims.empty()) {
    const Claim top = claims.top();
    claims.pop();
    if (label[top.cell] >= 0) continue;  // taken by a nearer plane
    label[top.cell] = label[top.from];
    (*moments)[label[top.cell]].Add(p[top.cell]);
    claim_neighbours(top.cell);
  }
}

}  // namespace hgrasp::segment
