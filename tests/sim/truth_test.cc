// Ground-truth surface distance: hand-computed points near the table, the wall and the boxes.

#include "sim/truth.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

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

}  // namespace
}  // namespace hgrasp::sim
