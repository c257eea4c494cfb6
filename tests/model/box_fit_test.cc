#include "model/box_fit.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "common/geometry.h"
#include "segment/segment.h"
#include "tests/scan/synthetic_range.h"

namespace hgrasp::model {
namespace {

using Eigen::Vector3d;
using scan::RangeImage;

using scan::testing::AddNoise;
using scan::testing::FillBlock;

/// Which side faces the scene shows besides the top.
enum class Sides { kNone, kFront, kFrontAndLeft, kFrontAndRight };

/// A box resting on the table z = 0: centre (cx, cy, size.z / 2), rotated by yaw about z, edge
/// lengths size (multiples of step) along its own x, y, z. Faces are sampled on a grid of the
/// given step with samples half a step inside each edge (so a face's outermost samples lie
/// step / 2 from its edges). Image layout: top (rows 0..nx-1, the front face's columns; its x
/// decreases with the row), front face O x = -sx/2 below it, the left face (O y = -sy/2) to the
/// front's left or the right face (O y = +sy/2) to its right; two invalid rows, then a table
/// (z = 0, 26 rows, 5 mm grid) over all columns.
RangeImage BoxScene(double cx, double cy, double yaw, const Vector3d& size, double step,
                    Sides sides) {
  const int nx = static_cast<int>(std::lround(size.x() / step));
  const int ny = static_cast<int>(std::lround(size.y() / step));
  const int nz = static_cast<int>(std::lround(size.z() / step));
  const int c0 = 5;
  const int cf = c0 + nx;  // first column of the front face
  const int cols = cf + ny + nx + 5;
  const int table_row = nx + nz + 2;
  RangeImage img(table_row + 26, cols);
  const Eigen::Matrix3d R = RotZ(yaw);
  const Vector3d centre(cx, cy, size.z() / 2);
  const Vector3d half = size / 2;
  const double h = step / 2;
  auto fill = [&](int r0, int nr, int col0, int nc, const Vector3d& o_O, const Vector3d& dr_O,
                  const Vector3d& dc_O) {
    FillBlock(&img, r0, nr, col0, nc, centre + R * o_O, R * dr_O, R * dc_O);
  };
  fill(0, nx, cf, ny, Vector3d(half.x() - h, -half.y() + h, half.z()), Vector3d(-step, 0, 0),
       Vector3d(0, step, 0));
  if (sides != Sides::kNone) {
    fill(nx, nz, cf, ny, Vector3d(-half.x(), -half.y() + h, half.z() - h), Vector3d(0, 0, -step),
         Vector3d(0, step, 0));
  }
  if (sides == Sides::kFrontAndLeft) {
    fill(nx, nz, c0, nx, Vector3d(half.x() - h, -half.y(), half.z() - h), Vector3d(0, 0, -step),
         Vector3d(-step, 0, 0));
  }
  if (sides == Sides::kFrontAndRight) {
    fill(nx, nz, cf + ny, nx, Vector3d(-half.x() + h, half.y(), half.z() - h),
         Vector3d(0, 0, -step), Vector3d(step, 0, 0));
  }
  FillBlock(&img, table_row, 26, 0, cols, Vector3d(0.475, -0.2, 0.0), Vector3d(-0.005, 0, 0),
            Vector3d(0, 0.005, 0));
  return img;
}

/// Segments and groups the scene, expects one object, and fits a box to it.
std::optional<BoxModel> FitScene(const RangeImage& img, size_t expected_regions) {
  const segment::SegmentResult s = segment::SegmentPlanes(img);
  const segment::Grouping g = segment::GroupObjects(s, img);
  EXPECT_EQ(g.objects.size(), 1u);
  if (g.objects.size() != 1u) return std::nullopt;
  EXPECT_EQ(g.objects[0].size(), expected_regions);
  return FitBox(s, g.objects[0], img);
}

/// Yaw of O's x axis in W, minus `yaw`, wrapped into [-45, 45) deg.
double YawErrorMod90Deg(const BoxModel& box, double yaw_deg) {
  const Eigen::Matrix3d R = box.X_WO.linear();
  double d = RadToDeg(std::atan2(R(1, 0), R(0, 0))) - yaw_deg;
  d = std::fmod(d + 45.0, 90.0);
  if (d < 0) d += 90.0;
  return d - 45.0;
}

/// Expects the horizontal sizes to be {sa, sb} in either order, the height sz, within tol (m).
void ExpectSize(const BoxModel& box, double sa, double sb, double sz, double tol) {
  const double lo = std::min(box.size_O.x(), box.size_O.y());
  const double hi = std::max(box.size_O.x(), box.size_O.y());
  EXPECT_NEAR(lo, std::min(sa, sb), tol);
  EXPECT_NEAR(hi, std::max(sa, sb), tol);
  EXPECT_NEAR(box.size_O.z(), sz, tol);
}

void ExpectUpAndConsistent(const BoxModel& box) {
  const Eigen::Matrix3d R = box.X_WO.linear();
  EXPECT_GT(R.col(2).dot(Vector3d::UnitZ()), std::cos(DegToRad(1.0)));
  EXPECT_NEAR(R.determinant(), 1.0, 1e-9);
  EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-9);
  // Corner 7 is +half along every axis, corner 0 -half.
  EXPECT_LT((box.vertices_W[7] - box.X_WO * (box.size_O / 2)).norm(), 1e-12);
  EXPECT_LT((box.vertices_W[0] - box.X_WO * (-box.size_O / 2)).norm(), 1e-12);
  EXPECT_NEAR(box.vertices_W[0].z(), 0.0, 1e-3);  // resting on the table
}

const Vector3d kSize(0.06, 0.09, 0.10);

TEST(FitBox, AxisAlignedBoxThreeFacesVisible) {
  // x in [0.25, 0.31], y in [-0.04, 0.05], z in [0, 0.1]: top, front x = 0.25, side y = -0.04.
  const RangeImage img = BoxScene(0.28, 0.005, 0.0, kSize, 0.005, Sides::kFrontAndLeft);
  const std::optional<BoxModel> box = FitScene(img, 3);
  ASSERT_TRUE(box.has_value());
  // The far faces come from the outermost samples, 2.5 mm inside the edges.
  ExpectSize(*box, 0.06, 0.09, 0.10, 0.003);
  EXPECT_LT((box->X_WO.translation() - Vector3d(0.28, 0.005, 0.05)).norm(), 0.003);
  EXPECT_NEAR(YawErrorMod90Deg(*box, 0.0), 0.0, 0.5);
  ExpectUpAndConsistent(*box);
  EXPECT_EQ(box->regions.size(), 3u);
  EXPECT_EQ(box->points, 216 + 360 + 240);  // top 12x18, front 20x18, side 20x12
  // O's x is A2's normal (the front, the largest side): along W x.
  EXPECT_GT(std::abs(box->X_WO.linear().col(0).x()), 0.999);
  EXPECT_NEAR(box->size_O.x(), 0.06, 0.003);
}

TEST(FitBox, RotatedBoxRecoversYaw) {
  const double yaw_deg = 30.0;
  const RangeImage img =
      BoxScene(0.30, 0.01, DegToRad(yaw_deg), kSize, 0.0025, Sides::kFrontAndRight);
  const std::optional<BoxModel> box = FitScene(img, 3);
  ASSERT_TRUE(box.has_value());
  EXPECT_NEAR(YawErrorMod90Deg(*box, yaw_deg), 0.0, 2.0);
  ExpectSize(*box, 0.06, 0.09, 0.10, 0.003);
  EXPECT_LT((box->X_WO.translation() - Vector3d(0.30, 0.01, 0.05)).norm(), 0.003);
  ExpectUpAndConsistent(*box);
}

TEST(FitBox, TopAndOneSideUseTheEdgeVoteForBothHiddenExtents) {
  const RangeImage img = BoxScene(0.28, 0.005, 0.0, kSize, 0.0025, Sides::kFront);
  const std::optional<BoxModel> box = FitScene(img, 2);
  ASSERT_TRUE(box.has_value());
  ExpectSize(*box, 0.06, 0.09, 0.10, 0.003);
  EXPECT_LT((box->X_WO.translation() - Vector3d(0.28, 0.005, 0.05)).norm(), 0.003);
  EXPECT_EQ(box->regions.size(), 2u);
  ExpectUpAndConsistent(*box);
}

TEST(FitBox, RotatedTopAndOneSide) {
  const double yaw_deg = -20.0;
  const RangeImage img = BoxScene(0.30, -0.02, DegToRad(yaw_deg), kSize, 0.0025, Sides::kFront);
  const std::optional<BoxModel> box = FitScene(img, 2);
  ASSERT_TRUE(box.has_value());
  EXPECT_NEAR(YawErrorMod90Deg(*box, yaw_deg), 0.0, 2.0);
  ExpectSize(*box, 0.06, 0.09, 0.10, 0.003);
  EXPECT_LT((box->X_WO.translation() - Vector3d(0.30, -0.02, 0.05)).norm(), 0.003);
}

// The top's region alone (GroupObjects would remove a lone top over the table as a second floor
// only if it were lower than the table; fit the region directly).
const segment::PlaneRegion& Top(const segment::SegmentResult& s) {
  const segment::PlaneRegion* top = &s.regions[0];
  for (const auto& r : s.regions) {
    if (r.centroid_W.z() > top->centroid_W.z()) top = &r;
  }
  return *top;
}

TEST(FitBox, TopOnlyGivesTheBoxFromItsOutline) {
  // The sides edge-on to the cameras: the top's rectangle and the table give the box.
  const double yaw = DegToRad(30);
  const RangeImage img = BoxScene(0.28, 0.005, yaw, kSize, 0.0025, Sides::kNone);
  const segment::SegmentResult s = segment::SegmentPlanes(img);
  ASSERT_EQ(s.regions.size(), 2u);
  const std::optional<BoxModel> box = FitBox(s, {Top(s).id}, img);
  ASSERT_TRUE(box.has_value());
  // The outermost samples lie half a step (1.25 mm) inside each edge.
  ExpectSize(*box, 0.06, 0.09, 0.10, 0.003);
  EXPECT_NEAR(YawErrorMod90Deg(*box, 30.0), 0.0, 0.5);
  EXPECT_LT((box->X_WO.translation() - Vector3d(0.28, 0.005, 0.05)).norm(), 0.002);
  ExpectUpAndConsistent(*box);
  EXPECT_EQ(box->regions, std::vector<int>{Top(s).id});
}

TEST(FitBox, SmallOrNonRectangularTopAloneIsNoBox) {
  // 10 x 15 cells: under min_top_only_cells.
  const RangeImage small = BoxScene(0.28, 0.005, 0.0, kSize, 0.006, Sides::kNone);
  const segment::SegmentResult s1 = segment::SegmentPlanes(small);
  EXPECT_FALSE(FitBox(s1, {Top(s1).id}, small).has_value());
  // A triangle of a top (half of it cut away along its diagonal): its hull fills half of the
  // rectangle around it.
  RangeImage triangle = BoxScene(0.28, 0.005, 0.0, kSize, 0.0025, Sides::kNone);
  const int nx = 24, ny = 36, cf = 5 + nx;
  for (int r = 0; r < nx; ++r) {
    for (int c = 0; c < ny; ++c) {
      if (c * nx > r * ny) triangle.at(r, cf + c).valid = false;
    }
  }
  const segment::SegmentResult s2 = segment::SegmentPlanes(triangle);
  EXPECT_GE(Top(s2).cells, 200);
  EXPECT_FALSE(FitBox(s2, {Top(s2).id}, triangle).has_value());
}

TEST(FitBox, NoisyBoxWithinFourMillimetres) {
  RangeImage img = BoxScene(0.28, 0.005, 0.0, kSize, 0.005, Sides::kFrontAndLeft);
  AddNoise(&img, 0.001, 42);
  const std::optional<BoxModel> box = FitScene(img, 3);
  ASSERT_TRUE(box.has_value());
  ExpectSize(*box, 0.06, 0.09, 0.10, 0.004);
  EXPECT_LT((box->X_WO.translation() - Vector3d(0.28, 0.005, 0.05)).norm(), 0.004);
  EXPECT_NEAR(YawErrorMod90Deg(*box, 0.0), 0.0, 2.0);
}

TEST(FitBox, TooFewCellsOrUnknownRegionsIsNoBox) {
  const RangeImage img = BoxScene(0.28, 0.005, 0.0, kSize, 0.005, Sides::kFrontAndLeft);
  const segment::SegmentResult s = segment::SegmentPlanes(img);
  const segment::Grouping g = segment::GroupObjects(s, img);
  ASSERT_EQ(g.objects.size(), 1u);
  BoxFitConfig config;
  config.min_face_cells = 1000;  // more than any face has
  EXPECT_FALSE(FitBox(s, g.objects[0], img, config).has_value());
  EXPECT_FALSE(FitBox(s, {}, img).has_value());
  EXPECT_FALSE(FitBox(s, {12345}, img).has_value());
  // The table alone (a horizontal region, no side): no box.
  EXPECT_FALSE(FitBox(s, g.floor_or_wall, img).has_value());
}

TEST(FitBoxes, CountsFailures) {
  RangeImage img = BoxScene(0.28, 0.005, 0.0, kSize, 0.005, Sides::kFrontAndLeft);
  const segment::SegmentResult s = segment::SegmentPlanes(img);
  segment::Grouping g = segment::GroupObjects(s, img);
  ASSERT_EQ(g.objects.size(), 1u);
  g.objects.push_back(g.floor_or_wall);  // the table as an "object": fails
  int failed = -1;
  const std::vector<BoxModel> boxes = FitBoxes(s, g, img, &failed);
  EXPECT_EQ(boxes.size(), 1u);
  EXPECT_EQ(failed, 1);
  EXPECT_EQ(FitBoxes(s, g, img).size(), 1u);  // failed may be null
}

}  // namespace
}  // namespace hgrasp::model
