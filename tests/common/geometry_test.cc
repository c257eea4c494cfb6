#include "common/geometry.h"

#include <gtest/gtest.h>

#include "common/error.h"

namespace hgrasp {
namespace {

TEST(PlaneTest, SignedDistanceOfAPlaneAtKnownOffset) {
  const Plane p{Eigen::Vector3d::UnitZ(), -0.5};  // z = 0.5
  EXPECT_DOUBLE_EQ(p.SignedDistance({1, 2, 0.75}), 0.25);
  EXPECT_DOUBLE_EQ(p.SignedDistance({0, 0, 0}), -0.5);
}

TEST(PlaneTest, TransformedByMovesThePlaneWithItsFrame) {
  const Plane p_B{Eigen::Vector3d::UnitX(), -1.0};  // x_B = 1
  Pose3 X_AB = Pose3::Identity();
  X_AB.linear() = RotZ(kPi / 2);  // B's x is A's y
  X_AB.translation() = Eigen::Vector3d(0, 2, 0);
  const Plane p_A = p_B.TransformedBy(X_AB);  // y_A = 3
  EXPECT_NEAR(p_A.n.y(), 1.0, 1e-15);
  EXPECT_NEAR(p_A.SignedDistance({5, 3, -2}), 0.0, 1e-12);
  EXPECT_NEAR(p_A.SignedDistance({0, 4, 0}), 1.0, 1e-12);
}

TEST(PlaneTest, ReflectPointAndPlane) {
  const Plane mirror{Eigen::Vector3d::UnitX(), -1.0};  // x = 1
  EXPECT_TRUE(mirror.Reflect(Eigen::Vector3d(0, 2, 3)).isApprox(Eigen::Vector3d(2, 2, 3)));
  // The plane y = x mirrored in x = 1 is y = 2 - x.
  const Plane diagonal{Eigen::Vector3d(-1, 1, 0).normalized(), 0.0};
  const Plane image = mirror.Reflect(diagonal);
  EXPECT_NEAR(image.SignedDistance({0, 2, 0}), 0.0, 1e-12);
  EXPECT_NEAR(image.SignedDistance({2, 0, 5}), 0.0, 1e-12);
}

TEST(InputErrorTest, MessageNamesFileFieldValueAndExpectation) {
  const InputError e("a.yaml:3", "objects[0].size", "-1", "positive edge lengths");
  EXPECT_STREQ(e.what(), "a.yaml:3: objects[0].size: got '-1'; expected positive edge lengths");
  const InputError missing("a.yaml", "name", "", "a scenario name");
  EXPECT_STREQ(missing.what(), "a.yaml: name: missing or empty; expected a scenario name");
}

}  // namespace
}  // namespace hgrasp
