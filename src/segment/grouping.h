#pragma once
/// @file The second part of GroupObjects: the regions left after floor and wall removal grouped
/// into connected objects.

#include <vector>

#include "scan/range_image.h"
#include "segment/segment.h"

namespace hgrasp::segment {

/// Per region id (0..max id of s.regions): its index in s.regions, -1 for ids not used. Aborts
/// on a negative or repeated id.
std::vector<int> RegionIndexById(const std::vector<PlaneRegion>& regions);

/// The connected groups of the regions of s not removed (removed: per index into s.regions, 1 if
/// removed): two regions are in one group when some pair of their cells lie within reach_cells
/// of each other in the range image (rows and columns) with valid 3-D points closer than
/// max_gap_m. index_of: RegionIndexById(s.regions); s must match range in size. Groups are in
/// order of their first region (index into s.regions); each holds its region ids ascending.
std::vector<std::vector<int>> GroupRegions(const SegmentResult& s, const scan::RangeImage& range,
                                           const std::vector<int>& index_of,
                                           const std::vector<char>& removed, int reach_cells,
                                           double max_gap_m);

}  // namespace hgrasp::segment
