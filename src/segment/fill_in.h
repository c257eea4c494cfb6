#pragma once
/// @file Step 3 of SegmentPlanes: cells without a patch normal (at creases, depth jumps and the
/// image border) join the neighbouring region whose plane they lie on.

#include <vector>

#include "segment/cell_grid.h"
#include "segment/patch_normals.h"
#include "segment/plane_moments.h"

namespace hgrasp::segment {

/// Labels the unlabelled valid cells that lie within max_dist (m) of the plane of a region they
/// are grid.Near, best first: of all (cell, labelled 4-neighbour) pairs, the one whose region's
/// plane the cell lies nearest is taken next (ties: the lower cell, then the lower neighbour),
/// and the cell's own neighbours become candidates. A region's plane is its plane fit when it has
/// at least min_plane_cells cells (counted before any cell joins); otherwise the neighbour's patch
/// plane (its normal through its point), or, where that has none, the neighbour's point itself.
/// label: per cell, -1 for none; moments: per region, updated with the cells that join it.
void FillUnlabelled(const CellGrid& grid, const PatchPlanes& patches, int min_plane_cells,
                    double max_dist, std::vector<int>* label, std::vector<Moments>* moments);

}  // namespace hgrasp::segment
