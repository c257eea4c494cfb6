#pragma once
/// @file Kinematics of one Puma 260 arm, read from models/humanoid.urdf: forward kinematics of
/// the gripper frame E, the geometric Jacobian, joint limits, and the closed-form inverse
/// kinematics with all (up to 8) solutions.
///
/// The arm is taken as a product of exponentials: at q = 0 every joint i has a unit axis w_i and
/// a point r_i on it (in W, from the URDF), and X_WE(q) = e^(xi_1 q_1) ... e^(xi_6 q_6) X_WE(0).
/// The Puma's geometry (Paul and Zhang: axes 1 and 2 meet at the shoulder point, axes 4, 5 and 6
/// at the wrist centre; the 260's shoulder offset d2 + d3 and forearm d4 are wherever the URDF
/// puts them) makes the inverse closed-form with three of Paden and Kahan's subproblems:
///  1. the wrist centre's distance from the shoulder point depends on q3 alone (subproblem 3:
///     up to two elbow solutions);
///  2. q1, q2 rotate the wrist centre to its target about two intersecting axes (subproblem 2:
///     up to two shoulder solutions each);
///  3. q4, q5 rotate axis 6 to its target about two axes meeting at the wrist centre (subproblem
///     2: up to two wrist solutions each), and q6 follows (subproblem 1).
/// Loading checks that the URDF has that geometry.

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "common/geometry.h"
#include "device/arm.h"
#include "robot/kinematic_tree.h"

namespace hgrasp::robot {

/// One inverse-kinematics solution with its configuration: which of the two branches each
/// subproblem took.
struct ArmIkSolution {
  device::Joint6 q = device::Joint6::Zero();  ///< rad, each in (-pi, pi]
  bool shoulder = false;  ///< the second q1/q2 branch (the arm reaching over its shoulder)
  bool elbow = false;     ///< the second q3 branch (elbow down)
  bool wrist = false;     ///< the second q4/q5 branch (wrist flipped)
};

/// The points within `radius` of the segment from a to b.
struct Capsule {
  Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
  double radius = 0;
};

class ArmKinematics {
 public:
  /// The arm `side` ("left" or "right") of `tree`: joints <side>_j1..<side>_j6, gripper frame
  /// <side>_gripper.
  /// @throws hgrasp::InputError when the tree lacks them or the axes do not meet as a Puma's do
  ///         (axes 1 and 2 at one point, axes 4, 5 and 6 at another, within 1 um).
  static ArmKinematics FromTree(const KinematicTree& tree, const std::string& side);

  /// Pose of the gripper frame E in W.
  Pose3 Forward(const device::Joint6& q) const;

  /// Geometric Jacobian in W at the gripper origin: rows 0-2 the origin's velocity (m/s), rows
  /// 3-5 the angular velocity (rad/s), per unit joint rate.
  Eigen::Matrix<double, 6, 6> Jacobian(const device::Joint6& q) const;

  /// Unit direction of the forearm: joint 4's axis, pointing from the elbow (joint 3's axis)
  /// towards the wrist centre.
  Eigen::Vector3d ForearmDirection(const device::Joint6& q) const;

  /// Every joint configuration (angles in (-pi, pi], joint limits not applied) whose gripper
  /// pose is X_WE: up to 8, none when the pose is out of reach. At a singularity (e.g. the wrist
  /// straight, q5 = 0) one representative of the family is returned.
  std::vector<ArmIkSolution> Inverse(const Pose3& X_WE) const;

  /// The arm's body at q in W: each cylinder of links 1-6 in the URDF as a capsule of its axis
  /// and radius: inside a tube (length at least 4 radii; the MJCF's capsule), around a joint's
  /// drum (shorter). The hand is not in it.
  std::vector<Capsule> LinkCapsules(const device::Joint6& q) const;
  /// Whether every joint lies within the URDF's limits.
  bool WithinLimits(const device::Joint6& q) const;
  const std::array<double, 6>& lower() const { return lower_; }
  const std::array<double, 6>& upper() const { return upper_; }

  /// Shoulder point (axes 1 and 2) and wrist centre (axes 4-6) at q = 0, in W.
  const Eigen::Vector3d& shoulder_point() const { return shoulder_; }
  const Eigen::Vector3d& wrist_point() const { return wrist_; }

 private:
  std::array<Eigen::Vector3d, 6> w_;  // joint axes at q = 0 (W, unit)
  std::array<Eigen::Vector3d, 6> r_;  // a point on each axis at q = 0 (W)
  Pose3 M_ = Pose3::Identity();       // X_WE at q = 0
  Eigen::Vector3d shoulder_ = Eigen::Vector3d::Zero(), wrist_ = Eigen::Vector3d::Zero();
  std::array<double, 6> lower_{}, upper_{};
  struct LinkCapsule {
    int joints = 0;   // how many joints move it (link k: joints 1..k)
    Capsule at_zero;  // in W at q = 0
  };
  std::vector<LinkCapsule> capsules_;
};

}  // namespace hgrasp::robot
