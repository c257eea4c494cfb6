// Step 3 of the segmentation on hand-worked rows of cells: cells without a normal join the
// nearest plane (not the region that reaches them first), within max_dist and the gap only.

#include "segment/fill_in.h"

#include <gtest/gtest.h>

#include <vector>

namespace hgrasp::segment {
namespace {

using Eigen::Vector3d;

struct Scene {
  CellGrid grid;
  PatchPlanes patches;
  std::vector<int> label;
};

// One row of cells at these points, with these labels and patch normals (zero: none).
Scene Row(const std::vector<Vector3d>& p, const std::vector<int>& label,
          const std::vector<Vector3d>& normal) {
  Scene s;
  s.grid.rows = 1;
  s.grid.cols = static_cast<int>(p.size());
  s.grid.p = p;
  s.grid.valid.assign(p.size(), 1);
  s.grid.max_gap_sq = 0.01 * 0.01;
  s.patches.normal = normal;
  s.patches.mean = p;
  for (const Vector3d& n : normal) s.patches.has_normal.push_back(!n.isZero());
  s.label = label;
  return s;
}

std::vector<Moments> MomentsOf(const Scene& s, int n_regions) {
  std::vector<Moments> m(n_regions);
  for (int i = 0; i < s.grid.size(); ++i) {
    if (s.label[i] >= 0) m[s.label[i]].Add(s.grid.p[i]);
  }
  return m;
}

TEST(FillUnlabelled, CellJoinsTheNearerPlane) {
  const Vector3d z = Vector3d::UnitZ(), x = Vector3d::UnitX(), none = Vector3d::Zero();
  // Cell 1 lies 2 mm off region 0's patch plane (z = 0 through cell 0) and 0.5 mm off region 1's
  // (x = 5.5 mm through cell 2): it goes to region 1, although region 0 comes first.
  Scene s = Row({{0, 0, 0}, {0.005, 0, 0.002}, {0.0055, 0, 0.006}}, {0, -1, 1}, {z, none, x});
  std::vector<Moments> m = MomentsOf(s, 2);
  FillUnlabelled(s.grid, s.patches, 25, 0.006, &s.label, &m);
  EXPECT_EQ(s.label, (std::vector<int>{0, 1, 1}));
  EXPECT_EQ(m[0].n(), 1.0);
  EXPECT_EQ(m[1].n(), 2.0);
  EXPECT_NEAR(m[1].Mean().z(), 0.004, 1e-15);
}

TEST(FillUnlabelled, ChainsAlongARowWithinTheDistanceAndGap) {
  const Vector3d z = Vector3d::UnitZ(), none = Vector3d::Zero();
  // Region 0 at cell 0 (plane z = 0); cells 1-3 without normal at 1 mm, 2 mm, 9 mm above it:
  // 1 and 2 join one after the other (each from the one before: a region under 25 cells has no
  // plane of its own, and a cell without normal passes on its point), 3 is 7 mm off cell 2's
  // point (>= max_dist 6 mm); cell 4 is 2 cm beyond (not near).
  Scene s =
      Row({{0, 0, 0}, {0.001, 0, 0.001}, {0.002, 0, 0.002}, {0.002, 0, 0.009}, {0.022, 0, 0.009}},
          {0, -1, -1, -1, -1}, {z, none, none, none, none});
  std::vector<Moments> m = MomentsOf(s, 1);
  FillUnlabelled(s.grid, s.patches, 25, 0.006, &s.label, &m);
  EXPECT_EQ(s.label, (std::vector<int>{0, 0, 0, -1, -1}));
  EXPECT_EQ(m[0].n(), 3.0);
}

TEST(FillUnlabelled, LargeRegionUsesItsOwnPlaneFit) {
  // Region 0: 4 cells on z = 0 (min_plane_cells 4: its own plane); cell 4 at 1 mm joins, cell 5
  // at 6.5 mm (>= 6 mm off the region's plane, though 5.5 mm from cell 4's point) does not.
  Scene s = Row({{0, 0, 0},
                 {0.005, 0, 0},
                 {0.005, 0.005, 0},
                 {0.0, 0.005, 0},
                 {0.0, 0.0095, 0.001},
                 {0.0, 0.0095, 0.0065}},
                {0, 0, 0, 0, -1, -1}, std::vector<Vector3d>(6, Vector3d::Zero()));
  std::vector<Moments> m = MomentsOf(s, 1);
  FillUnlabelled(s.grid, s.patches, 4, 0.006, &s.label, &m);
  EXPECT_EQ(s.label, (std::vector<int>{0, 0, 0, 0, 0, -1}));
}

}  // namespace
}  // namespace hgrasp::segment
