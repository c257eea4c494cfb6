#include "servo/head_tracking.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "common/error.h"

namespace hgrasp::servo {
namespace {

// Angular offsets of p_AQ from the z axis of A: (atan2(x, z), atan2(y, z)).
Eigen::Vector2d AxisOffsets(const Eigen::Vector3d& p_AQ) {
  return {std::atan2(p_AQ.x(), p_AQ.z()), std::atan2(p_AQ.y(), p_AQ.z())};
}

double AngleFromAxis(const Eigen::Vector3d& p_AQ) {
  return std::atan2(p_AQ.head<2>().norm(), p_AQ.z());
}

}  // namespace

HeadTracker::HeadTracker(robot::HeadKinematics kinematics, const HeadTrackingOptions& options)
    : kinematics_(std::move(kinematics)), options_(options) {
  const auto& o = options_;
  if (!(std::isfinite(o.gain) && o.gain > 0.0 && o.gain <= 1.0)) {
    throw InputError("HeadTrackingOptions", "gain", std::to_string(o.gain), "in (0, 1]");
  }
  if (!(std::isfinite(o.max_step) && o.max_step > 0.0)) {
    throw InputError("HeadTrackingOptions", "max_step", std::to_string(o.max_step),
                     "a positive angle (rad)");
  }
  if (!(std::isfinite(o.deadband) && o.deadband >= 0.0)) {
    throw InputError("HeadTrackingOptions", "deadband", std::to_string(o.deadband),
                     "a non-negative angle (rad)");
  }
  if (o.measurement_camera != robot::HeadKinematics::kLeft &&
      o.measurement_camera != robot::HeadKinematics::kRight) {
    throw InputError("HeadTrackingOptions", "measurement_camera",
                     std::to_string(o.measurement_camera), "0 (left) or 1 (right)");
  }
  const auto pan = kinematics_.tree().Limits("head_pan");
  const auto tilt = kinematics_.tree().Limits("head_tilt");
  pan_lower_ = pan.lower;
  pan_upper_ = pan.upper;
  tilt_lower_ = tilt.lower;
  tilt_upper_ = tilt.upper;
}

Pose3 HeadTracker::X_WAim(const device::HeadJoints& q) const {
  using K = robot::HeadKinematics;
  switch (options_.aim) {
    case AimFrame::kLeft:
      return kinematics_.X_WC(K::kLeft, q);
    case AimFrame::kRight:
      return kinematics_.X_WC(K::kRight, q);
    case AimFrame::kCyclopean: {
      const Pose3 X_WCL = kinematics_.X_WC(K::kLeft, q);
      const Pose3 X_WCR = kinematics_.X_WC(K::kRight, q);
      const Eigen::Quaterniond q_L(X_WCL.linear()), q_R(X_WCR.linear());
      Pose3 X_WY = Pose3::Identity();
      X_WY.linear() = q_L.slerp(0.5, q_R).toRotationMatrix();
      X_WY.translation() = 0.5 * (X_WCL.translation() + X_WCR.translation());
      return X_WY;
    }
  }
  HGRASP_DEMAND_MSG(false, "unknown AimFrame");
}

HeadTrackingResult HeadTracker::Track(const device::HeadJoints& q,
                                      const Eigen::Vector3d& p_CE) const {
  const Eigen::Vector3d p_WE = kinematics_.X_WC(options_.measurement_camera, q) * p_CE;
  auto offsets_at = [&](double pan, double tilt) {
    device::HeadJoints qq = q;
    qq.pan = pan;
    qq.tilt = tilt;
    return AxisOffsets(X_WAim(qq).inverse(Eigen::Isometry) * p_WE);
  };

  HeadTrackingResult result;
  result.q = q;
  const Eigen::Vector3d p_AE = X_WAim(q).inverse(Eigen::Isometry) * p_WE;
  result.offset_before_rad = AngleFromAxis(p_AE);
  result.offset_after_rad = result.offset_before_rad;
  if (result.offset_before_rad <= options_.deadband) return result;

  // Gauss-Newton on (pan, tilt) with a forward-difference Jacobian; pan mostly moves the
  // horizontal offset and tilt the vertical one, so a few iterations suffice.
  Eigen::Vector2d x(q.pan, q.tilt);
  constexpr double kH = 1e-7;
  for (int it = 0; it < 20; ++it) {
    const Eigen::Vector2d r = offsets_at(x[0], x[1]);
    if (r.norm() < 1e-10) break;
    Eigen::Matrix2d J;
    J.col(0) = (offsets_at(x[0] + kH, x[1]) - r) / kH;
    J.col(1) = (offsets_at(x[0], x[1] + kH) - r) / kH;
    const Eigen::Vector2d dx = J.colPivHouseholderQr().solve(-r);
    if (!dx.allFinite()) break;
    // Limit each Gauss-Newton step to 0.5 rad so that a poor start cannot spin the head around.
    x += dx.norm() > 0.5 ? Eigen::Vector2d(dx * (0.5 / dx.norm())) : dx;
    if (dx.norm() < 1e-12) break;
  }

  Eigen::Vector2d step = options_.gain * (x - Eigen::Vector2d(q.pan, q.tilt));
  step = step.cwiseMax(-options_.max_step).cwiseMin(options_.max_step);
  const double pan = q.pan + step[0];
  const double tilt = q.tilt + step[1];
  result.q.pan = std::clamp(pan, pan_lower_, pan_upper_);
  result.q.tilt = std::clamp(tilt, tilt_lower_, tilt_upper_);
  result.at_limit = result.q.pan != pan || result.q.tilt != tilt;
  result.moved = true;
  result.offset_after_rad = AngleFromAxis(X_WAim(result.q).inverse(Eigen::Isometry) * p_WE);
  return result;
}

Pose3 HeadTracker::X_CnewC(const device::HeadJoints& q_old, const device::HeadJoints& q_new) const {
  const int c = options_.measurement_camera;
  return kinematics_.X_WC(c, q_new).inverse(Eigen::Isometry) * kinematics_.X_WC(c, q_old);
}

Pose3 HeadTracker::CarryThroughHeadMove(const Pose3& X_CT, const device::HeadJoints& q_old,
                                        const device::HeadJoints& q_new) const {
  return X_CnewC(q_old, q_new) * X_CT;
}

}  // namespace hgrasp::servo
