#include "servo/control_law.h"

#include <cmath>
#include <string>

#include "common/error.h"
#include "servo/pose_filter.h"

namespace hgrasp::servo {
namespace {

void Require(bool ok, const std::string& field, double value, const std::string& expected) {
  if (!ok) throw InputError("ControlLawOptions", field, std::to_string(value), expected);
}

// v scaled down (not reversed) so that |v| <= limit.
Eigen::Vector3d ClampNorm(const Eigen::Vector3d& v, double limit) {
  const double n = v.norm();
  return n > limit ? Eigen::Vector3d(v * (limit / n)) : v;
}

bool IsValid(const ControlLawOptions& o) {
  auto gain_ok = [](double g) { return std::isfinite(g) && g > 0.0 && g <= 1.0; };
  auto pos_ok = [](double x) { return std::isfinite(x) && x > 0.0; };
  return gain_ok(o.translation_gain) && gain_ok(o.rotation_gain) &&
         pos_ok(o.max_translation_step) && pos_ok(o.max_rotation_step) &&
         pos_ok(o.translation_tolerance) && pos_ok(o.rotation_tolerance);
}

}  // namespace

void ValidateControlLawOptions(const ControlLawOptions& o) {
  auto gain_ok = [](double g) { return std::isfinite(g) && g > 0.0 && g <= 1.0; };
  auto pos_ok = [](double x) { return std::isfinite(x) && x > 0.0; };
  Require(gain_ok(o.translation_gain), "translation_gain", o.translation_gain, "in (0, 1]");
  Require(gain_ok(o.rotation_gain), "rotation_gain", o.rotation_gain, "in (0, 1]");
  Require(pos_ok(o.max_translation_step), "max_translation_step", o.max_translation_step,
          "a positive length (m)");
  Require(pos_ok(o.max_rotation_step), "max_rotation_step", o.max_rotation_step,
          "a positive angle (rad)");
  Require(pos_ok(o.translation_tolerance), "translation_tolerance", o.translation_tolerance,
          "a positive length (m)");
  Require(pos_ok(o.rotation_tolerance), "rotation_tolerance", o.rotation_tolerance,
          "a positive angle (rad)");
}

ServoError ComputeServoError(const Pose3& X_CE, const Pose3& X_CT) {
  ServoError e;
  e.X_ET = X_CE.inverse(Eigen::Isometry) * X_CT;
  e.p_ET = e.X_ET.translation();
  e.theta_ET = LogRotation(Eigen::Quaterniond(e.X_ET.linear()).normalized());
  e.translation_m = e.p_ET.norm();
  e.rotation_rad = e.theta_ET.norm();
  return e;
}

ServoCommand ComputeServoCommand(const Pose3& X_CE, const Pose3& X_CT,
                                 const ControlLawOptions& options) {
  HGRASP_DEMAND_MSG(IsValid(options), "ControlLawOptions not validated");
  ServoCommand cmd;
  cmd.error = ComputeServoError(X_CE, X_CT);
  cmd.converged = cmd.error.translation_m <= options.translation_tolerance &&
                  cmd.error.rotation_rad <= options.rotation_tolerance;
  if (cmd.converged) return cmd;
  const Eigen::Vector3d p_EEnew =
      ClampNorm(options.translation_gain * cmd.error.p_ET, options.max_translation_step);
  const Eigen::Vector3d theta_EEnew =
      ClampNorm(options.rotation_gain * cmd.error.theta_ET, options.max_rotation_step);
  cmd.X_EEnew.setIdentity();
  cmd.X_EEnew.linear() = ExpRotation(theta_EEnew).toRotationMatrix();
  cmd.X_EEnew.translation() = p_EEnew;
  return cmd;
}

}  // namespace hgrasp::servo
