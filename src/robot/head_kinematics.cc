#include "robot/head_kinematics.h"

#include <algorithm>
#include <vector>

#include "common/error.h"

namespace hgrasp::robot {
namespace {

const std::string kBracket = "camera_bracket";
const std::string kOptical[2] = {"camera_left_optical", "camera_right_optical"};
const std::string kLaserPlane = "laser_plane";
const std::string kPan = "head_pan";
const std::string kTilt = "head_tilt";
const std::string kVerge = "head_verge_left";
const std::string kVergeRight = "head_verge_right";
const std::string kLaser = "laser";

bool Contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

bool AlmostEqual(const Pose3& a, const Pose3& b, double tol) {
  return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff() <= tol;
}

}  // namespace

HeadKinematics HeadKinematics::FromUrdfFile(const std::string& path) {
  HeadKinematics head(KinematicTree::FromUrdfFile(path));
  const KinematicTree& tree = head.tree_;

  const std::vector<std::string> links = tree.LinkNames();
  for (const std::string& link : {kBracket, kOptical[0], kOptical[1], kLaserPlane}) {
    if (!Contains(links, link)) {
      throw InputError(path, "link " + link, "", "the head's link '" + link + "'");
    }
  }
  const std::vector<std::string> joints = tree.JointNames();
  for (const std::string& joint : {kPan, kTilt, kVerge, kVergeRight, kLaser}) {
    if (!Contains(joints, joint)) {
      throw InputError(path, "joint " + joint, "", "the head's movable joint '" + joint + "'");
    }
  }
  if (tree.IsMimic(kVerge) || !tree.IsMimic(kVergeRight)) {
    throw InputError(path, "joint " + kVergeRight, "not a mimic",
                     "a mimic of " + kVerge + " (the cameras verge together)");
  }
  // X_HC must depend on the verge angle only: the cameras are mounted on the bracket.
  const device::HeadJoints q{0.4, -0.3, 0.2};
  for (int camera : {kLeft, kRight}) {
    const Pose3 X_HC = head.X_WH(q).inverse() * head.X_WC(camera, q);
    if (!AlmostEqual(X_HC, head.X_HC(camera, q.verge), 1e-9)) {
      throw InputError(path, "link " + kOptical[camera], kOptical[camera],
                       "an optical frame carried by link " + kBracket +
                           " that moves in it with the verge joint only");
    }
  }
  return head;
}

const std::string& HeadKinematics::OpticalLink(int camera) {
  HGRASP_DEMAND_MSG(camera == kLeft || camera == kRight, "camera index " + std::to_string(camera));
  return kOptical[camera];
}

Pose3 HeadKinematics::X_WH(const device::HeadJoints& q) const {
  return tree_.LinkPose(kBracket, {{kPan, q.pan}, {kTilt, q.tilt}});
}

Pose3 HeadKinematics::X_WC(int camera, const device::HeadJoints& q) const {
  return tree_.LinkPose(OpticalLink(camera), {{kPan, q.pan}, {kTilt, q.tilt}, {kVerge, q.verge}});
}

Pose3 HeadKinematics::X_HC(int camera, double verge) const {
  const device::HeadJoints q{0.0, 0.0, verge};
  return X_WH(q).inverse() * X_WC(camera, q);
}

Pose3 HeadKinematics::X_WS(const device::HeadJoints& q, double laser_rad) const {
  return tree_.LinkPose(kLaserPlane, {{kPan, q.pan}, {kTilt, q.tilt}, {kLaser, laser_rad}});
}

}  // namespace hgrasp::robot
