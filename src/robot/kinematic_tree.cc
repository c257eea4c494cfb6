#include "robot/kinematic_tree.h"

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <limits>
#include <mutex>
#include <sstream>

#include "common/error.h"

namespace hgrasp::robot {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// Collects urdfdom's error messages (it reports through console_bridge, not to the caller).
class CapturingOutputHandler : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char* filename,
           int line) override {
    if (level < console_bridge::CONSOLE_BRIDGE_LOG_ERROR) return;
    if (!errors.empty()) errors += " | ";
    errors += text;
  }
  std::string errors;
};

/// urdfdom's parser with its console output captured; null on failure with `errors` filled.
urdf::ModelInterfaceSharedPtr ParseCapturingErrors(const std::string& xml, std::string* errors) {
  // console_bridge's output handler is process-wide.
  static std::mutex mutex;
  std::lock_guard<std::mutex> lock(mutex);
  CapturingOutputHandler handler;
  console_bridge::useOutputHandler(&handler);
  urdf::ModelInterfaceSharedPtr model;
  try {
    model = urdf::parseURDF(xml);
  } catch (const std::exception& e) {
    handler.errors += e.what();
  }
  console_bridge::restorePreviousOutputHandler();
  *errors = handler.errors;
  return model;
}

Pose3 ToPose3(const urdf::Pose& p) {
  Pose3 X = Pose3::Identity();
  X.linear() = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z)
                   .normalized()
                   .toRotationMatrix();
  X.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  return X;
}

}  // namespace

KinematicTree KinematicTree::FromUrdfFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw InputError(path, "file", std::strerror(errno), "a readable URDF file");
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(path, "file", "read error", "a readable URDF file");
  return FromUrdfString(text.str(), path);
}

KinematicTree KinematicTree::FromUrdfString(const std::string& xml,
                                            const std::string& name_for_errors) {
  std::string errors;
  const urdf::ModelInterfaceSharedPtr model = ParseCapturingErrors(xml, &errors);
  if (!model || !model->getRoot()) {
    throw InputError(name_for_errors, "urdf", errors.empty() ? "unparsable" : errors,
                     "a URDF robot description that urdfdom accepts");
  }

  KinematicTree tree;
  tree.name_ = model->getName();
  tree.source_ = name_for_errors;

  // Breadth-first from the root, so parents always come before their children.
  std::vector<urdf::LinkConstSharedPtr> queue = {model->getRoot()};
  tree.links_.push_back({model->getRoot()->name, -1, -1, {}});
  tree.link_index_[model->getRoot()->name] = 0;
  for (size_t next = 0; next < queue.size(); ++next) {
    const urdf::LinkConstSharedPtr link = queue[next];  // a copy: queue grows below
    for (const urdf::JointSharedPtr& uj : link->child_joints) {
      const std::string field = "joint[" + uj->name + "]";
      Joint j;
      j.name = uj->name;
      j.X_PJ = ToPose3(uj->parent_to_joint_origin_transform);
      j.limits = {-kInf, kInf, kInf, kInf};
      switch (uj->type) {
        case urdf::Joint::FIXED:
          j.type = JointType::kFixed;
          break;
        case urdf::Joint::REVOLUTE:
        case urdf::Joint::CONTINUOUS:
          j.type = JointType::kRevolute;
          break;
        case urdf::Joint::PRISMATIC:
          j.type = JointType::kPrismatic;
          break;
        default:
          throw InputError(name_for_errors, field + ".type", "floating, planar or unknown",
                           "fixed, revolute, continuous or prismatic");
      }
      if (j.type != JointType::kFixed) {
        const Eigen::Vector3d axis(uj->axis.x, uj->axis.y, uj->axis.z);
        if (!(axis.norm() > 1e-9)) {
          throw InputError(name_for_errors, field + ".axis", "0 0 0", "a non-zero axis");
        }
        j.axis = axis.normalized();
        if (uj->limits) {
          if (uj->type != urdf::Joint::CONTINUOUS) {
            j.limits.lower = uj->limits->lower;
            j.limits.upper = uj->limits->upper;
          }
          // urdfdom reads a missing velocity or effort as 0: that means "not given" here.
          if (uj->limits->velocity > 0) j.limits.velocity = uj->limits->velocity;
          if (uj->limits->effort > 0) j.limits.effort = uj->limits->effort;
        }
      }
      const int child_index = static_cast<int>(tree.links_.size());
      tree.joint_index_[j.name] = static_cast<int>(tree.joints_.size());
      tree.joints_.push_back(j);
      const urdf::LinkConstSharedPtr child = model->getLink(uj->child_link_name);
      HGRASP_DEMAND_MSG(child != nullptr, uj->child_link_name);  // urdfdom checks this
      tree.links_.push_back({child->name,
                             tree.link_index_.at(link->name),
                             static_cast<int>(tree.joints_.size()) - 1,
                             {}});
      tree.link_index_[child->name] = child_index;
      queue.push_back(child);
    }
  }

  for (Link& link : tree.links_) {
    for (const urdf::VisualSharedPtr& visual : model->getLink(link.name)->visual_array) {
      if (!visual || !visual->geometry || visual->geometry->type != urdf::Geometry::CYLINDER) {
        continue;
      }
      const auto& c = static_cast<const urdf::Cylinder&>(*visual->geometry);
      link.cylinders.push_back({ToPose3(visual->origin), c.radius, c.length});
    }
  }

  // Mimic joints: resolve chains to the ultimate master, composing the affine maps.
  for (Joint& j : tree.joints_) {
    const urdf::JointConstSharedPtr uj = model->getJoint(j.name);
    if (j.type == JointType::kFixed || !uj->mimic) continue;
    const std::string field = "joint[" + j.name + "].mimic.joint";
    std::string master = uj->mimic->joint_name;
    double multiplier = uj->mimic->multiplier;
    double offset = uj->mimic->offset;
    for (size_t hops = 0;; ++hops) {
      const auto it = tree.joint_index_.find(master);
      if (it == tree.joint_index_.end() || tree.joints_[it->second].type == JointType::kFixed) {
        throw InputError(name_for_errors, field, master, "the name of a movable joint");
      }
      if (hops > tree.joints_.size() || master == j.name) {
        throw InputError(name_for_errors, field, master, "a mimic chain without a cycle");
      }
      const urdf::JointConstSharedPtr um = model->getJoint(master);
      if (!um->mimic) {
        j.master = it->second;
        break;
      }
      // q_j = m (m2 q + o2) + o
      offset += multiplier * um->mimic->offset;
      multiplier *= um->mimic->multiplier;
      master = um->mimic->joint_name;
    }
    j.multiplier = multiplier;
    j.offset = offset;
  }
  return tree;
}

std::vector<std::string> KinematicTree::LinkNames() const {
  std::vector<std::string> names;
  names.reserve(links_.size());
  for (const Link& l : links_) names.push_back(l.name);
  return names;
}

const std::vector<KinematicTree::Cylinder>& KinematicTree::Cylinders(
    const std::string& link) const {
  const auto it = link_index_.find(link);
  if (it == link_index_.end()) {
    throw InputError(source_, "link", link, "a link of robot '" + name_ + "'");
  }
  return links_[it->second].cylinders;
}

std::vector<std::string> KinematicTree::JointNames() const {
  std::vector<std::string> names;
  for (const Joint& j : joints_) {
    if (j.type != JointType::kFixed) names.push_back(j.name);
  }
  return names;
}

const KinematicTree::Joint& KinematicTree::MovableJoint(const std::string& joint) const {
  const auto it = joint_index_.find(joint);
  if (it == joint_index_.end() || joints_[it->second].type == JointType::kFixed) {
    throw InputError(source_, "joint", joint, "a movable joint of robot '" + name_ + "'");
  }
  return joints_[it->second];
}

bool KinematicTree::IsMimic(const std::string& joint) const {
  return MovableJoint(joint).master >= 0;
}

Eigen::Vector3d KinematicTree::Axis(const std::string& joint) const {
  return MovableJoint(joint).axis;
}

std::string KinematicTree::ChildLink(const std::string& joint) const {
  const Joint& j = MovableJoint(joint);
  for (const Link& link : links_) {
    if (link.parent_joint >= 0 && &joints_[link.parent_joint] == &j) return link.name;
  }
  HGRASP_DEMAND(false);  // every joint has a child link
  return {};
}

KinematicTree::JointLimits KinematicTree::Limits(const std::string& joint) const {
  return MovableJoint(joint).limits;
}

std::vector<double> KinematicTree::JointValuesOf(const JointValues& q) const {
  std::vector<double> values(joints_.size(), 0.0);
  for (const auto& [name, value] : q) {
    const auto it = joint_index_.find(name);
    if (it == joint_index_.end() || joints_[it->second].type == JointType::kFixed) {
      throw InputError(source_, "q", name, "a movable joint of robot '" + name_ + "'");
    }
    values[it->second] = value;
  }
  for (size_t i = 0; i < joints_.size(); ++i) {
    const Joint& j = joints_[i];
    if (j.master >= 0) values[i] = j.multiplier * values[j.master] + j.offset;
  }
  return values;
}

Pose3 KinematicTree::ParentToChild(const Link& link, const std::vector<double>& values) const {
  const Joint& j = joints_[link.parent_joint];
  const double q = values[link.parent_joint];
  switch (j.type) {
    case JointType::kFixed:
      return j.X_PJ;
    case JointType::kRevolute: {
      Pose3 X = j.X_PJ;
      X.linear() = X.linear() * Eigen::AngleAxisd(q, j.axis).toRotationMatrix();
      return X;
    }
    case JointType::kPrismatic: {
      Pose3 X = j.X_PJ;
      X.translation() += X.linear() * (q * j.axis);
      return X;
    }
  }
  return j.X_PJ;  // not reached
}

std::unordered_map<std::string, Pose3> KinematicTree::LinkPoses(const JointValues& q) const {
  const std::vector<double> values = JointValuesOf(q);
  std::vector<Pose3> X_RL(links_.size(), Pose3::Identity());
  std::unordered_map<std::string, Pose3> poses;
  poses.reserve(links_.size());
  poses.emplace(links_[0].name, X_RL[0]);
  for (size_t i = 1; i < links_.size(); ++i) {
    X_RL[i] = X_RL[links_[i].parent] * ParentToChild(links_[i], values);
    poses.emplace(links_[i].name, X_RL[i]);
  }
  return poses;
}

Pose3 KinematicTree::LinkPose(const std::string& link, const JointValues& q) const {
  const auto it = link_index_.find(link);
  if (it == link_index_.end()) {
    throw InputError(source_, "link", link, "a link of robot '" + name_ + "'");
  }
  const std::vector<double> values = JointValuesOf(q);
  Pose3 X_RL = Pose3::Identity();
  // Walk up to the root, composing on the left: X_RL = X_RP * X_PL.
  for (int i = it->second; links_[i].parent >= 0; i = links_[i].parent) {
    X_RL = ParentToChild(links_[i], values) * X_RL;
  }
  return X_RL;
}

}  // namespace hgrasp::robot
