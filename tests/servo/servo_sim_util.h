#pragma once
// The servo tests' simulated set-up: a gripper posed in view of the cameras, and time run until
// the arm is still. Ground truth is read only to judge results.

#include <Eigen/Geometry>
#include <optional>
#include <string>

#include "common/error.h"
#include "common/paths.h"
#include "device/robot_devices.h"
#include "robot/arm_kinematics.h"
#include "robot/kinematic_tree.h"
#include "sim/sim_devices.h"

namespace hgrasp::servo::testing {

/// Joints that put arm `side`'s gripper at `p_W` pointing along `approach_W`, its palm's +y face
/// (LEDs 0, 1, 4 and 5) turned towards the left camera and then by `tilt` (rad) about the approach
/// axis: the analytic solution within limits nearest the arm's joints now; nullopt when
/// unreachable.
inline std::optional<device::Joint6> JointsFacingCamera(
    sim::SimRobot& robot, device::RobotDevices& dev, device::Side side, const Eigen::Vector3d& p_W,
    const Eigen::Vector3d& approach_W, double tilt) {
  const auto tree = robot::KinematicTree::FromUrdfFile(ResolveDataPath("models/humanoid.urdf"));
  const auto arm =
      robot::ArmKinematics::FromTree(tree, side == device::Side::kLeft ? "left" : "right");
  device::ArmState a;
  HGRASP_DEMAND(dev.ArmOf(side).Read(&a) == device::Status::kOk);
  const Eigen::Vector3d z = approach_W.normalized();
  const Eigen::Vector3d to_camera = robot.rig().View(sim::kLeft).X_WC.translation() - p_W;
  const Eigen::Vector3d y0 = (to_camera - to_camera.dot(z) * z).normalized();
  const Eigen::Vector3d y = Eigen::AngleAxisd(tilt, z) * y0;
  Pose3 X_WE = Pose3::Identity();
  X_WE.linear().col(0) = y.cross(z);
  X_WE.linear().col(1) = y;
  X_WE.linear().col(2) = z;
  X_WE.translation() = p_W;
  std::optional<device::Joint6> q;
  for (const robot::ArmIkSolution& s : arm.Inverse(X_WE)) {
    if (arm.WithinLimits(s.q) && (!q || (s.q - a.q).norm() < (*q - a.q).norm())) q = s.q;
  }
  return q;
}

/// Lets simulated time run (a frame is 40 ms, at least 0.4 s) until arm `side` is still or
/// `max_s` has passed; returns the last frame.
inline device::StereoFrame Settle(device::RobotDevices& dev, device::Side side, double max_s) {
  device::StereoFrame frame;
  for (double t = 0; t < max_s; t += 0.04) {
    HGRASP_DEMAND(dev.cameras->Grab(&frame) == device::Status::kOk);
    device::ArmState a;
    HGRASP_DEMAND(dev.ArmOf(side).Read(&a) == device::Status::kOk);
    if (!a.moving && t > 0.4) break;
  }
  return frame;
}

}  // namespace hgrasp::servo::testing
