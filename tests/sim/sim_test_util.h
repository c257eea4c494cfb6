#pragma once
// Shared set-up for the simulator tests: scenarios from YAML text, probe bodies, pixel helpers.

#include <mujoco/mujoco.h>

#include <Eigen/Geometry>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <string>

#include "sim/scenario.h"
#include "sim/sim_devices.h"

namespace hgrasp::sim::testing {

inline Scenario ScenarioFromYaml(const std::string& yaml) {
  return ParseScenario(yaml, "test.yaml");
}

/// A mocap body named `name` carrying one geom (no collisions), parked below the table.
inline std::string MocapProbe(const std::string& name, const std::string& geom_attributes) {
  return "<body name=\"" + name + "\" mocap=\"true\" pos=\"0 0 -3\"><geom name=\"" + name + "\" " +
         geom_attributes + " contype=\"0\" conaffinity=\"0\"/></body>\n";
}

/// Places mocap body `name` at X_WB and updates the kinematics.
inline void PlaceMocap(World* world, const std::string& name, const Pose3& X_WB) {
  const mjModel* m = world->model();
  const int mocap = m->body_mocapid[world->Id(mjOBJ_BODY, name)];
  const Eigen::Quaterniond q(X_WB.linear());
  for (int i = 0; i < 3; ++i) world->data()->mocap_pos[3 * mocap + i] = X_WB.translation()[i];
  world->data()->mocap_quat[4 * mocap + 0] = q.w();
  world->data()->mocap_quat[4 * mocap + 1] = q.x();
  world->data()->mocap_quat[4 * mocap + 2] = q.y();
  world->data()->mocap_quat[4 * mocap + 3] = q.z();
  mj_forward(world->model(), world->data());
}

/// Sets a scalar joint's position and its actuator's set-point (if any), then updates kinematics.
inline void SetJoint(World* world, const std::string& joint, double q) {
  const mjModel* m = world->model();
  world->data()->qpos[m->jnt_qposadr[world->Id(mjOBJ_JOINT, joint)]] = q;
  const int a = mj_name2id(m, mjOBJ_ACTUATOR, joint.c_str());
  if (a >= 0) world->data()->ctrl[a] = q;
  mj_forward(world->model(), world->data());
}

/// Pixels of a label image (CV_32S) that show geom `geom`.
inline int LabelPixels(const cv::Mat& label, int geom) {
  int pixels = 0;
  for (int r = 0; r < label.rows; ++r) {
    for (int c = 0; c < label.cols; ++c) pixels += label.at<int>(r, c) == geom;
  }
  return pixels;
}

/// An empty scene: no objects, noise 0.
inline const char* kEmptyScene = "name: empty\nobjects: []\n";

}  // namespace hgrasp::sim::testing
