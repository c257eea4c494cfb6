#pragma once
/// @file Step 5 of SegmentPlanes: boundary refinement after merging, and step 6: the regions
/// left, small ones dropped, as a SegmentResult.

#include <vector>

#include "segment/cell_grid.h"
#include "segment/plane_moments.h"
#include "segment/segment.h"

namespace hgrasp::segment {

/// Up to `passes` passes of boundary refinement: a cell next to (4-neighbour and grid.Near)
/// another region whose plane it lies nearer moves there; a pass decides every move from the
/// planes fitted at its start, then makes them; refinement stops after a pass without moves.
/// Only regions k with merged_into[k] == k and at least min_region_cells cells (at the pass's
/// start) have a plane and take part, either way. label: per cell, a region left by merging or
/// -1; moments: per region, updated with the moves.
///
/// Patches that straddle a crease can pass the connectivity tests with the face across it; a box
/// side then holds a line of table (or top) cells along its bottom (top) edge.
void RefineBoundaries(const CellGrid& grid, const std::vector<int>& merged_into, int passes,
                      int min_region_cells, std::vector<int>* label, std::vector<Moments>* moments);

/// The regions k with merged_into[k] == k and at least min_region_cells cells, numbered from 0 in
/// order of k, with their plane fits (centroids in W), into result->regions; result->labels
/// (grid.size() cells, all -1 on entry) gets their ids, -1 for the cells of the regions dropped.
void CollectRegions(const CellGrid& grid, const std::vector<int>& label,
                    const std::vector<int>& merged_into, const std::vector<Moments>& moments,
                    int min_region_cells, SegmentResult* result);

}  // namespace hgrasp::segment
