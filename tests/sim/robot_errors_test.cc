// The twin's robot is not its model (sim/robot_errors.h): the errors drawn from the scenario's
// seed and block, and the joints, links and controllers of a World built with them.
#include "sim/robot_errors.h"

#include <gtest/gtest.h>

#include <cmath>

#include "sim/sim_devices.h"
#include "tests/sim/sim_test_util.h"
#include "tests/support/status.h"

namespace hgrasp::sim {
namespace {

using device::Side;

Scenario Empty(const std::string& errors_yaml = "", std::uint64_t seed = 7) {
  return testing::ScenarioFromYaml("name: empty\nseed: " + std::to_string(seed) +
                                   "\nobjects: []\n" + errors_yaml);
}

TEST(RobotErrors, TheSameSeedBuildsTheSameRobotAndAnotherSeedAnother) {
  const RobotErrorsSpec spec;
  const RobotErrors a = DrawRobotErrors(spec, 7), b = DrawRobotErrors(spec, 7),
                    c = DrawRobotErrors(spec, 8);
  ASSERT_EQ(a.joints.size(), 15u);        // 2 x 6 arm joints and the head's 3
  ASSERT_EQ(a.body_offsets.size(), 16u);  // 2 x (base, 6 links, gripper)
  EXPECT_EQ(a.joints.at("left_j2").zero_rad, b.joints.at("left_j2").zero_rad);
  EXPECT_NE(a.joints.at("left_j2").zero_rad, c.joints.at("left_j2").zero_rad);
  EXPECT_EQ(a.body_offsets.at("right_link3"), b.body_offsets.at("right_link3"));
  // The head homes on its index pulses: no zero error, but its encoder's steps.
  EXPECT_EQ(a.joints.at("head_pan").zero_rad, 0.0);
  EXPECT_NEAR(a.joints.at("head_pan").resolution_rad, DegToRad(0.03), 1e-15);
  EXPECT_NEAR(a.joints.at("left_j1").latency_s, 0.028, 1e-15);
}

TEST(RobotErrors, TheDrawsHaveTheSpreadsTheBlockGives) {
  // Over 200 robots: 2400 joint zeros of std. dev. 0.1 deg and 9600 link coordinates of 0.25 mm
  // (the sample std. dev. within 5%), mean near 0.
  const RobotErrorsSpec spec;
  double zz = 0, z = 0, ll = 0;
  int nz = 0, nl = 0;
  for (std::uint64_t seed = 0; seed < 200; ++seed) {
    const RobotErrors e = DrawRobotErrors(spec, seed);
    for (const auto& [name, j] : e.joints) {
      if (name.rfind("head", 0) == 0) continue;
      zz += RadToDeg(j.zero_rad) * RadToDeg(j.zero_rad);
      z += RadToDeg(j.zero_rad);
      ++nz;
    }
    for (const auto& [name, d] : e.body_offsets) {
      ll += 1e6 * d.squaredNorm();
      nl += 3;
    }
  }
  EXPECT_NEAR(std::sqrt(zz / nz), 0.1, 0.005);
  EXPECT_NEAR(z / nz, 0.0, 0.01);
  EXPECT_NEAR(std::sqrt(ll / nl), 0.25, 0.0125);
}

TEST(RobotErrors, SwitchedOffTheRobotIsItsModel) {
  RobotErrorsSpec spec;
  spec.enabled = false;
  const RobotErrors e = DrawRobotErrors(spec, 7);
  EXPECT_TRUE(e.joints.empty());
  EXPECT_TRUE(e.body_offsets.empty());
  EXPECT_TRUE(e.head_mount.isApprox(Pose3::Identity(), 0.0));
  // A World without them: the encoders read the true angles and the controller's kinematics are
  // the arm's.
  SimRobot robot(Empty("robot_errors: {enabled: false}\n"));
  World& w = robot.world();
  const int a = w.Id(mjOBJ_ACTUATOR, "left_j2");
  EXPECT_EQ(w.EncoderReading(a), w.JointPosition("left_j2"));
  device::RobotDevices dev = robot.TakeDevices();
  device::ArmState s;
  EXPECT_OK(dev.ArmOf(Side::kLeft).Read(&s));
  const Pose3 nominal = ArmForwardKinematics(w, Side::kLeft, s.q);
  const Pose3 truth = w.BodyPose(w.Id(mjOBJ_BODY, "left_gripper"));
  EXPECT_LT((nominal.translation() - truth.translation()).norm(), 1e-9);
}

// Moves one joint of the left arm to `goal` (as its encoder reads) and lets it settle.
void MoveJoint(device::RobotDevices* dev, int joint, double goal) {
  device::ArmState s;
  EXPECT_OK(dev->ArmOf(Side::kLeft).Read(&s));
  device::Joint6 q = s.q;
  q[joint] = goal;
  ASSERT_EQ(dev->ArmOf(Side::kLeft).MoveJoints(q), device::Status::kOk);
  device::StereoFrame f;
  for (int i = 0; i < 60; ++i) EXPECT_OK(dev->cameras->GrabWithoutImages(&f));
}

TEST(RobotErrors, AJointStandsOffItsEncoderByItsZeroAndHalfItsBacklash) {
  // Errors exaggerated so that they stand out of the servo's few-microradian settling: a zero
  // 0.5 deg off and 0.2 deg of backlash, encoder steps of 0.01 deg.
  SimRobot robot(
      Empty("robot_errors: {arm_joint_zero_deg: 0.5, arm_backlash_deg: 0.2, "
            "arm_encoder_deg: 0.01}\n"));
  World& w = robot.world();
  device::RobotDevices dev = robot.TakeDevices();
  const JointError& e = w.robot_errors().joints.at("left_j1");
  ASSERT_GT(std::abs(e.zero_rad), 1e-4);
  const double step = DegToRad(0.01);
  device::ArmState s;
  // At home the link stands at the keyframe; its encoder reads that less the zero, in steps.
  const double home = w.JointPosition("left_j1");
  EXPECT_OK(dev.ArmOf(Side::kLeft).Read(&s));
  EXPECT_NEAR(s.q[0], home - e.zero_rad, 0.5 * step + 1e-12);
  EXPECT_NEAR(s.q[0] / step, std::round(s.q[0] / step), 1e-6);
  // Moved up to an encoder angle: the motor goes to the nearest whole count, which the
  // encoder then reads; the link stands at it plus the zero, less half the backlash (the link
  // lags the motor). Moved down to the same angle: plus half the backlash.
  const double target = home - e.zero_rad + 0.2;
  const double count = step * std::round(target / step);
  ASSERT_GT(std::abs(count - target), 1e-7);  // a goal between counts
  MoveJoint(&dev, 0, target);
  EXPECT_NEAR(w.JointPosition("left_j1"), count + e.zero_rad - DegToRad(0.1), 2e-5);
  EXPECT_OK(dev.ArmOf(Side::kLeft).Read(&s));
  EXPECT_NEAR(s.q[0], count, 1e-9);
  MoveJoint(&dev, 0, target + 0.1);
  MoveJoint(&dev, 0, target);
  EXPECT_NEAR(w.JointPosition("left_j1"), count + e.zero_rad + DegToRad(0.1), 2e-5);
  EXPECT_OK(dev.ArmOf(Side::kLeft).Read(&s));
  EXPECT_NEAR(s.q[0], count, 1e-9);
}

TEST(RobotErrors, ACommandMovesTheArmOnlyAfterItsLatency) {
  SimRobot robot(Empty("robot_errors: {arm_latency_ms: 100}\n"));
  World& w = robot.world();
  device::RobotDevices dev = robot.TakeDevices();
  const double q0 = w.JointPosition("left_j1");
  device::ArmState s;
  EXPECT_OK(dev.ArmOf(Side::kLeft).Read(&s));
  device::Joint6 q = s.q;
  q[0] += 0.2;
  ASSERT_EQ(dev.ArmOf(Side::kLeft).MoveJoints(q), device::Status::kOk);
  device::StereoFrame f;
  EXPECT_OK(dev.cameras->GrabWithoutImages(&f));  // 40 ms
  EXPECT_OK(dev.cameras->GrabWithoutImages(&f));  // 80 ms: not yet started
  EXPECT_NEAR(w.JointPosition("left_j1"), q0, 1e-4);
  EXPECT_OK(dev.ArmOf(Side::kLeft).Read(&s));
  EXPECT_TRUE(s.moving);
  for (int i = 0; i < 3; ++i) EXPECT_OK(dev.cameras->GrabWithoutImages(&f));  // 200 ms: under way
  EXPECT_GT(w.JointPosition("left_j1"), q0 + 1e-3);
}

TEST(RobotErrors, TheOpenLoopGripperIsMillimetresFromWhereTheControllerBelievesIt) {
  // The default robot: the controller's kinematics (nominal links, its encoders' angles) put
  // the gripper 0.5-10 mm from where it truly is, for every seed of a handful; the robot's own
  // errors, not a constant.
  for (std::uint64_t seed : {1, 2, 3, 4, 5}) {
    SimRobot robot(Empty("", seed));
    World& w = robot.world();
    device::RobotDevices dev = robot.TakeDevices();
    for (Side side : {Side::kLeft, Side::kRight}) {
      device::ArmState s;
      EXPECT_OK(dev.ArmOf(side).Read(&s));
      const Pose3 believed = ArmForwardKinematics(w, side, s.q);
      const Pose3 truth =
          w.BodyPose(w.Id(mjOBJ_BODY, std::string(device::ToString(side)) + "_gripper"));
      const double off = (believed.translation() - truth.translation()).norm();
      EXPECT_GT(off, 0.0005) << seed;
      EXPECT_LT(off, 0.010) << seed;
    }
  }
}

TEST(RobotErrors, TheLinksStandWhereTheErrorsPutThem) {
  SimRobot robot(Empty());
  const World& w = robot.world();
  const int body = w.Id(mjOBJ_BODY, "right_link3");
  const Eigen::Vector3d d = w.robot_errors().body_offsets.at("right_link3");
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(w.model()->body_pos[3 * body + i] - w.nominal_model()->body_pos[3 * body + i], d[i],
                1e-15);
  }
}

}  // namespace
}  // namespace hgrasp::sim
