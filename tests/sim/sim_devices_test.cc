// The simulated devices behave as the seam promises: lockstep time, latched readings, motions
// within the speed limits, tool-frame moves, the hand, the LEDs and the laser encoder.

#include "sim/sim_devices.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <random>

#include "tests/sim/sim_test_util.h"
#include "tests/support/status.h"

namespace hgrasp::sim {
namespace {

using device::Side;
using device::Status;

class SimDevicesTest : public ::testing::Test {
 protected:
  SimDevicesTest()
      : robot_(testing::ScenarioFromYaml(testing::kEmptyScene)), dev_(robot_.TakeDevices()) {}
  // Grabs frames until `done` or `max_frames`; returns the frames grabbed.
  template <typename F>
  int GrabUntil(F done, int max_frames) {
    device::StereoFrame f;
    for (int i = 0; i < max_frames; ++i) {
      if (done()) return i;
      EXPECT_OK(dev_.cameras->Grab(&f));
    }
    return max_frames;
  }
  SimRobot robot_;
  device::RobotDevices dev_;
};

TEST_F(SimDevicesTest, GrabAdvancesTimeByOneFrameAndLatchesReadings) {
  device::StereoFrame a, b;
  ASSERT_EQ(dev_.cameras->Grab(&a), Status::kOk);
  ASSERT_EQ(dev_.cameras->Grab(&b), Status::kOk);
  EXPECT_NEAR(b.t_s - a.t_s, 0.040, 1e-9);
  EXPECT_EQ(b.sequence, a.sequence + 1);
  EXPECT_EQ(a.left.rows, 240);
  EXPECT_EQ(a.left.cols, 320);
  EXPECT_EQ(a.left.type(), CV_8UC3);
  device::HeadState head;
  EXPECT_OK(dev_.head->Read(&head));
  EXPECT_NEAR(b.head.tilt, head.q.tilt, 1e-12);
  EXPECT_NEAR(b.head.verge, head.q.verge, 1e-12);
}

TEST_F(SimDevicesTest, HeadMovesToTargetWithinItsSpeedLimit) {
  device::HeadState s0, s;
  EXPECT_OK(dev_.head->Read(&s0));
  const device::HeadJoints target{0.3, s0.q.tilt - 0.1, s0.q.verge + 0.02};
  ASSERT_EQ(dev_.head->MoveTo(target), Status::kOk);
  const int frames = GrabUntil(
      [&] {
        EXPECT_OK(dev_.head->Read(&s));
        return !s.moving && s.t_s > s0.t_s;
      },
      200);
  GrabUntil([] { return false; }, 10);  // settle
  EXPECT_OK(dev_.head->Read(&s));
  EXPECT_NEAR(s.q.pan, 0.3, 2e-3);
  EXPECT_NEAR(s.q.tilt, target.tilt, 2e-3);
  EXPECT_NEAR(s.q.verge, target.verge, 2e-3);
  // 0.3 rad of pan at 150 deg/s takes at least 0.115 s.
  EXPECT_GE(frames * 0.04, 0.3 / DegToRad(150));
  EXPECT_EQ(dev_.head->MoveTo({0, DegToRad(75), 0}), Status::kRejected);  // tilt limit 60 deg
}

TEST_F(SimDevicesTest, ArmJointMoveArrivesTogetherWithinSpeedLimits) {
  device::ArmState s0, s;
  EXPECT_OK(dev_.ArmOf(Side::kRight).Read(&s0));
  device::Joint6 goal = s0.q;
  goal[0] += 0.4;
  goal[3] += 0.6;
  ASSERT_EQ(dev_.ArmOf(Side::kRight).MoveJoints(goal), Status::kOk);
  const double limits_deg[6] = {120, 120, 165, 575, 430, 400};
  double worst_ratio = 0;
  device::StereoFrame f;
  for (int i = 0; i < 100; ++i) {
    EXPECT_OK(dev_.cameras->Grab(&f));
    EXPECT_OK(dev_.ArmOf(Side::kRight).Read(&s));
    for (int j = 0; j < 6; ++j)
      worst_ratio = std::max(worst_ratio, std::abs(s.qd[j]) / DegToRad(limits_deg[j]));
  }
  EXPECT_LT((s.q - goal).cwiseAbs().maxCoeff(), 2e-3);
  EXPECT_LT(worst_ratio, 1.05);
  device::Joint6 bad = goal;
  bad[4] = DegToRad(150);  // beyond joint 5's range
  EXPECT_EQ(dev_.ArmOf(Side::kRight).MoveJoints(bad), Status::kRejected);
}

TEST_F(SimDevicesTest, RelativeMoveInGripperFrameMovesTheGripperByThatMuch) {
  World& w = robot_.world();
  const int gripper = w.Id(mjOBJ_BODY, "left_gripper");
  const Pose3 before = w.BodyPose(gripper);
  Pose3 delta = Pose3::Identity();
  delta.translation() = Eigen::Vector3d(0.02, -0.01, 0.03);
  delta.linear() = Eigen::AngleAxisd(0.1, Eigen::Vector3d(0, 0, 1)).toRotationMatrix();
  ASSERT_EQ(dev_.ArmOf(Side::kLeft).MoveRelative(delta), Status::kOk);
  GrabUntil([] { return false; }, 60);
  const Pose3 after = w.BodyPose(gripper);
  const Pose3 expected = before * delta;
  EXPECT_LT((after.translation() - expected.translation()).norm(), 1e-3);
  EXPECT_LT(Eigen::AngleAxisd(after.linear().transpose() * expected.linear()).angle(),
            DegToRad(0.5));
  Pose3 far = Pose3::Identity();
  far.translation() = Eigen::Vector3d(0, 0, 2.0);  // 2 m: out of reach
  EXPECT_EQ(dev_.ArmOf(Side::kLeft).MoveRelative(far), Status::kRejected);
}

TEST_F(SimDevicesTest, HandOpensAndClosesWithLimitedForce) {
  device::Hand& hand = dev_.HandOf(Side::kRight);
  device::HandState s;
  ASSERT_EQ(hand.Open(0.09), Status::kOk);
  GrabUntil([] { return false; }, 30);
  EXPECT_OK(hand.Read(&s));
  EXPECT_NEAR(s.opening_m, 0.09, 1e-3);
  ASSERT_EQ(hand.Close(30.0), Status::kOk);
  GrabUntil([] { return false; }, 40);
  EXPECT_OK(hand.Read(&s));
  EXPECT_LT(s.opening_m, 1e-3);
  EXPECT_LE(s.grip_force_n, 30.0 + 1e-6);
  EXPECT_EQ(hand.Close(-1.0), Status::kRejected);
}

TEST_F(SimDevicesTest, LedsSwitchTheirMaterial) {
  World& w = robot_.world();
  EXPECT_GE(dev_.leds->Count(Side::kLeft), 4);
  const int led = w.Id(mjOBJ_GEOM, "left_led2");
  const int on = w.Id(mjOBJ_MATERIAL, "led_on"), off = w.Id(mjOBJ_MATERIAL, "led_off");
  ASSERT_EQ(dev_.leds->Set(Side::kLeft, 0b100), Status::kOk);
  EXPECT_EQ(w.model()->geom_matid[led], on);
  EXPECT_EQ(w.model()->geom_matid[w.Id(mjOBJ_GEOM, "left_led0")], off);
  ASSERT_EQ(dev_.leds->Set(Side::kLeft, 0), Status::kOk);
  EXPECT_EQ(w.model()->geom_matid[led], off);
  EXPECT_EQ(dev_.leds->Set(Side::kLeft, 1u << 20), Status::kRejected);
}

// The recovery test's occluder: within the window every LED renders dark whatever it is switched
// to, and after it the switches hold again.
TEST_F(SimDevicesTest, HiddenLedsRenderDarkOnlyWithinTheWindow) {
  World& w = robot_.world();
  const int led = w.Id(mjOBJ_GEOM, "left_led2");
  const int on = w.Id(mjOBJ_MATERIAL, "led_on"), off = w.Id(mjOBJ_MATERIAL, "led_off");
  ASSERT_EQ(dev_.leds->Set(Side::kLeft, 0b100), Status::kOk);
  const double t0 = w.time();
  w.HideLeds(t0 + 0.1, t0 + 0.3);
  device::StereoFrame f;
  EXPECT_OK(dev_.cameras->Grab(&f));  // t0 + 0.04: before the window
  EXPECT_FALSE(w.leds_hidden());
  EXPECT_EQ(w.model()->geom_matid[led], on);
  for (int i = 0; i < 3; ++i) EXPECT_OK(dev_.cameras->Grab(&f));  // t0 + 0.16: inside
  EXPECT_TRUE(w.leds_hidden());
  EXPECT_EQ(w.model()->geom_matid[led], off);
  ASSERT_EQ(dev_.leds->Set(Side::kLeft, 0b110), Status::kOk);  // switching while hidden
  EXPECT_EQ(w.model()->geom_matid[w.Id(mjOBJ_GEOM, "left_led1")], off);
  for (int i = 0; i < 4; ++i) EXPECT_OK(dev_.cameras->Grab(&f));  // t0 + 0.32: after
  EXPECT_FALSE(w.leds_hidden());
  EXPECT_EQ(w.model()->geom_matid[led], on);
  EXPECT_EQ(w.model()->geom_matid[w.Id(mjOBJ_GEOM, "left_led1")], on);
}

// The hand-eye test's displaced head: the cameras move by exactly the mounting error, seen
// from the head's mounting frame, and nothing else does.
TEST(SimHeadMountTest, CamerasMoveByTheMountingError) {
  const Scenario scenario = testing::ScenarioFromYaml(testing::kEmptyScene);
  World nominal(scenario);
  WorldOptions options;
  options.head_mount_error.linear() =
      Eigen::AngleAxisd(DegToRad(3.0), Eigen::Vector3d(0, 1, 0)).toRotationMatrix();
  options.head_mount_error.translation() = Eigen::Vector3d(0.02, 0, 0);
  World displaced(scenario, options);
  const int head = nominal.Id(mjOBJ_BODY, "head_pan_link");
  const Pose3 X_WM = nominal.BodyPose(head);
  EXPECT_TRUE(displaced.BodyPose(head).isApprox(X_WM * options.head_mount_error, 1e-9));
  for (const char* camera : {"camera_left", "camera_right"}) {
    const Pose3 X_WC = Renderer::OpticalFramePose(nominal.data(), nominal.Id(mjOBJ_CAMERA, camera));
    const Pose3 X_WC2 =
        Renderer::OpticalFramePose(displaced.data(), displaced.Id(mjOBJ_CAMERA, camera));
    // X_WC' = X_WM X_MT X_MW X_WC: the same camera pose relative to the mounting.
    EXPECT_TRUE(X_WC2.isApprox(X_WM * options.head_mount_error * X_WM.inverse() * X_WC, 1e-9))
        << camera;
  }
  const int gripper = nominal.Id(mjOBJ_BODY, "left_gripper");
  EXPECT_TRUE(displaced.BodyPose(gripper).isApprox(nominal.BodyPose(gripper), 1e-12));
}

TEST_F(SimDevicesTest, LaserEncoderFollowsAConstantSpeedSweep) {
  ASSERT_EQ(dev_.laser->MoveTo(1500, 2500.0), Status::kOk);  // 25 deg/s
  device::StereoFrame f;
  std::vector<int> counts;
  for (int i = 0; i < 20; ++i) {
    EXPECT_OK(dev_.cameras->Grab(&f));
    counts.push_back(f.laser_encoder_count);
  }
  // Mid-sweep, successive frames are 40 ms * 2500 counts/s = 100 counts apart (within lag).
  EXPECT_NEAR(counts[10] - counts[9], 100, 3);
  GrabUntil([] { return false; }, 20);
  device::StripeLaserState s;
  EXPECT_OK(dev_.laser->Read(&s));
  EXPECT_NEAR(s.encoder_count, 1500, 2);
  EXPECT_EQ(dev_.laser->MoveTo(100000, 1000), Status::kRejected);
}

TEST(SimRobotTest, AtHomeTheCamerasSeeNoPartOfTheRobot) {
  SimRobot robot(testing::ScenarioFromYaml(testing::kEmptyScene));
  World& w = robot.world();
  const int table = w.Id(mjOBJ_GEOM, "table");
  for (int cam : {kLeft, kRight}) {
    const cv::Mat& label = robot.rig().View(cam).images.label;
    int robot_pixels = 0;
    for (int r = 0; r < label.rows; ++r)
      for (int c = 0; c < label.cols; ++c)
        robot_pixels += label.at<int>(r, c) >= 0 && label.at<int>(r, c) != table;
    EXPECT_EQ(robot_pixels, 0) << "camera " << cam;
  }
}

TEST(SimRobotTest, WorkspaceIsSeenByBothCamerasFromTheHomePose) {
  // DESIGN.md: a box of 4-15 cm edges anywhere in x [0.20, 0.40], y [-0.15, 0.15], at any yaw.
  // Its farthest points lie up to 0.15/sqrt(2) from the workspace edge and 0.15 high.
  SimRobot robot(testing::ScenarioFromYaml(testing::kEmptyScene));
  const double reach = 0.15 / std::sqrt(2.0);
  for (int cam : {kLeft, kRight}) {
    const CameraView& view = robot.rig().View(cam);
    for (double x : {0.20 - reach, 0.40 + reach})
      for (double y : {-0.15 - reach, 0.15 + reach})
        for (double z : {0.0, 0.15}) {
          const auto uv = view.camera.Project(view.X_WC.inverse() * Eigen::Vector3d(x, y, z));
          ASSERT_TRUE(uv.has_value());
          EXPECT_TRUE(view.camera.Contains(*uv))
              << "camera " << cam << " misses " << x << " " << y << " " << z;
        }
  }
}

}  // namespace
}  // namespace hgrasp::sim

namespace hgrasp::sim {
namespace {

// The gripper pose that grasps at `centre_W` (the midpoint between the finger pads, 0.12 m out
// along E's z) with the fingers closing along horizontal direction `yaw`, the approach pointing
// down and tilted by `tilt` about the closing axis (the paper's R2: palm above the top face).
Pose3 GraspPose(const Eigen::Vector3d& centre_W, double yaw, double tilt) {
  const Eigen::Vector3d x = RotZ(yaw) * Eigen::Vector3d::UnitX();
  const Eigen::Vector3d z = Eigen::AngleAxisd(tilt, x) * Eigen::Vector3d(0, 0, -1);
  Pose3 X_WE = Pose3::Identity();
  X_WE.linear().col(0) = x;
  X_WE.linear().col(1) = z.cross(x);
  X_WE.linear().col(2) = z;
  X_WE.translation() = centre_W - 0.12 * z;
  return X_WE;
}

TEST(SimRobotTest, WorkspaceIsReachableByAnArm) {
  // DESIGN.md: a box anywhere in x [0.20, 0.40], y [-0.15, 0.15], at any yaw, can be grasped by
  // at least one arm. Grasp centres 1 cm below the top of 4 and 15 cm boxes, four closing
  // directions, the approach tilted up to 60 deg about the closing axis.
  World world(testing::ScenarioFromYaml(testing::kEmptyScene));
  std::mt19937 rng(5);
  int targets = 0, reached = 0;
  for (double x : {0.20, 0.25, 0.30, 0.35, 0.40})
    for (double y : {-0.15, -0.075, 0.0, 0.075, 0.15})
      for (double z : {0.03, 0.14})
        for (double yaw_deg : {0, 45, 90, 135}) {
          ++targets;
          bool ok = false;
          for (double tilt_deg : {0, 15, -15, 30, -30, 45, -45, 60, -60}) {
            const Pose3 X_WE = GraspPose({x, y, z}, DegToRad(yaw_deg), DegToRad(tilt_deg));
            for (device::Side side : {device::Side::kLeft, device::Side::kRight}) {
              // The controller solves locally: try a few starting configurations.
              for (int start = 0; start < 6 && !ok; ++start) {
                device::Joint6 q0;
                for (int i = 0; i < 6; ++i) {
                  const int j = world.Id(mjOBJ_JOINT, std::string(device::ToString(side)) + "_j" +
                                                          std::to_string(i + 1));
                  std::uniform_real_distribution<double> u(world.model()->jnt_range[2 * j],
                                                           world.model()->jnt_range[2 * j + 1]);
                  q0[i] = start == 0 ? 0.0 : u(rng);
                }
                ok = ArmInverseKinematics(world, side, X_WE, q0).has_value();
              }
              if (ok) break;
            }
            if (ok) break;
          }
          reached += ok;
          EXPECT_TRUE(ok) << "no arm reaches (" << x << ", " << y << ", " << z << ") yaw "
                          << yaw_deg;
        }
  std::printf("reach: %d of %d grasp targets reachable by an arm\n", reached, targets);
}

}  // namespace
}  // namespace hgrasp::sim

namespace hgrasp::sim {
namespace {

TEST(SimRobotTest, SameScenarioAndSeedGiveTheSameFrames) {
  // DESIGN.md rule 6: every random draw comes from the scenario seed.
  const auto scenario = [](int seed) {
    return testing::ScenarioFromYaml("name: d\nseed: " + std::to_string(seed) +
                                     "\ncamera_noise: 2\nobjects:\n  - {name: a, shape: box, "
                                     "size: [0.06, 0.06, 0.06], position: [0.3, 0.0], color: "
                                     "[0.9, 0.2, 0.2]}\n");
  };
  SimRobot a(scenario(7)), b(scenario(7)), c(scenario(8));
  auto da = a.TakeDevices(), db = b.TakeDevices(), dc = c.TakeDevices();
  for (auto* d : {&da, &db, &dc}) {
    EXPECT_OK(d->laser->SetLaser(true));
    EXPECT_OK(d->laser->MoveTo(500, 5000));
  }
  for (int k = 0; k < 3; ++k) {
    device::StereoFrame fa, fb, fc;
    EXPECT_OK(da.cameras->Grab(&fa));
    EXPECT_OK(db.cameras->Grab(&fb));
    EXPECT_OK(dc.cameras->Grab(&fc));
    EXPECT_EQ(cv::norm(fa.left, fb.left, cv::NORM_INF), 0);
    EXPECT_EQ(cv::norm(fa.right, fb.right, cv::NORM_INF), 0);
    EXPECT_GT(cv::norm(fa.left, fc.left, cv::NORM_INF), 0);  // another seed, other noise
  }
}

}  // namespace
}  // namespace hgrasp::sim

namespace hgrasp::sim {
namespace {

TEST(SimRobotTest, LaserMoveToWhereItIsKeepsTheSimulationSound) {
  // A zero-length constant-speed move once put NaN into the laser's set-point, and MuJoCo reset
  // the whole world to its zero pose.
  SimRobot robot(testing::ScenarioFromYaml(testing::kEmptyScene));
  auto dev = robot.TakeDevices();
  const double tilt = robot.world().JointPosition("head_tilt");
  ASSERT_EQ(dev.laser->MoveTo(0, 9000.0), device::Status::kOk);
  device::StereoFrame frame;
  for (int i = 0; i < 5; ++i) ASSERT_EQ(dev.cameras->Grab(&frame), device::Status::kOk);
  EXPECT_EQ(robot.world().data()->warning[mjWARN_BADCTRL].number, 0);
  EXPECT_NEAR(robot.world().JointPosition("head_tilt"), tilt, 1e-4);
  EXPECT_EQ(frame.laser_encoder_count, 0);
}

}  // namespace
}  // namespace hgrasp::sim
