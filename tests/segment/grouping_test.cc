// Grouping of the regions left after floor and wall removal, on hand-drawn range images.

#include "segment/grouping.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace hgrasp::segment {
namespace {

using Eigen::Vector3d;

constexpr double kStep = 0.005;  // grid spacing (m)

// A segmentation from a picture: a digit d is a valid cell of region id d, on the plane z = 0 at
// (column, row) x 5 mm, lifted by lift[d] (m); '.' a valid cell of no region, ' ' an invalid
// cell. The regions are listed in order of id (their contents do not matter here).
struct Scene {
  scan::RangeImage range{0, 0};
  SegmentResult s;
};
Scene FromPicture(const std::vector<std::string>& rows, const std::vector<double>& lift = {}) {
  Scene out;
  const int n_rows = static_cast<int>(rows.size()), n_cols = static_cast<int>(rows[0].size());
  out.range = scan::RangeImage(n_rows, n_cols);
  out.s.rows = n_rows;
  out.s.cols = n_cols;
  int max_id = -1;
  for (int r = 0; r < n_rows; ++r) {
    for (int c = 0; c < n_cols; ++c) {
      const char ch = rows[r][c];
      const int id = ch >= '0' && ch <= '9' ? ch - '0' : -1;
      scan::RangeCell& cell = out.range.at(r, c);
      cell.valid = ch != ' ';
      const double z = id >= 0 && id < static_cast<int>(lift.size()) ? lift[id] : 0.0;
      cell.p_W = Vector3d(c * kStep, r * kStep, z);
      out.s.labels.push_back(id);
      max_id = std::max(max_id, id);
    }
  }
  for (int id = 0; id <= max_id; ++id) {
    PlaneRegion region;
    region.id = id;
    out.s.regions.push_back(region);
  }
  return out;
}

using Groups = std::vector<std::vector<int>>;

TEST(RegionIndexById, MapsIdsToIndices) {
  std::vector<PlaneRegion> regions(2);
  regions[0].id = 4;
  regions[1].id = 1;
  EXPECT_EQ(RegionIndexById(regions), (std::vector<int>{-1, 1, -1, -1, 0}));
  EXPECT_TRUE(RegionIndexById({}).empty());
}

TEST(GroupRegions, TouchingRegionsAreOneObject) {
  const Scene sc = FromPicture({
      "0011..22",
      "0011..22",
  });
  const std::vector<int> index_of = RegionIndexById(sc.s.regions);
  // 0 and 1 touch; 2 is 3 cells (15 mm between the points across the gap) away from 1: within a
  // reach of 3 cells and 16 mm ...
  EXPECT_EQ(GroupRegions(sc.s, sc.range, index_of, {0, 0, 0}, 3, 0.016), (Groups{{0, 1, 2}}));
  // ... not within 2 cells, nor within 3 cells and 15 mm (closer than, strictly).
  EXPECT_EQ(GroupRegions(sc.s, sc.range, index_of, {0, 0, 0}, 2, 0.016), (Groups{{0, 1}, {2}}));
  EXPECT_EQ(GroupRegions(sc.s, sc.range, index_of, {0, 0, 0}, 3, 0.015), (Groups{{0, 1}, {2}}));
}

TEST(GroupRegions, ReachBridgesMissingCellsUpToItsLength) {
  // Between 0 and 1 two invalid cells (the gap along a box's edge): 3 columns from one to the
  // other; 1 and 2 are 5 columns apart.
  const Scene sc = FromPicture({"00  11....22"});
  const std::vector<int> index_of = RegionIndexById(sc.s.regions);
  EXPECT_EQ(GroupRegions(sc.s, sc.range, index_of, {0, 0, 0}, 3, 0.02), (Groups{{0, 1}, {2}}));
}

TEST(GroupRegions, AGapIn3DSeparatesTouchingRegions) {
  // 1 lies 2 cm above 0 and 2 (a box on the table seen from above, say): its cells touch theirs
  // in the image, but their points are farther apart than 15 mm.
  const Scene sc = FromPicture({"001122", "001122"}, {0.0, 0.02, 0.0});
  const std::vector<int> index_of = RegionIndexById(sc.s.regions);
  // 0 and 2 are 15 mm apart across 1: not closer than 15 mm.
  EXPECT_EQ(GroupRegions(sc.s, sc.range, index_of, {0, 0, 0}, 3, 0.015), (Groups{{0}, {1}, {2}}));
}

TEST(GroupRegions, RemovedRegionsAreLeftOutAndBridgeNothing) {
  const Scene sc = FromPicture({"0011112222"});
  const std::vector<int> index_of = RegionIndexById(sc.s.regions);
  // With 1 removed, 0 and 2 are 5 cells apart.
  EXPECT_EQ(GroupRegions(sc.s, sc.range, index_of, {0, 1, 0}, 3, 0.03), (Groups{{0}, {2}}));
  EXPECT_EQ(GroupRegions(sc.s, sc.range, index_of, {0, 0, 0}, 3, 0.03), (Groups{{0, 1, 2}}));
}

TEST(GroupRegions, GroupsInOrderOfTheirFirstRegionWithIdsAscending) {
  // Region ids in s.regions out of order: ids 9, 2, 5 at indices 0, 1, 2; 9 touches 5. The first
  // group is that of index 0, its ids sorted.
  Scene sc = FromPicture({"5599....22"});
  sc.s.regions = {};
  for (const int id : {9, 2, 5}) {
    PlaneRegion r;
    r.id = id;
    sc.s.regions.push_back(r);
  }
  const std::vector<int> index_of = RegionIndexById(sc.s.regions);
  EXPECT_EQ(GroupRegions(sc.s, sc.range, index_of, {0, 0, 0}, 1, 0.015), (Groups{{5, 9}, {2}}));
}

}  // namespace
}  // namespace hgrasp::segment
