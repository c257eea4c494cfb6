#pragma once
/// @file Step 4 of SegmentPlanes: region merging by boundary-cost minimisation.

#include <vector>

#include "segment/cell_grid.h"
#include "segment/plane_moments.h"

namespace hgrasp::segment {

/// Repeatedly merges the adjacent pair of regions whose merged plane fit has the smallest
/// residual (Residual of the two's moment sums together, m^2), until that exceeds max_cost; ties
/// go to the lower region index. label: the region of each cell of grid (-1: none); regions are
/// adjacent where two of their cells are 4-neighbours with grid.Near. moments: per region; on
/// return the merged regions' sums for the regions left (those of the regions merged away are
/// stale). Returns, per region, the region it was merged into (itself for the regions left),
/// which is the merged regions' lowest index.
///
/// First, adjacent regions of at most three cells together are merged in raster order of their
/// cells: such a merge costs exactly 0, i.e. is a cheapest one. Then each region keeps its
/// neighbours with the cost of merging with each (recomputed whenever either changes) and its
/// cheapest merge, which an indexed heap orders.
std::vector<int> MergeRegions(const std::vector<int>& label, const CellGrid& grid, double max_cost,
                              std::vector<Moments>* moments);

}  // namespace hgrasp::segment
