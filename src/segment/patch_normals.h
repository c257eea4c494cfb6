#pragma once
/// @file Step 1 of SegmentPlanes: a plane fitted to the valid cells of each cell's
/// patch x patch window; where its residual is small enough, the cell has a normal.

#include <Eigen/Core>
#include <vector>

#include "segment/cell_grid.h"

namespace hgrasp::segment {

/// Per cell of a CellGrid: its window's plane, where it has one.
struct PatchPlanes {
  /// Unit normal of the window's plane fit (unoriented: every use is insensitive to its sign);
  /// zero where !has_normal.
  std::vector<Eigen::Vector3d> normal;
  /// Mean of the window's points, relative to CellGrid::origin_W (the paper's m_i: the point the
  /// patch plane passes through); zero where !has_normal.
  std::vector<Eigen::Vector3d> mean;
  std::vector<char> has_normal;  ///< 1 where the cell has a valid normal
};

/// The plane fits to each valid cell's patch x patch window (patch odd, >= 3; clipped at the
/// image border; invalid cells skipped). A cell has a normal when its window holds at least
/// max(3, (patch^2 + 1) / 2) points and the fit's residual (smallest eigenvalue of the window's
/// covariance, m^2) is at most max_residual_m2. The windows' moment sums come from a separable
/// box filter, O(1) per cell: running sums down the columns (over a ring of rows), then running
/// sums along each row.
PatchPlanes PatchNormals(const CellGrid& grid, int patch, double max_residual_m2);

}  // namespace hgrasp::segment
