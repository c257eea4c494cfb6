#pragma once
/// @file A Puma 260 arm as its controller (VAL II) presents it.

#include <Eigen/Core>

#include "common/geometry.h"
#include "device/status.h"

namespace hgrasp::device {

using Joint6 = Eigen::Matrix<double, 6, 1>;  ///< joint angles (rad) or rates (rad/s), DH order

struct ArmState {
  double t_s = 0.0;            ///< time the joints were read (s, device clock)
  Joint6 q = Joint6::Zero();   ///< joint angles (rad), models/humanoid.urdf convention
  Joint6 qd = Joint6::Zero();  ///< joint rates (rad/s)
  bool moving = false;         ///< a commanded motion is still under way
};

/// One arm. Commands return at once; motion happens under the controller (joint-interpolated,
/// within the joint speed limits scaled by SetSpeed) and is observed through Read().
class Arm {
 public:
  virtual ~Arm() = default;

  virtual Status Read(ArmState* state) = 0;

  /// Joint-interpolated move to absolute joint angles (rad). VAL II: DO MOVE #PPOINT(...).
  virtual Status MoveJoints(const Joint6& q_target) = 0;

  /// Move by a differential pose expressed in the current gripper frame E:
  /// X_EE' = (rotation, translation in m). VAL II: DO MOVE HERE:TRANS(...). The controller
  /// solves its own inverse kinematics; kRejected when the pose is out of reach.
  virtual Status MoveRelative(const Pose3& X_EEnew) = 0;

  /// Fraction (0, 1] of the joint speed limits used by later moves. VAL II: SPEED.
  virtual Status SetSpeed(double fraction) = 0;

  /// Stop where the arm is now.
  virtual Status Stop() = 0;
  /// The safe stop (DESIGN.md rule 8): Stop, and more where the driver can do more for a
  /// controller it cannot hear (Val2Arm types the stop blind first). Never moves the arm.
  virtual Status SafeStop() { return Stop(); }
  /// The part of SafeStop that needs no answer, at once: a driver that cannot hear its
  /// controller types the stop blind (Val2Arm); nothing otherwise. The robot's safe stop calls
  /// it for every arm before any arm's SafeStop waits on its line, so that one arm's confirmed
  /// stop does not hold up the blind stop of an arm that has gone silent. Never moves the arm.
  virtual void StopAtOnce() {}
};

}  // namespace hgrasp::device
