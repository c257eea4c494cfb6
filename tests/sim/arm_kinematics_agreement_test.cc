// The pipeline's arm kinematics (robot::ArmKinematics, from the URDF) against MuJoCo's own
// frames of the MJCF model: the gripper pose for 1000 random configurations of each arm.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <random>

#include "common/paths.h"
#include "robot/arm_kinematics.h"
#include "sim/sim_devices.h"
#include "tests/sim/sim_test_util.h"

namespace hgrasp::sim {
namespace {

TEST(ArmKinematicsAgreement, ForwardKinematicsMatchesMuJoCoWithin1e6) {
  const robot::KinematicTree tree =
      robot::KinematicTree::FromUrdfFile(ResolveDataPath("models/humanoid.urdf"));
  World world(testing::ScenarioFromYaml(testing::kEmptyScene));
  std::mt19937_64 rng(260);
  for (const device::Side side : {device::Side::kLeft, device::Side::kRight}) {
    const robot::ArmKinematics arm =
        robot::ArmKinematics::FromTree(tree, std::string(device::ToString(side)));
    double worst_m = 0, worst_rad = 0;
    for (int n = 0; n < 1000; ++n) {
      device::Joint6 q;
      for (int i = 0; i < 6; ++i) {
        q[i] = std::uniform_real_distribution<double>(arm.lower()[i], arm.upper()[i])(rng);
      }
      const Pose3 ours = arm.Forward(q), mujoco = ArmForwardKinematics(world, side, q);
      worst_m = std::max(worst_m, (ours.translation() - mujoco.translation()).norm());
      worst_rad = std::max(worst_rad,
                           Eigen::AngleAxisd(ours.linear().transpose() * mujoco.linear()).angle());
    }
    std::printf("%s arm, 1000 configurations: worst %.2e m, %.2e rad\n",
                std::string(device::ToString(side)).c_str(), worst_m, worst_rad);
    EXPECT_LT(worst_m, 1e-6);
    EXPECT_LT(worst_rad, 1e-6);
  }
}

}  // namespace
}  // namespace hgrasp::sim
