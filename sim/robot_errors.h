#pragma once
/// @file The twin's robot is not its model (issue 19): the errors of one robot, drawn from a
/// scenario's robot_errors block and seed. World builds its MuJoCo model with the links moved
/// by them and runs its joints through them; the pipeline, the controllers' kinematics
/// (sim::ArmForwardKinematics, the VAL II emulator's) and the URDF stay nominal.
///
/// A joint with errors is driven and read as a real geared joint is: the controller commands
/// and reads the motor's encoder; the link stands `zero_rad` off the encoder's zero and lags the
/// motor by half its backlash in the direction of the last move; the reading is whole steps of
/// `resolution_rad`, and a goal is servoed to the nearest whole step (at rest the encoder reads
/// it); a command starts moving `latency_s` after it is given.

#include <array>
#include <cstdint>
#include <map>
#include <string>

#include <Eigen/Core>

#include "common/geometry.h"
#include "sim/scenario.h"

namespace hgrasp::sim {

struct JointError {
  double zero_rad = 0;        ///< true angle at the encoder's zero
  double backlash_rad = 0;    ///< full backlash
  double resolution_rad = 0;  ///< encoder step (0: exact)
  double latency_s = 0;       ///< command to first motion
};

struct RobotErrors {
  /// By actuator name (left_j1 ... right_j6, head_pan, head_tilt, head_verge_left); a joint
  /// not listed has none.
  std::map<std::string, JointError> joints;
  /// By body name: added to the body's position in its parent (the arms' base, links and
  /// gripper frame) (m).
  std::map<std::string, Eigen::Vector3d> body_offsets;
  /// The head's true mounting in its modelled one (WorldOptions::head_mount_error).
  Pose3 head_mount = Pose3::Identity();
  /// Each camera's true focal length over its modelled one (left, right): World narrows or
  /// widens the camera's field of view by it (fovy' = 2 atan(tan(fovy / 2) / scale)).
  std::array<double, 2> camera_focal_scale = {1.0, 1.0};
};

/// One robot's errors from `spec`, drawn from `seed` (the same seed, the same robot; its own
/// stream, apart from the scene's and the cameras' draws). Nothing when spec.enabled is false.
RobotErrors DrawRobotErrors(const RobotErrorsSpec& spec, std::uint64_t seed);

/// The largest joint zero error, link offset and mounting error, for logs and reports.
struct RobotErrorSummary {
  double max_joint_zero_deg = 0, max_link_mm = 0, head_mount_mm = 0, head_mount_deg = 0;
  double max_focal_pct = 0;  ///< the larger |scale - 1| of the two cameras (%)
};
RobotErrorSummary Summarise(const RobotErrors& errors);

}  // namespace hgrasp::sim
