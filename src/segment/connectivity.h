#pragma once
/// @file Step 2 of SegmentPlanes: the initial segmentation by sequential binary connectivity
/// (raster scan + union-find) of the cells with a patch normal, under the paper's coplanarity
/// tests between 4-neighbours.

#include <Eigen/Core>
#include <vector>

#include "segment/cell_grid.h"
#include "segment/patch_normals.h"
#include "segment/plane_moments.h"

namespace hgrasp::segment {

/// The paper's coplanarity test of two patches with unit normals n1, n2 (either sign) through the
/// points m1, m2: |n1 . n2| > alpha1 and max(|r12 . n1|, |r12 . n2|) < alpha2 for the unit
/// r12 = (m1 - m2) / |m1 - m2| (true when m1 == m2).
bool Coplanar(const Eigen::Vector3d& n1, const Eigen::Vector3d& m1, const Eigen::Vector3d& n2,
              const Eigen::Vector3d& m2, double alpha1, double alpha2);

/// Whether cells i and j connect: both have a patch normal, grid.Near(i, j), and their patches
/// pass Coplanar.
bool CellsConnect(const CellGrid& grid, const PatchPlanes& patches, int i, int j, double alpha1,
                  double alpha2);

/// The initial regions: the connected components of the cells with a patch normal under
/// CellsConnect between 4-neighbours, labelled 0..n_regions-1 in raster order of their first
/// cell; -1 for cells without a normal.
struct InitialRegions {
  std::vector<int> label;  ///< per cell
  int n_regions = 0;
};
InitialRegions ConnectRegions(const CellGrid& grid, const PatchPlanes& patches, double alpha1,
                              double alpha2);

/// Moment sums (of the points of grid) per region of `label` (-1: none), n_regions of them.
std::vector<Moments> RegionMoments(const CellGrid& grid, const std::vector<int>& label,
                                   int n_regions);

}  // namespace hgrasp::segment
