// Step 1 of the segmentation on hand-worked grids: a tilted plane (exact normal, patch means,
// which border cells have too few points), and a step edge (no normal where a window straddles
// it).

#include "segment/patch_normals.h"

#include <gtest/gtest.h>

#include <cmath>

namespace hgrasp::segment {
namespace {

using Eigen::Vector3d;

constexpr double kStep = 0.005;  // grid spacing (m)

// A rows x cols grid, all valid, with points f(r, c).
template <typename F>
CellGrid Grid(int rows, int cols, const F& f) {
  CellGrid g;
  g.rows = rows;
  g.cols = cols;
  g.max_gap_sq = 0.01 * 0.01;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      g.p.push_back(f(r, c));
      g.valid.push_back(1);
    }
  }
  return g;
}

TEST(PatchNormals, TiltedPlaneHasItsExactNormal) {
  // z = 0.5 x: normal (-0.5, 0, 1) / |.|, up to sign.
  const CellGrid g =
      Grid(10, 10, [](int r, int c) { return Vector3d(c * kStep, r * kStep, 0.5 * c * kStep); });
  const PatchPlanes pp = PatchNormals(g, 5, 4e-6);
  const Vector3d n = Vector3d(-0.5, 0.0, 1.0).normalized();
  int with_normal = 0;
  for (int r = 0; r < 10; ++r) {
    for (int c = 0; c < 10; ++c) {
      const int i = r * 10 + c;
      // Window of a patch of 5 clipped at the border: 3 rows (columns) at the first and last
      // row (column), 4 at the second; a normal needs (25 + 1) / 2 = 13 points, i.e. not 3 x 3
      // or 3 x 4.
      auto in = [](int k) { return k == 0 || k == 9 ? 3 : (k == 1 || k == 8 ? 4 : 5); };
      const bool expected = in(r)*in(c) >= 13;
      ASSERT_EQ(pp.has_normal[i] != 0, expected) << r << "," << c;
      if (!expected) {
        EXPECT_EQ(pp.normal[i], Vector3d::Zero());
        continue;
      }
      ++with_normal;
      EXPECT_NEAR(std::abs(pp.normal[i].dot(n)), 1.0, 1e-12) << r << "," << c;
      if (r >= 2 && r <= 7 && c >= 2 && c <= 7) {  // a full window: its mean is the cell's point
        EXPECT_LT((pp.mean[i] - g.p[i]).norm(), 1e-15) << r << "," << c;
      }
    }
  }
  EXPECT_EQ(with_normal, 100 - 4 * 3);  // per corner: 3 x 3, 3 x 4 and 4 x 3
}

TEST(PatchNormals, StepEdgeHasNoNormalWhereTheWindowStraddlesIt) {
  // z = 0 for columns 0-4, z = 5 cm for columns 5-11.
  const CellGrid g =
      Grid(9, 12, [](int r, int c) { return Vector3d(c * kStep, r * kStep, c >= 5 ? 0.05 : 0.0); });
  const PatchPlanes pp = PatchNormals(g, 5, 4e-6);
  for (int r = 2; r <= 6; ++r) {  // rows with full windows
    for (int c = 2; c <= 9; ++c) {
      const int i = r * 12 + c;
      // A window's columns c-2..c+2 straddle the step for c in 3..6.
      const bool straddles = c >= 3 && c <= 6;
      EXPECT_EQ(pp.has_normal[i] != 0, !straddles) << r << "," << c;
      if (!straddles) {
        EXPECT_NEAR(std::abs(pp.normal[i].z()), 1.0, 1e-12);
      }
    }
  }
}

TEST(PatchNormals, InvalidCellsHaveNoNormalAndAreSkipped) {
  CellGrid g = Grid(7, 7, [](int r, int c) { return Vector3d(c * kStep, r * kStep, 0.0); });
  // An invalid cell whose (zero) point lies far off the plane z = 0 would spoil its neighbours'
  // windows if it were counted.
  g.valid[3 * 7 + 3] = 0;
  g.p[3 * 7 + 3] = Vector3d(0.0, 0.0, 1.0);
  const PatchPlanes pp = PatchNormals(g, 3, 4e-6);
  EXPECT_EQ(pp.has_normal[3 * 7 + 3], 0);
  EXPECT_EQ(pp.has_normal[3 * 7 + 4], 1);
  EXPECT_NEAR(std::abs(pp.normal[3 * 7 + 4].z()), 1.0, 1e-12);
}

}  // namespace
}  // namespace hgrasp::segment
