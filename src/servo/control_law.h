#pragma once
/// @file Position-based visual servoing control law (paper section 6; Taylor & Kleeman).
///
/// Both poses are measured in the same camera frame C: the target gripper pose X_CT (from the
/// grasp plan, held relative to the cameras) and the gripper's measured pose X_CE (from the Kalman
/// filter, servo/pose_filter.h). The pose error is the target seen from the gripper,
///   X_ET = X_CE^-1 * X_CT,
/// expressed in the gripper frame E, and the command is a differential pose X_EE' in E, which is
/// exactly what the Puma controller executes (device::Arm::MoveRelative, VAL II
/// "DO MOVE HERE:TRANS(...)"). Because the command never leaves the gripper frame, no
/// camera-to-robot-base calibration is needed: an error in where the cameras are relative to the
/// arm's base changes neither X_ET nor the move that removes it.
///
/// Law: proportional on translation and rotation separately,
///   p_EE' = clamp(k_t * p_ET, max_translation_step),
///   R_EE' = Exp(clamp(k_r * Log(R_ET), max_rotation_step)),
/// so that with k_t = k_r = 1 and no clamping one step lands on the target (X_EE' = X_ET).

#include <Eigen/Core>

#include "common/geometry.h"

namespace hgrasp::servo {

struct ControlLawOptions {
  /// Fraction of the translation error commanded per step, in (0, 1]. 0.5: the measured pose is
  /// filtered and lags, so a full step would overshoot; half the error halves it each cycle.
  double translation_gain = 0.5;
  /// Fraction of the rotation error (angle) commanded per step, in (0, 1].
  double rotation_gain = 0.5;
  /// Largest translation per step (m): keeps each move short enough for the LEDs to stay
  /// tracked and for the controller's joint-interpolated path to stay near a straight line.
  double max_translation_step = 0.02;
  /// Largest rotation per step (rad).
  double max_rotation_step = DegToRad(5.0);
  /// Converged when |p_ET| <= translation_tolerance (m) and the angle of R_ET <=
  /// rotation_tolerance (rad). Defaults 5 mm / 2 deg (issue 7).
  double translation_tolerance = 0.005;
  double rotation_tolerance = DegToRad(2.0);
};

/// Checks the options: gains in (0, 1], steps and tolerances positive and finite.
/// @throws hgrasp::InputError naming the field, the value and what was expected.
void ValidateControlLawOptions(const ControlLawOptions& options);

/// The pose error X_ET = X_CE^-1 * X_CT and its size.
struct ServoError {
  Pose3 X_ET = Pose3::Identity();                      ///< target T in the gripper frame E
  Eigen::Vector3d p_ET = Eigen::Vector3d::Zero();      ///< translation of the error, in E (m)
  Eigen::Vector3d theta_ET = Eigen::Vector3d::Zero();  ///< rotation vector of R_ET, in E (rad)
  double translation_m = 0.0;                          ///< |p_ET|
  double rotation_rad = 0.0;                           ///< |theta_ET|, in [0, pi]
};

/// X_ET from the measured gripper pose and the target, both in the camera frame C.
ServoError ComputeServoError(const Pose3& X_CE, const Pose3& X_CT);

struct ServoCommand {
  /// The differential move for device::Arm::MoveRelative, in the current gripper frame E.
  /// Identity when converged.
  Pose3 X_EEnew = Pose3::Identity();
  ServoError error;        ///< the error the command was computed from
  bool converged = false;  ///< within both tolerances: no move needed
};

/// One step of the proportional law. `options` must pass ValidateControlLawOptions (a broken
/// invariant aborts).
ServoCommand ComputeServoCommand(const Pose3& X_CE, const Pose3& X_CT,
                                 const ControlLawOptions& options = {});

}  // namespace hgrasp::servo
