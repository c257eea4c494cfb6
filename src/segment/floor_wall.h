#pragma once
/// @file The first part of GroupObjects: floor and wall removal (paper 5.1).

#include <vector>

#include "segment/segment.h"

namespace hgrasp::segment {

/// Removes floors and walls from `regions` until none remain (see GroupObjects for the rules).
/// Each round looks for a floor first, then, if none, for a wall. Returns, per region (index into
/// regions), 1 if removed; appends the removed regions' ids to floor_or_wall in the order removed.
std::vector<char> RemoveFloorsAndWalls(const std::vector<PlaneRegion>& regions,
                                       std::vector<int>* floor_or_wall);

}  // namespace hgrasp::segment
