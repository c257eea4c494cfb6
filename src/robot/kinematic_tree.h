#pragma once
/// @file A small, generic kinematic tree loaded from URDF (urdfdom): link poses from joint
/// values. The Puma kinematics, the head -> camera frames and the gripper LED positions are all
/// read from models/humanoid.urdf through it.

#include <string>
#include <unordered_map>
#include <vector>

#include "common/geometry.h"

namespace hgrasp::robot {

/// A tree of links joined by fixed, revolute, continuous and prismatic joints, with every joint
/// origin parsed once at load time. Poses are in the root link's frame (for humanoid.urdf the
/// root is "world" = W). Joint values are SI: rad for revolute and continuous joints, m for
/// prismatic ones. A mimic joint follows its master: q = multiplier * q_master + offset.
/// Immutable after loading, so one tree may be shared between threads.
class KinematicTree {
 public:
  /// Joint limits as written in the URDF <limit> element.
  struct JointLimits {
    double lower;     ///< rad or m; -infinity for a continuous joint
    double upper;     ///< rad or m; +infinity for a continuous joint
    double velocity;  ///< rad/s or m/s; +infinity when not given
    double effort;    ///< N m or N; +infinity when not given
  };

  /// Joint values by joint name (rad or m).
  using JointValues = std::unordered_map<std::string, double>;

  /// Loads a URDF file.
  /// @throws hgrasp::InputError naming the file when it cannot be read, is not valid URDF, or
  ///         uses a joint type other than fixed, revolute, continuous or prismatic.
  static KinematicTree FromUrdfFile(const std::string& path);

  /// Parses URDF text; `name_for_errors` stands for the file in error messages.
  /// @throws hgrasp::InputError as FromUrdfFile.
  static KinematicTree FromUrdfString(const std::string& xml, const std::string& name_for_errors);

  /// The robot name from <robot name="...">.
  const std::string& name() const { return name_; }

  /// The root link, the frame all poses are given in.
  const std::string& root() const { return links_.front().name; }

  /// All links, parents before children (root first).
  std::vector<std::string> LinkNames() const;

  /// The movable joints (revolute, continuous, prismatic), mimic joints included, parents before
  /// children.
  std::vector<std::string> JointNames() const;

  /// True when `joint` is a movable joint that mimics another one.
  /// @throws hgrasp::InputError when `joint` is not a movable joint of this tree.
  bool IsMimic(const std::string& joint) const;

  /// Unit axis of a movable joint in its own (= its child link's) frame.
  /// @throws hgrasp::InputError when `joint` is not a movable joint of this tree.
  Eigen::Vector3d Axis(const std::string& joint) const;

  /// The child link of a movable joint (the link whose frame is the joint's frame).
  /// @throws hgrasp::InputError when `joint` is not a movable joint of this tree.
  std::string ChildLink(const std::string& joint) const;

  /// Limits of a movable joint.
  /// @throws hgrasp::InputError when `joint` is not a movable joint of this tree.
  JointLimits Limits(const std::string& joint) const;

  /// A cylinder of a link's <visual> geometry (models/humanoid.xml collides the same shapes):
  /// its axis is z of X_LG, its centre X_LG's origin.
  struct Cylinder {
    Pose3 X_LG = Pose3::Identity();  ///< in the link's frame
    double radius = 0;               ///< m
    double length = 0;               ///< m, along z of X_LG
  };
  /// The cylinders among `link`'s <visual> elements, in the file's order (boxes, spheres and
  /// meshes are not listed).
  /// @throws hgrasp::InputError for an unknown link.
  const std::vector<Cylinder>& Cylinders(const std::string& link) const;
  /// Pose X_RL of every link L in the root frame R.
  /// @param q joint values; missing joints are 0, the value given for a mimic joint is ignored
  ///          (it follows its master).
  /// @throws hgrasp::InputError when q names something that is not a movable joint of this tree.
  std::unordered_map<std::string, Pose3> LinkPoses(const JointValues& q) const;

  /// Pose X_RL of one link in the root frame, computing only the chain from the root to it.
  /// @throws hgrasp::InputError for an unknown link, or as LinkPoses for q.
  Pose3 LinkPose(const std::string& link, const JointValues& q) const;

 private:
  enum class JointType { kFixed, kRevolute, kPrismatic };

  struct Joint {
    std::string name;
    JointType type = JointType::kFixed;
    Pose3 X_PJ = Pose3::Identity();                   ///< joint frame in the parent link frame
    Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< unit axis in the joint (= child) frame
    JointLimits limits{};
    int master = -1;  ///< index into joints_ of the (ultimate) master of a mimic joint, else -1
    double multiplier = 1.0;
    double offset = 0.0;
  };

  struct Link {
    std::string name;
    int parent = -1;        ///< index into links_; -1 for the root
    int parent_joint = -1;  ///< index into joints_; -1 for the root
    std::vector<Cylinder> cylinders;
  };

  KinematicTree() = default;
  const Joint& MovableJoint(const std::string& joint) const;
  /// Value of every joint (index as joints_) from q; throws for names that are not movable.
  std::vector<double> JointValuesOf(const JointValues& q) const;
  /// X_PC: the pose of `link` in its parent link for the joint values `values`.
  Pose3 ParentToChild(const Link& link, const std::vector<double>& values) const;

  std::string name_;
  std::string source_;         ///< file name used in error messages
  std::vector<Link> links_;    ///< parents before children; links_[0] is the root
  std::vector<Joint> joints_;  ///< all joints, fixed included, in the order of their child links
  std::unordered_map<std::string, int> link_index_;
  std::unordered_map<std::string, int> joint_index_;
};

}  // namespace hgrasp::robot
