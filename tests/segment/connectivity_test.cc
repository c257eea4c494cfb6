// Step 2 of the segmentation on hand-worked cases: the paper's coplanarity test, the neighbour
// gap, and the sequential labelling (raster order, union-find of the two arms of a U).

#include "segment/connectivity.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace hgrasp::segment {
namespace {

using Eigen::Vector3d;

constexpr double kStep = 0.005;  // grid spacing (m)

TEST(Coplanar, PaperTestsOnHandWorkedPatches) {
  const Vector3d z = Vector3d::UnitZ(), x = Vector3d::UnitX();
  // Two patches of one plane, 5 mm apart: r12 . n = 0.
  EXPECT_TRUE(Coplanar(z, Vector3d(0, 0, 0), z, Vector3d(kStep, 0, 0), 0.9, 0.1));
  EXPECT_TRUE(Coplanar(z, Vector3d(0, 0, 0), -z, Vector3d(kStep, 0, 0), 0.9, 0.1));  // either sign
  // A 90-degree corner: n1 . n2 = 0 <= alpha1, whatever the positions.
  EXPECT_FALSE(Coplanar(z, Vector3d(0, 0, 0), x, Vector3d(kStep, 0, 0), 0.9, 0.1));
  // Parallel planes 2 mm apart, patches 5 mm apart: |r12 . n| = 2 / sqrt(29) = 0.37 >= alpha2.
  EXPECT_FALSE(Coplanar(z, Vector3d(0, 0, 0), z, Vector3d(kStep, 0, 0.002), 0.9, 0.1));
  // ... but within a looser alpha2 = 0.4.
  EXPECT_TRUE(Coplanar(z, Vector3d(0, 0, 0), z, Vector3d(kStep, 0, 0.002), 0.9, 0.4));
  // Normals 30 deg apart: cos 30 = 0.866 <= 0.9, > 0.85.
  const Vector3d n30(0.5, 0.0, std::sqrt(0.75));
  EXPECT_FALSE(Coplanar(z, Vector3d(0, 0, 0), n30, Vector3d(0, kStep, 0), 0.9, 0.1));
  EXPECT_TRUE(Coplanar(z, Vector3d(0, 0, 0), n30, Vector3d(0, kStep, 0), 0.85, 0.1));
  // Coincident means pass the second test.
  EXPECT_TRUE(Coplanar(z, Vector3d(1, 2, 3), z, Vector3d(1, 2, 3), 0.9, 0.1));
}

// A grid from a picture: one row of characters per row; 'z' a cell with normal z on the plane
// z = 0, 'x' a cell with normal x on a wall rising from the plane, '.' a valid cell without normal,
// ' ' an invalid cell, 'f' a cell with normal z but 2 cm above the plane (farther than the gap from
// its neighbours).
struct Scene {
  CellGrid grid;
  PatchPlanes patches;
};
Scene FromPicture(const std::vector<std::string>& rows) {
  Scene s;
  s.grid.rows = static_cast<int>(rows.size());
  s.grid.cols = static_cast<int>(rows[0].size());
  s.grid.max_gap_sq = 0.01 * 0.01;
  for (int r = 0; r < s.grid.rows; ++r) {
    for (int c = 0; c < s.grid.cols; ++c) {
      const char ch = rows[r][c];
      // 'x' cells form the wall x = const rising from the plane at the row's first 'x'.
      const int x0 = static_cast<int>(rows[r].find('x'));
      const Vector3d p = ch == 'x' ? Vector3d(x0 * kStep, r * kStep, (c - x0) * kStep)
                                   : Vector3d(c * kStep, r * kStep, ch == 'f' ? 0.02 : 0.0);
      s.grid.p.push_back(ch == ' ' ? Vector3d::Zero() : p);
      s.grid.valid.push_back(ch != ' ');
      const bool has = ch == 'z' || ch == 'x' || ch == 'f';
      s.patches.has_normal.push_back(has);
      const Vector3d n = ch == 'x' ? Vector3d(Vector3d::UnitX()) : Vector3d(Vector3d::UnitZ());
      s.patches.normal.push_back(has ? n : Vector3d::Zero());
      s.patches.mean.push_back(has ? p : Vector3d::Zero());
    }
  }
  return s;
}

TEST(CellsConnect, NeedsNormalsTheGapAndCoplanarity) {
  const Scene s = FromPicture({"zz.zxf"});
  EXPECT_TRUE(CellsConnect(s.grid, s.patches, 0, 1, 0.9, 0.1));   // coplanar neighbours
  EXPECT_FALSE(CellsConnect(s.grid, s.patches, 1, 2, 0.9, 0.1));  // no normal
  EXPECT_FALSE(CellsConnect(s.grid, s.patches, 3, 4, 0.9, 0.1));  // 90-degree corner
  // 'f' has normal z but lies 2 cm above: a gap larger than max_neighbour_gap_m (1 cm) ...
  const Scene t = FromPicture({"zf"});
  EXPECT_FALSE(CellsConnect(t.grid, t.patches, 0, 1, 0.9, 1.0));
  // ... and connected with a 3 cm gap (alpha2 1: the parallel planes' offset is allowed).
  Scene u = t;
  u.grid.max_gap_sq = 0.03 * 0.03;
  EXPECT_TRUE(CellsConnect(u.grid, u.patches, 0, 1, 0.9, 1.0));
}

TEST(ConnectRegions, LabelsInRasterOrderAndJoinsTheArmsOfAU) {
  const Scene s = FromPicture({
      "z.z.xx",
      "z.z.xx",
      "zzz. f",
  });
  const InitialRegions out = ConnectRegions(s.grid, s.patches, 0.9, 0.1);
  // The U of 'z' is one region (its arms got labels 0 and 1, joined on the bottom row); the 'x'
  // block the second; 'f' is alone (2 cm above: not near); '.' and ' ' have no label.
  const std::vector<int> expected = {
      0, -1, 0, -1, 1,  1,  //
      0, -1, 0, -1, 1,  1,  //
      0, 0,  0, -1, -1, 2,
  };
  EXPECT_EQ(out.label, expected);
  EXPECT_EQ(out.n_regions, 3);
  const std::vector<Moments> m = RegionMoments(s.grid, out.label, out.n_regions);
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m[0].n(), 7.0);
  EXPECT_EQ(m[1].n(), 4.0);
  EXPECT_EQ(m[2].n(), 1.0);
  EXPECT_NEAR(m[2].Mean().z(), 0.02, 1e-15);
}

TEST(ConnectRegions, CornerSplitsTwoFaces) {
  // A 90-degree corner between two blocks: no pair across it connects.
  const Scene s = FromPicture({"zzxx", "zzxx"});
  const InitialRegions out = ConnectRegions(s.grid, s.patches, 0.9, 0.1);
  EXPECT_EQ(out.label, (std::vector<int>{0, 0, 1, 1, 0, 0, 1, 1}));
  EXPECT_EQ(out.n_regions, 2);
}

}  // namespace
}  // namespace hgrasp::segment
