#pragma once
/// @file The grasp planner (Taylor & Kleeman, section 5.3): a two-finger grasp of a box model by
/// the middles of two opposite faces just below the top, the hand aligned with the contacts and
/// the palm above the box, reachable by the Puma's inverse kinematics within its joint limits,
/// the most comfortable of the feasible grasps chosen. Beyond the paper: both arms are tried, a
/// hand that would hit the table or another box is refused, an arm whose links would touch a box
/// or the table on its way down to the grasp is refused, and a pre-grasp pose above the box is
/// planned for the approach.

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "common/geometry.h"
#include "device/arm.h"
#include "device/status.h"
#include "model/box_fit.h"
#include "robot/arm_kinematics.h"

namespace hgrasp::grasp {

/// The hand in its gripper frame E (models/humanoid.urdf): z the approach direction out of the
/// flange, x from thumb to index; the fingers close symmetrically along x.
struct HandGeometry {
  double max_opening_m = 0.10;  ///< fingers fully open, inner pad faces apart
  double contact_z_m = 0.12;    ///< height of the contact points above E along z
  /// Boxes of the hand in E, centre and full size: the palm, and each pad at a given opening
  /// (x is set from the opening; see HandBoxes).
  Eigen::Vector3d palm_centre{0.0, 0.0, 0.02}, palm_size{0.12, 0.05, 0.04};
  Eigen::Vector3d pad_size{0.012, 0.02, 0.10};
  double pad_centre_z_m = 0.09;
};

struct GraspConfig {
  double delta_m = 0.01;       ///< contacts this far below the top face (paper: delta)
  double clearance_m = 0.01;   ///< opening beyond the box's width on each side
  double approach_m = 0.08;    ///< pre-grasp: this far back along the approach
  double via_height_m = 0.10;  ///< via pose: this far above the pre-grasp
  std::vector<double> tilts_deg = {0, 15, 30, 45, 60, -15, -30};  ///< approach tilts about x_E
  double table_clearance_m = 0.003;  ///< the hand stays this far above the table (z = 0)
  /// The arm's links (ArmKinematics::LinkCapsules) stay this far from every box, the target
  /// included: the boxes are models (a few mm off) and the arm is not its model either (its
  /// joint zeros and links are a few mm off, which the servo corrects at the hand only).
  double arm_clearance_m = 0.01;
  /// The links are checked at this many steps of each joint-space move, via to pre-grasp and
  /// pre-grasp to grasp (the approach moves in joint space, the servo close to it).
  int arm_path_steps = 5;
  HandGeometry hand;
};

/// A planned grasp.
struct GraspPlan {
  int box = -1;                                   ///< index into the boxes planned over
  device::Side side = device::Side::kLeft;        ///< the arm
  Pose3 X_WE = Pose3::Identity();                 ///< gripper pose at the grasp
  Pose3 X_WE_pre = Pose3::Identity();             ///< gripper pose before it, back along z_E
  device::Joint6 q = device::Joint6::Zero();      ///< arm joints at the grasp
  device::Joint6 q_pre = device::Joint6::Zero();  ///< arm joints at the pre-grasp
  /// Gripper pose and joints above the pre-grasp (via_height_m), same configuration: moving
  /// there first, the hand comes down onto the box instead of sweeping across the table.
  Pose3 X_WE_via = Pose3::Identity();
  device::Joint6 q_via = device::Joint6::Zero();
  std::array<Eigen::Vector3d, 2> contacts_W{};  ///< thumb's contact, index finger's contact
  double opening_m = 0;                         ///< finger opening for the approach
  double tilt_rad = 0;                          ///< approach tilt about x_E from straight down
  double comfort_rad = 0;  ///< angle between the forearm (joint 4's axis) and the approach
};

/// Plans a grasp of boxes[target], avoiding the other boxes and the table: for each pair of
/// opposite side faces narrow enough for the open hand, each arm, each approach tilt and each
/// inverse-kinematics solution within the joint limits (with the pre-grasp and the via pose
/// above it reachable in the same configuration) whose hand clears the table and the other
/// boxes at the grasp, the pre-grasp and the via pose, and whose links clear the table and every
/// box from the via pose down to the grasp, the one with the smallest comfort angle;
/// nullopt when none is feasible. `arms` holds the left arm then the right one. If `feasible` is
/// not null it receives every feasible candidate (for tests and pictures).
std::optional<GraspPlan> PlanGrasp(const std::vector<model::BoxModel>& boxes, int target,
                                   const std::array<const robot::ArmKinematics*, 2>& arms,
                                   const GraspConfig& config = {},
                                   std::vector<GraspPlan>* feasible = nullptr);

/// The hand's boxes (palm, thumb pad, index pad) in W for gripper pose X_WE and a finger
/// opening: centre, rotation and full size each.
struct OrientedBox {
  Eigen::Vector3d centre;
  Eigen::Matrix3d R;
  Eigen::Vector3d size;
};
std::array<OrientedBox, 3> HandBoxes(const Pose3& X_WE, double opening_m, const HandGeometry& hand);

/// Whether two oriented boxes overlap (separating axis test, 15 axes).
bool Overlap(const OrientedBox& a, const OrientedBox& b);

/// The distance from the segment a-b to a solid oriented box; 0 where they meet.
double SegmentBoxDistance(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                          const OrientedBox& box);

/// Whether the arm's links at q keep arm_clearance_m from every box and table_clearance_m above
/// the table (z = 0).
bool ArmClear(const robot::ArmKinematics& arm, const device::Joint6& q,
              const std::vector<model::BoxModel>& boxes, const GraspConfig& config);

}  // namespace hgrasp::grasp
