#pragma once
/// @file Head tracking during visual servoing (paper section 6): pan and tilt keep the gripper
/// near the image centre, and the head kinematics carry the servo target (held relative to the
/// cameras) through the head's motion.
///
/// Frames (DESIGN.md rule 4): W world, C the optical frame of the camera the gripper pose is
/// measured in (normally CL, robot::HeadKinematics::kLeft), C' the same camera after the head
/// move, E the gripper, T the target gripper pose. The "cyclopean" frame Y has its origin at the
/// midpoint of the two optical centres and the rotation halfway (slerp) between R_WCL and R_WCR:
/// centring the gripper on Y's z axis splits the image offset evenly between the two cameras
/// when they verge.
///
/// Only the head's own kinematics are used (encoders + models/humanoid.urdf): the gripper
/// position measured in C is carried into W through X_WC(q) and re-aimed, so no camera-to-arm
/// calibration enters here either. The carried target X_C'T = X_C'C * X_CT, X_C'C = X_WC'^-1 *
/// X_WC, keeps the target the same point in W (and in the arm's base) while the cameras move.

#include <Eigen/Core>

#include "common/geometry.h"
#include "device/head.h"
#include "robot/head_kinematics.h"

namespace hgrasp::servo {

/// Which optical axis is aimed at the gripper.
enum class AimFrame {
  kLeft,       ///< the left camera's optical axis (CL)
  kRight,      ///< the right camera's optical axis (CR)
  kCyclopean,  ///< the cyclopean frame Y (see the file comment)
};

struct HeadTrackingOptions {
  AimFrame aim = AimFrame::kLeft;
  /// The camera in whose optical frame gripper positions and targets are given (the frame of the
  /// pose filter): robot::HeadKinematics::kLeft or kRight.
  int measurement_camera = robot::HeadKinematics::kLeft;
  /// Fraction of the pan/tilt correction applied per call, in (0, 1]. 1: centre in one move.
  double gain = 1.0;
  /// Largest change of pan and of tilt per call (rad): the head moves while the arm moves and
  /// the LEDs must stay in view.
  double max_step = DegToRad(15.0);
  /// No head move while the gripper is within this angle of the aimed axis (rad): avoids moving
  /// the cameras (and disturbing the filter) for every pixel of noise. 0 always moves.
  double deadband = DegToRad(1.0);
};

struct HeadTrackingResult {
  device::HeadJoints q;            ///< the new head joints (verge unchanged)
  bool moved = false;              ///< false inside the deadband (q equals the input joints)
  bool at_limit = false;           ///< pan or tilt was clamped to its URDF limit
  double offset_before_rad = 0.0;  ///< angle between the aimed axis and the gripper, before
  double offset_after_rad = 0.0;   ///< the same predicted at q (0 unless clamped or gain < 1)
};

class HeadTracker {
 public:
  /// Takes the head kinematics (normally HeadKinematics::FromUrdfFile) and the options.
  /// @throws hgrasp::InputError naming the field when gain is not in (0, 1], max_step is not
  ///         positive, deadband is negative or measurement_camera is not kLeft or kRight.
  HeadTracker(robot::HeadKinematics kinematics, const HeadTrackingOptions& options = {});

  /// New head joints that bring the gripper at p_CE (in the measurement camera's optical frame C
  /// at joints q, m) onto the aimed optical axis, within the pan and tilt limits of the URDF.
  /// Solved by Gauss-Newton on (pan, tilt) over the model, since the optical centres are offset
  /// from the pan and tilt axes. The gripper must be in front of the aimed frame's x-y plane.
  HeadTrackingResult Track(const device::HeadJoints& q, const Eigen::Vector3d& p_CE) const;

  /// X_C'C: the measurement camera at q_old seen from itself at q_new.
  Pose3 X_CnewC(const device::HeadJoints& q_old, const device::HeadJoints& q_new) const;

  /// X_C'T = X_C'C * X_CT: a pose held in the measurement camera frame at q_old, carried to the
  /// same camera at q_new so that it stays fixed in W.
  Pose3 CarryThroughHeadMove(const Pose3& X_CT, const device::HeadJoints& q_old,
                             const device::HeadJoints& q_new) const;

  /// The aimed frame (CL, CR or Y) in W at joints q.
  Pose3 X_WAim(const device::HeadJoints& q) const;

  const HeadTrackingOptions& options() const { return options_; }
  const robot::HeadKinematics& kinematics() const { return kinematics_; }

 private:
  robot::HeadKinematics kinematics_;
  HeadTrackingOptions options_;
  double pan_lower_, pan_upper_, tilt_lower_, tilt_upper_;
};

}  // namespace hgrasp::servo
