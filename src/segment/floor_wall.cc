#include "segment/floor_wall.h"

#include <cmath>
#include <limits>

namespace hgrasp::segment {
namespace {

constexpr double kFloorNz = 0.95, kFloorClearance = 0.005;
constexpr double kWallNz = 0.1, kWallClearance = 0.02;

// A floor lies below all other planes, and a wall behind them, the removed ones included: z of
// the floors and x of the walls removed so far.
struct Removed {
  std::vector<char> region;  // per region: 1 if removed
  std::vector<double> floor_z, wall_x;
};

/// The remaining region (not gone) of the least key(region) (ties: the first); -1 if none.
template <typename Key>
int Least(const std::vector<PlaneRegion>& regions, const std::vector<char>& gone, const Key& key) {
  int least = -1;
  for (int k = 0; k < static_cast<int>(regions.size()); ++k) {
    if (!gone[k] && (least < 0 || key(regions[k]) < key(regions[least]))) least = k;
  }
  return least;
}

/// Floor: the lowest remaining horizontal region, no other region's centroid more than the
/// clearance below it. Removes it with every region whose centroid lies within the clearance of
/// its height, whatever its normal; returns whether it found one.
bool RemoveFloor(const std::vector<PlaneRegion>& regions, Removed* removed,
                 std::vector<int>* floor_or_wall) {
  const int n = static_cast<int>(regions.size());
  std::vector<char>& gone = removed->region;
  const int lowest = Least(regions, gone, [](const PlaneRegion& r) {
    return std::abs(r.normal_W.z()) > kFloorNz ? r.centroid_W.z()
                                               : std::numeric_limits<double>::infinity();
  });
  if (lowest < 0 || !(std::abs(regions[lowest].normal_W.z()) > kFloorNz)) return false;
  // Regions at its height are pieces of the same plane: a line of missing cells can split the
  // table, and a strip of it along a box's foot or the scan's edge, fitted to few or mixed
  // points, can come out tilted. No box face lies that low: a side's centroid is half its
  // box's height up, and a box under 2 clearances tall is below what the scan resolves.
  const double z0 = regions[lowest].centroid_W.z();
  auto same_plane = [&](int k) {
    return std::abs(regions[k].centroid_W.z() - z0) < kFloorClearance;
  };
  bool below_all = true;
  for (int k = 0; k < n; ++k) {
    if (!gone[k] && regions[k].centroid_W.z() <= z0 - kFloorClearance) below_all = false;
  }
  for (const double z : removed->floor_z) {
    if (z0 > z + kFloorClearance) below_all = false;
  }
  if (!below_all) return false;
  removed->floor_z.push_back(z0);
  for (int k = 0; k < n; ++k) {
    if (!gone[k] && (k == lowest || same_plane(k))) {
      gone[k] = 1;
      floor_or_wall->push_back(regions[k].id);
    }
  }
  return true;
}

/// Wall: the farthest remaining region in x, vertical, all others well nearer. Removes it;
/// returns whether it found one.
bool RemoveWall(const std::vector<PlaneRegion>& regions, Removed* removed,
                std::vector<int>* floor_or_wall) {
  const int n = static_cast<int>(regions.size());
  std::vector<char>& gone = removed->region;
  const int farthest = Least(regions, gone, [](const PlaneRegion& r) { return -r.centroid_W.x(); });
  if (farthest < 0 || !(std::abs(regions[farthest].normal_W.z()) < kWallNz)) return false;
  const double x0 = regions[farthest].centroid_W.x();
  bool behind_all = true;
  for (int k = 0; k < n; ++k) {
    if (k != farthest && !gone[k] && regions[k].centroid_W.x() > x0 - kWallClearance) {
      behind_all = false;
    }
  }
  for (const double x : removed->wall_x) {
    if (x0 < x - kWallClearance) behind_all = false;
  }
  if (!behind_all) return false;
  gone[farthest] = 1;
  removed->wall_x.push_back(x0);
  floor_or_wall->push_back(regions[farthest].id);
  return true;
}

}  // namespace

std::vector<char> RemoveFloorsAndWalls(const std::vector<PlaneRegion>& regions,
                                       std::vector<int>* floor_or_wall) {
  Removed removed;
  removed.region.assign(regions.size(), 0);
  while (RemoveFloor(regions, &removed, floor_or_wall) ||
         RemoveWall(regions, &removed, floor_or_wall)) {
  }
  return removed.region;
}

}  // namespace hgrasp::segment
