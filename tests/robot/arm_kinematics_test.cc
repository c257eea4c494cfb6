// The Puma arms' kinematics from models/humanoid.urdf: the closed-form inverse against the
// forward kinematics over random configurations, the Jacobian against finite differences.

#include "robot/arm_kinematics.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <random>
#include <string>

#include "common/error.h"
#include "common/paths.h"

namespace hgrasp::robot {
namespace {

const KinematicTree& Tree() {
  static const KinematicTree tree =
      KinematicTree::FromUrdfFile(ResolveDataPath("models/humanoid.urdf"));
  return tree;
}

double AngleBetween(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle();
}

device::Joint6 RandomWithinLimits(const ArmKinematics& arm, std::mt19937_64* rng) {
  device::Joint6 q;
  for (int i = 0; i < 6; ++i) {
    const double lo = std::max(arm.lower()[i], -kPi), hi = std::min(arm.upper()[i], kPi);
    q[i] = std::uniform_real_distribution<double>(lo, hi)(*rng);
  }
  return q;
}

class ArmKinematicsTest : public ::testing::TestWithParam<const char*> {};

TEST_P(ArmKinematicsTest, InverseRoundTripOverTenThousandPoses) {
  const ArmKinematics arm = ArmKinematics::FromTree(Tree(), GetParam());
  std::mt19937_64 rng(2002);
  double worst_m = 0, worst_rad = 0, worst_found = 0;
  size_t solutions = 0, eight = 0;
  for (int n = 0; n < 10000; ++n) {
    const device::Joint6 q = RandomWithinLimits(arm, &rng);
    const Pose3 X = arm.Forward(q);
    const std::vector<ArmIkSolution> sols = arm.Inverse(X);
    ASSERT_FALSE(sols.empty()) << q.transpose();
    ASSERT_LE(sols.size(), 8u);
    solutions += sols.size();
    eight += sols.size() == 8;
    double nearest = 1e9;
    for (const ArmIkSolution& s : sols) {
      const Pose3 Y = arm.Forward(s.q);
      worst_m = std::max(worst_m, (Y.translation() - X.translation()).norm());
      worst_rad = std::max(worst_rad, AngleBetween(Y.linear(), X.linear()));
      device::Joint6 d = s.q - q;
      for (int i = 0; i < 6; ++i) d[i] = std::remainder(d[i], 2 * kPi);
      nearest = std::min(nearest, d.cwiseAbs().maxCoeff());
    }
    worst_found = std::max(worst_found, nearest);
  }
  std::printf(
      "%s arm, 10000 poses: %.2f solutions per pose (%zu with 8); worst round trip %.2e m, "
      "%.2e rad; the generating configuration found within %.2e rad\n",
      GetParam(), solutions / 10000.0, eight, worst_m, worst_rad, worst_found);
  EXPECT_LT(worst_m, 1e-9);
  EXPECT_LT(worst_rad, 1e-9);
  EXPECT_LT(worst_found, 1e-6);
}

TEST_P(ArmKinematicsTest, JacobianMatchesFiniteDifferences) {
  const ArmKinematics arm = ArmKinematics::FromTree(Tree(), GetParam());
  std::mt19937_64 rng(7);
  double worst = 0;
  for (int n = 0; n < 100; ++n) {
    const device::Joint6 q = RandomWithinLimits(arm, &rng);
    const Eigen::Matrix<double, 6, 6> J = arm.Jacobian(q);
    const Pose3 X = arm.Forward(q);
    constexpr double h = 1e-6;
    for (int i = 0; i < 6; ++i) {
      device::Joint6 qp = q, qm = q;
      qp[i] += h;
      qm[i] -= h;
      const Pose3 P = arm.Forward(qp), M = arm.Forward(qm);
      const Eigen::Vector3d v = (P.translation() - M.translation()) / (2 * h);
      // Angular velocity: the skew part of dR R^T.
      const Eigen::Matrix3d W = (P.linear() - M.linear()) / (2 * h) * X.linear().transpose();
      const Eigen::Vector3d w(W(2, 1), W(0, 2), W(1, 0));
      worst = std::max({worst, (J.block<3, 1>(0, i) - v).norm(), (J.block<3, 1>(3, i) - w).norm()});
    }
  }
  std::printf("%s arm: Jacobian against central differences, worst %.2e\n", GetParam(), worst);
  EXPECT_LT(worst, 1e-7);
}

TEST_P(ArmKinematicsTest, OutOfReachHasNoSolution) {
  const ArmKinematics arm = ArmKinematics::FromTree(Tree(), GetParam());
  Pose3 X = arm.Forward(device::Joint6::Zero());
  X.translation() = arm.shoulder_point() + Eigen::Vector3d(1.0, 0.0, 0.0);  // 1 m away
  EXPECT_TRUE(arm.Inverse(X).empty());
}

TEST_P(ArmKinematicsTest, LimitsFromTheUrdf) {
  const ArmKinematics arm = ArmKinematics::FromTree(Tree(), GetParam());
  const std::string j1 = std::string(GetParam()) + "_j1";
  EXPECT_EQ(arm.lower()[0], Tree().Limits(j1).lower);
  EXPECT_EQ(arm.upper()[0], Tree().Limits(j1).upper);
  device::Joint6 q = device::Joint6::Zero();
  EXPECT_TRUE(arm.WithinLimits(q));
  q[0] = arm.upper()[0] + 1e-3;
  EXPECT_FALSE(arm.WithinLimits(q));
}

INSTANTIATE_TEST_SUITE_P(Arms, ArmKinematicsTest, ::testing::Values("left", "right"));

// The capsules move with their links: each end, taken into its link's frame at q = 0, is where
// the tree's own forward kinematics puts it at any q. The forearm tube is the MJCF's capsule
// (models/humanoid.xml: fromto 0 0 -0.0635 0 0.17 -0.0635 in link 3, radius 0.028).
TEST_P(ArmKinematicsTest, LinkCapsulesMoveWithTheirLinks) {
  const std::string side = GetParam();
  const ArmKinematics arm = ArmKinematics::FromTree(Tree(), side);
  const device::Joint6 zero = device::Joint6::Zero();
  const std::vector<Capsule> at_zero = arm.LinkCapsules(zero);
  ASSERT_GE(at_zero.size(), 6u);
  const Pose3 X_WL3 = Tree().LinkPose(side + "_link3", {});
  int forearms = 0;
  const Eigen::Vector3d elbow(0, 0, -0.0635), wrist(0, 0.17, -0.0635);
  for (const Capsule& c : at_zero) {
    const Eigen::Vector3d a = X_WL3.inverse() * c.a, b = X_WL3.inverse() * c.b;
    const bool ends = ((a - elbow).norm() < 1e-9 && (b - wrist).norm() < 1e-9) ||
                      ((b - elbow).norm() < 1e-9 && (a - wrist).norm() < 1e-9);
    if (ends && std::abs(c.radius - 0.028) < 1e-12) ++forearms;
  }
  EXPECT_EQ(forearms, 1);
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 50; ++trial) {
    const device::Joint6 q = RandomWithinLimits(arm, &rng);
    KinematicTree::JointValues values;
    for (int i = 0; i < 6; ++i) values[side + "_j" + std::to_string(i + 1)] = q[i];
    const std::vector<Capsule> moved = arm.LinkCapsules(q);
    ASSERT_EQ(moved.size(), at_zero.size());
    // Each capsule belongs to one link: the one whose frame carries both its ends.
    for (size_t k = 0; k < moved.size(); ++k) {
      bool carried = false;
      for (int link = 1; link <= 6 && !carried; ++link) {
        const std::string name = side + "_link" + std::to_string(link);
        const Pose3 X = Tree().LinkPose(name, values) * Tree().LinkPose(name, {}).inverse();
        carried = (X * at_zero[k].a - moved[k].a).norm() < 1e-9 &&
                  (X * at_zero[k].b - moved[k].b).norm() < 1e-9;
      }
      EXPECT_TRUE(carried) << "capsule " << k << " trial " << trial;
    }
  }
}

TEST(ArmKinematics, UnknownSideThrows) {
  EXPECT_THROW(ArmKinematics::FromTree(Tree(), "middle"), hgrasp::InputError);
}

}  // namespace
}  // namespace hgrasp::robot
