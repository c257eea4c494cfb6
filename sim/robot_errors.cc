#include "sim/robot_errors.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "sim/draw.h"

namespace hgrasp::sim {

RobotErrors DrawRobotErrors(const RobotErrorsSpec& spec, std::uint64_t seed) {
  RobotErrors e;
  if (!spec.enabled) return e;
  // Its own stream: "robot" in ASCII, so that a robot's errors do not follow the scene's draws.
  Draw draw(seed ^ 0x726f626f74ull);
  for (const char* side : {"left", "right"}) {
    for (int j = 1; j <= 6; ++j) {
      JointError& je = e.joints[std::string(side) + "_j" + std::to_string(j)];
      je.zero_rad = DegToRad(draw.Gauss(spec.arm_joint_zero_deg));
      je.backlash_rad = DegToRad(spec.arm_backlash_deg);
      je.resolution_rad = DegToRad(spec.arm_encoder_deg);
      je.latency_s = 1e-3 * spec.arm_latency_ms;
    }
    for (const char* body : {"base", "link1", "link2", "link3", "link4", "link5", "link6",
                             "gripper"}) {
      Eigen::Vector3d d;
      for (int i = 0; i < 3; ++i) d[i] = 1e-3 * draw.Gauss(spec.arm_link_mm);
      e.body_offsets[std::string(side) + "_" + body] = d;
    }
  }
  // The Biclops homes on its index pulses (drivers/biclops): its zeros are its model's.
  for (const char* joint : {"head_pan", "head_tilt", "head_verge_left"}) {
    JointError& je = e.joints[joint];
    je.resolution_rad = DegToRad(spec.head_encoder_deg);
    je.latency_s = 1e-3 * spec.head_latency_ms;
  }
  Eigen::Vector3d t, r;
  for (int i = 0; i < 3; ++i) t[i] = 1e-3 * draw.Gauss(spec.head_mount_mm);
  for (int i = 0; i < 3; ++i) r[i] = DegToRad(draw.Gauss(spec.head_mount_deg));
  e.head_mount.translation() = t;
  e.head_mount.linear() = (Eigen::AngleAxisd(r.z(), Eigen::Vector3d::UnitZ()) *
                           Eigen::AngleAxisd(r.y(), Eigen::Vector3d::UnitY()) *
                           Eigen::AngleAxisd(r.x(), Eigen::Vector3d::UnitX()))
                              .toRotationMatrix();
  // Drawn last: the errors above stay those every earlier seed's robot had.
  for (double& scale : e.camera_focal_scale) scale = 1.0 + 0.01 * draw.Gauss(spec.camera_focal_pct);
  return e;
}

RobotErrorSummary Summarise(const RobotErrors& errors) {
  RobotErrorSummary s;
  for (const auto& [name, j] : errors.joints) {
    s.max_joint_zero_deg = std::max(s.max_joint_zero_deg, std::abs(RadToDeg(j.zero_rad)));
  }
  for (const auto& [name, d] : errors.body_offsets) {
    s.max_link_mm = std::max(s.max_link_mm, 1e3 * d.cwiseAbs().maxCoeff());
  }
  s.head_mount_mm = 1e3 * errors.head_mount.translation().norm();
  s.head_mount_deg = RadToDeg(Eigen::AngleAxisd(errors.head_mount.linear()).angle());
  for (double scale : errors.camera_focal_scale) {
    s.max_focal_pct = std::max(s.max_focal_pct, 100.0 * std::abs(scale - 1.0));
  }
  return s;
}

}  // namespace hgrasp::sim
