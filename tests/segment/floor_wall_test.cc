// Floor and wall removal on hand-worked region lists (normals and centroids only).

#include "segment/floor_wall.h"

#include <gtest/gtest.h>

#include <vector>

namespace hgrasp::segment {
namespace {

using Eigen::Vector3d;

PlaneRegion Region(int id, const Vector3d& normal, const Vector3d& centroid) {
  PlaneRegion r;
  r.id = id;
  r.normal_W = normal.normalized();
  r.centroid_W = centroid;
  r.cells = 100;
  return r;
}

const Vector3d kUp = Vector3d::UnitZ(), kFacing = -Vector3d::UnitX();

TEST(RemoveFloorsAndWalls, TableUnderABoxIsTheFloor) {
  // Ids need not be indices: the ids are reported.
  const std::vector<PlaneRegion> regions = {
      Region(7, kUp, {0.3, 0.0, 0.1}),        // box top
      Region(3, kUp, {0.4, 0.0, 0.0}),        // table
      Region(5, kFacing, {0.25, 0.0, 0.05}),  // box front
  };
  std::vector<int> removed_ids;
  EXPECT_EQ(RemoveFloorsAndWalls(regions, &removed_ids), (std::vector<char>{0, 1, 0}));
  EXPECT_EQ(removed_ids, (std::vector<int>{3}));
}

TEST(RemoveFloorsAndWalls, PiecesAtTheFloorsHeightGoWithIt) {
  const std::vector<PlaneRegion> regions = {
      Region(0, kUp, {0.3, 0.2, 0.004}),  // 4 mm above the lowest: the same plane
      Region(1, kUp, {0.3, -0.2, 0.0}), Region(2, kUp, {0.3, 0.0, 0.006}),  // 6 mm above: not
  };
  std::vector<int> removed_ids;
  // The floor is region 1 with region 0; then region 2 is the lowest left, but more than 5 mm
  // above that floor: no second floor.
  EXPECT_EQ(RemoveFloorsAndWalls(regions, &removed_ids), (std::vector<char>{1, 1, 0}));
  EXPECT_EQ(removed_ids, (std::vector<int>{0, 1}));
}

TEST(RemoveFloorsAndWalls, NoFloorWhenSomethingIsBelowIt) {
  // A face whose centroid is 6 mm below the lowest horizontal region: that is no floor below all
  // other planes.
  const std::vector<PlaneRegion> regions = {
      Region(0, kUp, {0.3, 0.0, 0.0}),
      Region(1, kFacing, {0.3, 0.1, -0.006}),
  };
  std::vector<int> removed_ids;
  EXPECT_EQ(RemoveFloorsAndWalls(regions, &removed_ids), (std::vector<char>{0, 0}));
  EXPECT_TRUE(removed_ids.empty());
}

// Issue 37 (wide_19, wide_12 of the wide family): a strip of the table fitted tilted (n.z 0.90,
// its centroid at the table's height) or a face 3 mm up kept the table from being the floor, and
// every box joined it in one object. Now they are pieces of the floor.
TEST(RemoveFloorsAndWalls, TiltedPiecesAtTheTablesHeightGoWithTheFloor) {
  const std::vector<PlaneRegion> regions = {
      Region(0, kUp, {0.41, 0.0, 0.0}),                           // the table
      Region(1, Vector3d(-0.09, 0.43, 0.90), {0.48, 0.32, 0.0}),  // a strip of it, tilted
      Region(2, kFacing, {0.3, 0.1, 0.003}),                      // 3 mm up, facing the robot
      Region(3, kUp, {0.37, 0.0, 0.115}),                         // a box top
      Region(4, kFacing, {0.34, 0.0, 0.06}),                      // its side
  };
  std::vector<int> removed_ids;
  EXPECT_EQ(RemoveFloorsAndWalls(regions, &removed_ids), (std::vector<char>{1, 1, 1, 0, 0}));
  EXPECT_EQ(removed_ids, (std::vector<int>{0, 1, 2}));
}

TEST(RemoveFloorsAndWalls, TiltedLowestRegionIsNoFloor) {
  // |n.z| = cos 20 deg = 0.94 <= 0.95.
  const Vector3d tilted(std::sin(20 * M_PI / 180), 0.0, std::cos(20 * M_PI / 180));
  const std::vector<PlaneRegion> regions = {Region(0, tilted, {0.3, 0.0, 0.0}),
                                            Region(1, kUp, {0.3, 0.0, 0.1})};
  std::vector<int> removed_ids;
  EXPECT_EQ(RemoveFloorsAndWalls(regions, &removed_ids), (std::vector<char>{0, 0}));
}

TEST(RemoveFloorsAndWalls, LoneTopOverAnEarlierFloorStays) {
  const std::vector<PlaneRegion> regions = {Region(0, kUp, {0.3, 0.0, 0.0}),
                                            Region(1, kUp, {0.3, 0.0, 0.1})};
  std::vector<int> removed_ids;
  EXPECT_EQ(RemoveFloorsAndWalls(regions, &removed_ids), (std::vector<char>{1, 0}));
  EXPECT_EQ(removed_ids, (std::vector<int>{0}));
}

TEST(RemoveFloorsAndWalls, WallBehindEverythingAfterTheFloor) {
  const std::vector<PlaneRegion> regions = {
      Region(0, kFacing, {0.8, 0.0, 0.2}),   // wall
      Region(1, kUp, {0.4, 0.0, 0.0}),       // table
      Region(2, kFacing, {0.3, 0.0, 0.05}),  // box front
      Region(3, kUp, {0.33, 0.0, 0.1}),      // box top
  };
  std::vector<int> removed_ids;
  EXPECT_EQ(RemoveFloorsAndWalls(regions, &removed_ids), (std::vector<char>{1, 1, 0, 0}));
  EXPECT_EQ(removed_ids, (std::vector<int>{1, 0}));  // the floor first, then the wall
}

TEST(RemoveFloorsAndWalls, NoWallWithAnotherFaceWithinTwoCentimetres) {
  const std::vector<PlaneRegion> regions = {
      Region(0, kFacing, {0.8, 0.0, 0.2}),
      Region(1, kFacing, {0.79, 0.3, 0.2}),  // 1 cm nearer: < 2 cm
  };
  std::vector<int> removed_ids;
  EXPECT_EQ(RemoveFloorsAndWalls(regions, &removed_ids), (std::vector<char>{0, 0}));
  // 2.5 cm nearer: the farther is a wall; then the other is no wall 2.5 cm in front of it.
  std::vector<PlaneRegion> apart = regions;
  apart[1].centroid_W.x() = 0.775;
  EXPECT_EQ(RemoveFloorsAndWalls(apart, &removed_ids), (std::vector<char>{1, 0}));
  EXPECT_EQ(removed_ids, (std::vector<int>{0}));
}

}  // namespace
}  // namespace hgrasp::segment
