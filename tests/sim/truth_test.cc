// Ground-truth surface distance: hand-computed points near the table, the wall and the boxes; and
// the true face under a point, from the label images.

#include "sim/truth.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "sim/stereo_rig.h"
#include "tests/sim/sim_test_util.h"

namespace hgrasp::sim {
namespace {

TEST(DistanceToBoxSurfaceTest, OutsideInsideEdgeAndCorner) {
  Pose3 X_WO = Pose3::Identity();
  X_WO.translation() << 1.0, 2.0, 3.0;
  const Eigen::Vector3d size(0.2, 0.4, 0.6);  // half 0.1, 0.2, 0.3
  const Eigen::Vector3d c = X_WO.translation();
  EXPECT_NEAR(DistanceToBoxSurface(X_WO, size, c + Eigen::Vector3d(0.15, 0, 0)), 0.05, 1e-12);
  EXPECT_NEAR(DistanceToBoxSurface(X_WO, size, c + Eigen::Vector3d(0, -0.2, 0)), 0.0, 1e-12);
  // Inside: the nearest face.
  EXPECT_NEAR(DistanceToBoxSurface(X_WO, size, c), 0.1, 1e-12);
  EXPECT_NEAR(DistanceToBoxSurface(X_WO, size, c + Eigen::Vector3d(0.05, 0.19, -0.1)), 0.01, 1e-12);
  // Beyond an edge and a corner.
  EXPECT_NEAR(DistanceToBoxSurface(X_WO, size, c + Eigen::Vector3d(0.13, 0.24, 0)), 0.05, 1e-12);
  EXPECT_NEAR(DistanceToBoxSurface(X_WO, size, c + Eigen::Vector3d(-0.12, 0.23, -0.36)),
              std::sqrt(0.02 * 0.02 + 0.03 * 0.03 + 0.06 * 0.06), 1e-12);
}

// Box a: 6 x 8 x 10 cm, axis-aligned at (0.30, 0.10). Box b: 10 x 5 x 6 cm at (0.30, -0.12),
// yaw 30 deg. A wall at x = 0.8.
class TruthDistanceTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    world_ = std::make_unique<World>(testing::ScenarioFromYaml(R"(name: truth
wall: {x: 0.8}
objects:
  - {name: a, shape: box, size: [0.06, 0.08, 0.10], position: [0.30, 0.10], color: [1, 0, 0]}
  - {name: b, shape: box, size: [0.10, 0.05, 0.06], position: [0.30, -0.12], yaw_deg: 30, color: [0, 0, 1]}
)"));
  }
  static void TearDownTestSuite() { world_.reset(); }
  static Pose3 ObjectPose(int i) { return world_->BodyPose(world_->objects()[i].body); }
  static double D(const Eigen::Vector3d& p_W) { return DistanceToTrueSurface(*world_, p_W); }
  static std::unique_ptr<World> world_;
};
std::unique_ptr<World> TruthDistanceTest::world_;

TEST_F(TruthDistanceTest, ObjectsRestWhereTheScenarioPutsThem) {
  // The hand-computed cases below rely on the settled poses being the nominal ones. MuJoCo's soft
  // contact lets a resting box sink about 0.2 mm into the table.
  for (int i = 0; i < 2; ++i) {
    const Pose3 X_WO = ObjectPose(i);
    const Pose3 nominal = world_->objects()[i].spec.X_WO();
    EXPECT_LT((X_WO.translation() - nominal.translation()).norm(), 5e-4)
        << i << ": " << (X_WO.translation() - nominal.translation()).transpose();
    EXPECT_LT((X_WO.linear() - nominal.linear()).norm(), 1e-3) << i;
  }
}

TEST_F(TruthDistanceTest, AboveTheTableFarFromEverything) {
  EXPECT_NEAR(D({0.60, 0.40, 0.01}), 0.01, 1e-12);
  EXPECT_NEAR(D({0.60, 0.40, 0.0}), 0.0, 1e-12);
  // Beside the table's near edge (x = 0.08), level with its top, and beyond its corner edge.
  EXPECT_NEAR(D({0.05, 0.40, -0.02}), 0.03, 1e-12);
  EXPECT_NEAR(D({0.04, 0.40, 0.03}), 0.05, 1e-12);
}

TEST_F(TruthDistanceTest, InFrontOfTheWall) {
  EXPECT_NEAR(D({0.70, 0.0, 0.5}), 0.10, 1e-12);
  EXPECT_NEAR(D({0.79, 0.3, 0.2}), 0.01, 1e-12);
}

TEST_F(TruthDistanceTest, NoWallNoWallDistance) {
  World empty(testing::ScenarioFromYaml(testing::kEmptyScene));
  EXPECT_NEAR(DistanceToTrueSurface(empty, {0.79, 0.3, 0.2}), 0.2, 1e-12);
}

TEST_F(TruthDistanceTest, InFrontOfABoxFace) {
  const Pose3 X_WO = ObjectPose(0);  // half sizes 0.03, 0.04, 0.05
  EXPECT_NEAR(D(X_WO * Eigen::Vector3d(0.05, 0.0, 0.0)), 0.02, 1e-9);
  EXPECT_NEAR(D(X_WO * Eigen::Vector3d(-0.03, 0.01, 0.01)), 0.0, 1e-9);
  EXPECT_NEAR(D(X_WO * Eigen::Vector3d(0.0, 0.0, 0.08)), 0.03, 1e-9);  // above the top
  // Nominally: 2 cm in front of the face x = 0.33.
  EXPECT_NEAR(D({0.35, 0.10, 0.05}), 0.02, 1e-4);
}

TEST_F(TruthDistanceTest, InsideABoxNearAFace) {
  const Pose3 X_WO = ObjectPose(0);
  EXPECT_NEAR(D(X_WO * Eigen::Vector3d(0.025, 0.01, 0.0)), 0.005, 1e-9);
  EXPECT_NEAR(D(X_WO * Eigen::Vector3d(0.0, -0.037, 0.01)), 0.003, 1e-9);
  EXPECT_NEAR(D(X_WO.translation()), 0.03, 1e-9);  // the centre: the x faces are nearest
}

TEST_F(TruthDistanceTest, NearABoxEdge) {
  const Pose3 X_WO = ObjectPose(0);
  // Beyond the vertical edge at (+0.03, +0.04): 1 cm out in x, 2 cm out in y.
  EXPECT_NEAR(D(X_WO * Eigen::Vector3d(0.04, 0.06, 0.02)), std::sqrt(0.01 * 0.01 + 0.02 * 0.02),
              1e-9);
  // Beyond the top edge at x = -0.03, z = +0.05.
  EXPECT_NEAR(D(X_WO * Eigen::Vector3d(-0.06, 0.0, 0.09)), 0.05, 1e-9);
}

TEST_F(TruthDistanceTest, RotatedBox) {
  // Box b's +x face, 1.5 cm out along its normal (cos 30, sin 30, 0), computed by hand.
  const double c30 = std::cos(DegToRad(30)), s30 = std::sin(DegToRad(30));
  const Eigen::Vector3d centre(0.30, -0.12, 0.03);
  EXPECT_NEAR(D(centre + 0.065 * Eigen::Vector3d(c30, s30, 0)), 0.015, 2e-4);
  // 1 cm beyond the +y face (normal (-sin 30, cos 30, 0)), 1 cm above mid-height.
  EXPECT_NEAR(D(centre + 0.035 * Eigen::Vector3d(-s30, c30, 0) + Eigen::Vector3d(0, 0, 0.01)), 0.01,
              2e-4);
  // Exactly, at the settled pose: beyond the edge (+x, -y) in the box frame, and inside.
  const Pose3 X_WO = ObjectPose(1);  // half sizes 0.05, 0.025, 0.03
  EXPECT_NEAR(D(X_WO * Eigen::Vector3d(0.053, -0.029, 0.0)), 0.005, 1e-9);
  EXPECT_NEAR(D(X_WO * Eigen::Vector3d(0.01, 0.02, 0.0)), 0.005, 1e-9);
}

TEST(NearestBoxFaceTest, FacesInTheBoxFrame) {
  Pose3 X_WO = Pose3::Identity();
  X_WO.linear() = RotZ(DegToRad(90));  // O x = W y, O y = W -x
  X_WO.translation() << 1.0, 2.0, 3.0;
  const Eigen::Vector3d size(0.2, 0.4, 0.6);  // half 0.1, 0.2, 0.3
  // Outside each face, in O.
  EXPECT_EQ(NearestBoxFace(X_WO, size, X_WO * Eigen::Vector3d(0.15, 0.0, 0.0)), 0);
  EXPECT_EQ(NearestBoxFace(X_WO, size, X_WO * Eigen::Vector3d(-0.12, 0.1, 0.2)), 1);
  EXPECT_EQ(NearestBoxFace(X_WO, size, X_WO * Eigen::Vector3d(0.05, 0.25, 0.0)), 2);
  EXPECT_EQ(NearestBoxFace(X_WO, size, X_WO * Eigen::Vector3d(0.0, -0.21, -0.29)), 3);
  EXPECT_EQ(NearestBoxFace(X_WO, size, X_WO * Eigen::Vector3d(0.0, 0.0, 0.31)), 4);
  EXPECT_EQ(NearestBoxFace(X_WO, size, X_WO * Eigen::Vector3d(0.09, 0.19, -0.35)), 5);
  // In W: the point beyond W +y lies beyond O +x.
  EXPECT_EQ(NearestBoxFace(X_WO, size, Eigen::Vector3d(1.0, 2.15, 3.0)), 0);
  EXPECT_EQ(NearestBoxFace(X_WO, size, Eigen::Vector3d(1.25, 2.0, 3.0)), 3);
  // Inside: the nearest face.
  EXPECT_EQ(NearestBoxFace(X_WO, size, X_WO * Eigen::Vector3d(0.0, 0.0, -0.25)), 5);
  EXPECT_EQ(NearestBoxFace(X_WO, size, X_WO * Eigen::Vector3d(0.0, 0.19, 0.0)), 2);
  // Beyond an edge both faces are equally near: the one whose plane the point lies farther
  // beyond.
  EXPECT_EQ(NearestBoxFace(X_WO, size, X_WO * Eigen::Vector3d(0.11, 0.0, 0.35)), 4);
  EXPECT_EQ(NearestBoxFace(X_WO, size, X_WO * Eigen::Vector3d(0.16, 0.0, 0.31)), 0);
}

// Box a: 6 x 8 x 10 cm, axis-aligned at (0.30, -0.13): the cameras (about 0.6 m up near W x = 0,
// y = +-0.07) see its top, its -x face (towards the robot) and its +y face (the plane y = -0.09);
// its +x and -y faces are turned away. Box b: 4 x 10 x 6 cm at (0.30, 0.12), yaw 90 deg (O x = W y,
// O y = W -x): its face towards the robot is O +y and its face towards W -y is O -x. A wall at x =
// 0.7.
class TrueFaceLabelsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    world_ = std::make_unique<World>(testing::ScenarioFromYaml(R"(name: faces
wall: {x: 0.7}
objects:
  - {name: a, shape: box, size: [0.06, 0.08, 0.10], position: [0.30, -0.13], color: [0.9, 0.2, 0.2]}
  - {name: b, shape: box, size: [0.04, 0.10, 0.06], position: [0.30, 0.12], yaw_deg: 90, color: [0.2, 0.2, 0.9]}
)"));
    rig_ = std::make_unique<StereoRig>(world_.get());
  }
  static void TearDownTestSuite() {
    rig_.reset();
    world_.reset();
  }
  static Pose3 ObjectPose(int i) { return world_->BodyPose(world_->objects()[i].body); }
  static int Code(int camera, const Eigen::Vector3d& p_W, double tol_m = 0.005) {
    return TrueFaceLabels(*world_, rig_.get(), camera, {p_W}, tol_m).at(0);
  }
  // The geom id the camera's label image shows at p_W's nearest pixel (-1 outside the image).
  static int LabelAt(int camera, const Eigen::Vector3d& p_W) {
    const CameraView& view = rig_->View(camera);
    const auto uv = view.camera.Project(view.X_WC.inverse() * p_W);
    if (!uv) return -1;
    const int c = static_cast<int>(std::lround(uv->x())),
              r = static_cast<int>(std::lround(uv->y()));
    if (c < 0 || r < 0 || c >= view.images.label.cols || r >= view.images.label.rows) return -1;
    return view.images.label.at<int>(r, c);
  }
  static std::unique_ptr<World> world_;
  static std::unique_ptr<StereoRig> rig_;
};
std::unique_ptr<World> TrueFaceLabelsTest::world_;
std::unique_ptr<StereoRig> TrueFaceLabelsTest::rig_;

TEST_F(TrueFaceLabelsTest, CodesAreLaidOutAsDocumented) {
  EXPECT_EQ(TruthFaceCode(0, 0), 2);
  EXPECT_EQ(TruthFaceCode(0, 5), 7);
  EXPECT_EQ(TruthFaceCode(1, 4), 12);
  EXPECT_TRUE(TrueFaceLabels(*world_, rig_.get(), kLeft, {}).empty());
}

TEST_F(TrueFaceLabelsTest, VisibleFacesOfAnAxisAlignedBox) {
  const Pose3 X_WO = ObjectPose(0);  // half sizes 0.03, 0.04, 0.05
  for (int cam : {kLeft, kRight}) {
    SCOPED_TRACE(cam);
    EXPECT_EQ(Code(cam, X_WO * Eigen::Vector3d(0.01, 0.02, 0.05)), TruthFaceCode(0, 4));  // top
    EXPECT_EQ(Code(cam, X_WO * Eigen::Vector3d(-0.03, 0.01, 0.0)), TruthFaceCode(0, 1));  // -x
    EXPECT_EQ(Code(cam, X_WO * Eigen::Vector3d(0.0, 0.04, -0.01)), TruthFaceCode(0, 2));  // +y
    // Off the surface within the tolerance: 3 mm in front of -x, 4 mm inside the top.
    EXPECT_EQ(Code(cam, X_WO * Eigen::Vector3d(-0.033, -0.01, 0.02)), TruthFaceCode(0, 1));
    EXPECT_EQ(Code(cam, X_WO * Eigen::Vector3d(0.0, -0.01, 0.046)), TruthFaceCode(0, 4));
    // Nominal coordinates, worked out from the scenario alone (the box settles within 0.5 mm).
    EXPECT_EQ(Code(cam, {0.30, -0.13, 0.10}), TruthFaceCode(0, 4));
    EXPECT_EQ(Code(cam, {0.27, -0.14, 0.05}), TruthFaceCode(0, 1));
    EXPECT_EQ(Code(cam, {0.31, -0.09, 0.03}), TruthFaceCode(0, 2));
  }
}

TEST_F(TrueFaceLabelsTest, RotatedBoxFacesAreNamedInItsOwnFrame) {
  const Pose3 X_WO = ObjectPose(1);  // half sizes 0.02, 0.05, 0.03 along O x, y, z
  for (int cam : {kLeft, kRight}) {
    SCOPED_TRACE(cam);
    EXPECT_EQ(Code(cam, {0.30, 0.12, 0.06}), TruthFaceCode(1, 4));   // top
    EXPECT_EQ(Code(cam, {0.25, 0.125, 0.03}), TruthFaceCode(1, 2));  // W -x: O +y
    EXPECT_EQ(Code(cam, {0.31, 0.10, 0.02}), TruthFaceCode(1, 1));   // W -y: O -x
    EXPECT_EQ(Code(cam, X_WO * Eigen::Vector3d(0.0, 0.05, 0.01)), TruthFaceCode(1, 2));
  }
}

TEST_F(TrueFaceLabelsTest, TableAndWall) {
  for (int cam : {kLeft, kRight}) {
    SCOPED_TRACE(cam);
    EXPECT_EQ(Code(cam, {0.30, 0.0, 0.0}), kTruthTable);
    EXPECT_EQ(Code(cam, {0.22, -0.13, 0.004}), kTruthTable);
    EXPECT_EQ(Code(cam, {0.40, 0.02, -0.003}), kTruthTable);
    ASSERT_EQ(LabelAt(cam, {0.70, 0.0, 0.03}), world_->Id(mjOBJ_GEOM, "wall"));
    EXPECT_EQ(Code(cam, {0.70, 0.0, 0.03}), kTruthWall);
    EXPECT_EQ(Code(cam, {0.698, 0.05, 0.02}), kTruthWall);
  }
}

TEST_F(TrueFaceLabelsTest, OffEverySurfaceIsNone) {
  for (int cam : {kLeft, kRight}) {
    SCOPED_TRACE(cam);
    EXPECT_EQ(Code(cam, {0.30, 0.0, 0.05}), kTruthNone);   // mid-air above the table
    EXPECT_EQ(Code(cam, {0.30, 0.0, 0.006}), kTruthNone);  // just beyond the tolerance
    EXPECT_EQ(Code(cam, {0.30, 0.0, 0.006}, 0.01), kTruthTable);
    EXPECT_EQ(Code(cam, ObjectPose(0) * Eigen::Vector3d(-0.04, 0.0, 0.0)), kTruthNone);  // 1 cm
    EXPECT_EQ(Code(cam, {-1.0, 0.0, 0.6}), kTruthNone);  // behind the cameras
    EXPECT_EQ(Code(cam, {0.30, 0.9, 0.0}), kTruthNone);  // outside the image
  }
}

TEST_F(TrueFaceLabelsTest, HiddenFacesAndOccludedPointsAreNeverLabelled) {
  const Pose3 X_WO = ObjectPose(0);
  const int a = world_->objects()[0].geom;
  for (int cam : {kLeft, kRight}) {
    SCOPED_TRACE(cam);
    // The back (+x) and -y faces project onto the box's own front in the label image.
    const Eigen::Vector3d back = X_WO * Eigen::Vector3d(0.03, 0.0, 0.0);
    const Eigen::Vector3d side = X_WO * Eigen::Vector3d(0.0, -0.04, 0.01);
    ASSERT_EQ(LabelAt(cam, back), a);
    ASSERT_EQ(LabelAt(cam, side), a);
    const std::vector<int> codes = TrueFaceLabels(*world_, rig_.get(), cam, {back, side});
    EXPECT_NE(codes[0], TruthFaceCode(0, 0));
    EXPECT_NE(codes[1], TruthFaceCode(0, 3));
    EXPECT_EQ(codes[0], kTruthNone);
    EXPECT_EQ(codes[1], kTruthNone);
    // The table just behind the box is hidden by it.
    ASSERT_EQ(LabelAt(cam, {0.345, -0.13, 0.0}), a);
    EXPECT_EQ(Code(cam, {0.345, -0.13, 0.0}), kTruthNone);
  }
}

// Every surface point the camera renders of box a gets one of its visible faces' codes: the face
// whose plane the point lies on, and away from the edges (where the normals rendered from depth
// blend neighbouring faces) the face whose normal was rendered.
TEST_F(TrueFaceLabelsTest, RenderedPointsOfTheBoxGetTheirFace) {
  const Pose3 X_WO = ObjectPose(0);
  const Eigen::Vector3d h = 0.5 * world_->objects()[0].spec.size_O;
  const int a = world_->objects()[0].geom;
  constexpr double kEdgeMargin = 0.012;  // m: a few pixels at 0.6 m, more on grazing faces
  for (int cam : {kLeft, kRight}) {
    SCOPED_TRACE(cam);
    const CameraView& view = rig_->View(cam);
    std::vector<Eigen::Vector3d> points, normals;
    for (int r = 0; r < view.images.label.rows; ++r) {
      for (int c = 0; c < view.images.label.cols; ++c) {
        if (view.images.label.at<int>(r, c) != a) continue;
        const cv::Vec3d p = view.points_W.at<cv::Vec3d>(r, c);
        const cv::Vec3d n = view.normals_W.at<cv::Vec3d>(r, c);
        points.emplace_back(p[0], p[1], p[2]);
        normals.emplace_back(n[0], n[1], n[2]);
      }
    }
    ASSERT_GT(points.size(), 300u);
    const std::vector<int> codes = TrueFaceLabels(*world_, rig_.get(), cam, points);
    int none = 0, interior = 0, per_face[6] = {0, 0, 0, 0, 0, 0};
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (codes[i] == kTruthNone) {
        ++none;
        continue;
      }
      const int face = codes[i] - TruthFaceCode(0, 0);
      ASSERT_GE(face, 0);
      ASSERT_LT(face, 6);
      ++per_face[face];
      const int axis = face / 2;
      const double sign = face % 2 == 0 ? 1.0 : -1.0;
      const Eigen::Vector3d p_O = X_WO.inverse() * points[i];
      EXPECT_LT(std::abs(sign * p_O[axis] - h[axis]), 1e-3)
          << "face " << face << " at " << p_O.transpose();
      bool inside_edges = true;
      for (int k = 0; k < 3; ++k) {
        if (k != axis) inside_edges = inside_edges && std::abs(p_O[k]) < h[k] - kEdgeMargin;
      }
      if (!inside_edges) continue;
      ++interior;
      const Eigen::Vector3d n_W = sign * X_WO.linear().col(axis);
      EXPECT_GT(n_W.dot(normals[i]), 0.98) << "face " << face << " at " << p_O.transpose();
    }
    EXPECT_LT(none, static_cast<int>(points.size()) / 100);
    EXPECT_EQ(per_face[0] + per_face[3] + per_face[5], 0);  // +x, -y, bottom: hidden
    EXPECT_GT(per_face[1], 50);
    EXPECT_GT(per_face[2], 20);
    EXPECT_GT(per_face[4], 50);
    EXPECT_GT(interior, static_cast<int>(points.size()) / 3);
    std::printf(
        "camera %d: box a %zu pixels, faces -x %d +y %d top %d, none %d, %d checked "
        "against rendered normals\n",
        cam, points.size(), per_face[1], per_face[2], per_face[4], none, interior);
  }
}

}  // namespace
}  // namespace hgrasp::sim
