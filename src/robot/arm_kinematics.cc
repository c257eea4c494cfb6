#include "robot/arm_kinematics.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "common/error.h"

namespace hgrasp::robot {
namespace {

using Eigen::Vector3d;

/// e^(xi theta) for a revolute joint of unit axis w through r.
Pose3 Exp(const Vector3d& w, const Vector3d& r, double theta) {
  Pose3 X = Pose3::Identity();
  X.linear() = Eigen::AngleAxisd(theta, w).toRotationMatrix();
  X.translation() = r - X.linear() * r;
  return X;
}

double Wrap(double a) {
  a = std::remainder(a, 2.0 * kPi);  // [-pi, pi]
  return a <= -kPi ? a + 2.0 * kPi : a;
}

/// Subproblem 1: the angle that turns p onto q about the axis (w, r).
double RotateOnto(const Vector3d& w, const Vector3d& r, const Vector3d& p, const Vector3d& q) {
  const Vector3d u = p - r, v = q - r;
  const Vector3d up = u - w * w.dot(u), vp = v - w * w.dot(v);
  return std::atan2(w.dot(up.cross(vp)), up.dot(vp));
}

/// Subproblem 2: (theta1, theta2) with e^(w1 theta1) e^(w2 theta2) p = q, the axes meeting at r.
/// Two solutions, one (twice) at tangency, none when no rotation reaches q.
std::vector<std::pair<double, double>> RotateTwiceOnto(const Vector3d& w1, const Vector3d& w2,
                                                       const Vector3d& r, const Vector3d& p,
                                                       const Vector3d& q) {
  const Vector3d u = p - r, v = q - r;
  const double c12 = w1.dot(w2);
  const double den = c12 * c12 - 1.0;
  const double alpha = (c12 * w2.dot(u) - w1.dot(v)) / den;
  const double beta = (c12 * w1.dot(v) - w2.dot(u)) / den;
  const Vector3d n = w1.cross(w2);
  double gamma2 =
      (u.squaredNorm() - alpha * alpha - beta * beta - 2.0 * alpha * beta * c12) / n.squaredNorm();
  // Rounding at tangency: a tiny negative is zero (relative to |u|^2).
  if (gamma2 < 0.0 && gamma2 > -1e-12 * std::max(u.squaredNorm(), 1e-12)) gamma2 = 0.0;
  if (gamma2 < 0.0) return {};
  std::vector<std::pair<double, double>> out;
  for (const double sign : {1.0, -1.0}) {
    const Vector3d c = r + alpha * w1 + beta * w2 + sign * std::sqrt(gamma2) * n;
    out.emplace_back(RotateOnto(w1, r, c, q), RotateOnto(w2, r, p, c));
  }
  return out;
}

/// Subproblem 3: the angles that turn p about (w, r) to distance delta from q.
std::vector<double> RotateToDistance(const Vector3d& w, const Vector3d& r, const Vector3d& p,
                                     const Vector3d& q, double delta) {
  const Vector3d u = p - r, v = q - r;
  const Vector3d up = u - w * w.dot(u), vp = v - w * w.dot(v);
  const double along = w.dot(p - q);
  const double delta_p2 = delta * delta - along * along;
  const double nu = up.norm(), nv = vp.norm();
  if (nu < 1e-12 || nv < 1e-12) return {};
  double c = (nu * nu + nv * nv - delta_p2) / (2.0 * nu * nv);
  if (c > 1.0 && c < 1.0 + 1e-12) c = 1.0;
  if (c < -1.0 && c > -1.0 - 1e-12) c = -1.0;
  if (c > 1.0 || c < -1.0) return {};
  const double theta0 = std::atan2(w.dot(up.cross(vp)), up.dot(vp));
  const double half = std::acos(c);
  return {theta0 + half, theta0 - half};
}

/// The point where two axes (w1 through r1, w2 through r2) meet, or throws naming them.
Vector3d Meet(const Vector3d& w1, const Vector3d& r1, const Vector3d& w2, const Vector3d& r2,
              const std::string& what) {
  // Closest points r1 + s w1 and r2 + t w2.
  const Vector3d d = r2 - r1;
  const double b = w1.dot(w2);
  const double den = 1.0 - b * b;
  if (den < 1e-12) throw InputError("", what, "parallel axes", "axes that meet at a point");
  const double s = (w1.dot(d) - b * w2.dot(d)) / den;
  const double t = (b * w1.dot(d) - w2.dot(d)) / den;
  const Vector3d a = r1 + s * w1, c = r2 + t * w2;
  if ((a - c).norm() > 1e-6) {
    throw InputError("", what, std::to_string((a - c).norm()) + " m apart",
                     "axes that meet at a point (a Puma's shoulder and wrist)");
  }
  return 0.5 * (a + c);
}

}  // namespace

ArmKinematics ArmKinematics::FromTree(const KinematicTree& tree, const std::string& side) {
  ArmKinematics arm;
  for (int i = 0; i < 6; ++i) {
    const std::string joint = side + "_j" + std::to_string(i + 1);
    const Pose3 X_WJ = tree.LinkPose(tree.ChildLink(joint), {});
    arm.w_[i] = (X_WJ.linear() * tree.Axis(joint)).normalized();
    arm.r_[i] = X_WJ.translation();
    const KinematicTree::JointLimits limits = tree.Limits(joint);
    arm.lower_[i] = limits.lower;
    arm.upper_[i] = limits.upper;
  }
  arm.M_ = tree.LinkPose(side + "_gripper", {});
  for (int k = 1; k <= 6; ++k) {
    const std::string link = side + "_link" + std::to_string(k);
    const Pose3 X_WL = tree.LinkPose(link, {});
    for (const KinematicTree::Cylinder& c : tree.Cylinders(link)) {
      const Pose3 X_WG = X_WL * c.X_LG;
      // An arm's tube (long: the MJCF collides it as a capsule of the same extent) is the
      // capsule inside it; a joint's drum (short) the capsule around it.
      const double inset = c.length >= 4.0 * c.radius ? c.radius : 0.0;
      const Vector3d half = (0.5 * c.length - inset) * X_WG.linear().col(2);
      arm.capsules_.push_back(
          {k, {X_WG.translation() - half, X_WG.translation() + half, c.radius}});
    }
  }
  arm.shoulder_ = Meet(arm.w_[0], arm.r_[0], arm.w_[1], arm.r_[1], side + " joints 1 and 2");
  arm.wrist_ = Meet(arm.w_[3], arm.r_[3], arm.w_[4], arm.r_[4], side + " joints 4 and 5");
  const Vector3d to_axis6 = arm.wrist_ - arm.r_[5];
  if ((to_axis6 - arm.w_[5] * arm.w_[5].dot(to_axis6)).norm() > 1e-6) {
    throw InputError("", side + " joint 6", "off the wrist centre",
                     "an axis through the wrist centre of joints 4 and 5");
  }
  return arm;
}

std::vector<Capsule> ArmKinematics::LinkCapsules(const device::Joint6& q) const {
  std::array<Pose3, 7> X;  // X[k]: the product of the first k exponentials
  X[0] = Pose3::Identity();
  for (int i = 0; i < 6; ++i) X[i + 1] = X[i] * Exp(w_[i], r_[i], q[i]);
  std::vector<Capsule> out;
  out.reserve(capsules_.size());
  for (const LinkCapsule& c : capsules_) {
    out.push_back({X[c.joints] * c.at_zero.a, X[c.joints] * c.at_zero.b, c.at_zero.radius});
  }
  return out;
}

Pose3 ArmKinematics::Forward(const device::Joint6& q) const {
  Pose3 X = Pose3::Identity();
  for (int i = 0; i < 6; ++i) X = X * Exp(w_[i], r_[i], q[i]);
  return X * M_;
}

Eigen::Matrix<double, 6, 6> ArmKinematics::Jacobian(const device::Joint6& q) const {
  Eigen::Matrix<double, 6, 6> J;
  Pose3 X = Pose3::Identity();  // the product of the exponentials before joint i
  std::array<Vector3d, 6> w, r;
  for (int i = 0; i < 6; ++i) {
    w[i] = X.linear() * w_[i];
    r[i] = X * r_[i];
    X = X * Exp(w_[i], r_[i], q[i]);
  }
  const Vector3d p = (X * M_).translation();
  for (int i = 0; i < 6; ++i) {
    J.block<3, 1>(0, i) = w[i].cross(p - r[i]);
    J.block<3, 1>(3, i) = w[i];
  }
  return J;
}

Eigen::Vector3d ArmKinematics::ForearmDirection(const device::Joint6& q) const {
  const Pose3 E12 = Exp(w_[0], r_[0], q[0]) * Exp(w_[1], r_[1], q[1]);
  const Pose3 E123 = E12 * Exp(w_[2], r_[2], q[2]);
  const Vector3d w4 = E123.linear() * w_[3];
  return (E123 * wrist_ - E12 * r_[2]).dot(w4) >= 0.0 ? w4 : Vector3d(-w4);
}

std::vector<ArmIkSolution> ArmKinematics::Inverse(const Pose3& X_WE) const {
  const Pose3 g = X_WE * M_.inverse();  // e^(xi_1 q_1) ... e^(xi_6 q_6)
  const Vector3d wrist_target = g * wrist_;
  const double reach = (wrist_target - shoulder_).norm();
  // A point on axis 6 away from the wrist centre, and one off axis 6.
  const Vector3d on6 = wrist_ + w_[5];
  Vector3d off = w_[5].cross(Vector3d::UnitX());
  if (off.norm() < 0.5) off = w_[5].cross(Vector3d::UnitY());
  const Vector3d off6 = wrist_ + off.normalized();

  std::vector<ArmIkSolution> out;
  const std::vector<double> q3s = RotateToDistance(w_[2], r_[2], wrist_, shoulder_, reach);
  for (size_t e = 0; e < q3s.size(); ++e) {
    const Pose3 E3 = Exp(w_[2], r_[2], q3s[e]);
    const auto q12s = RotateTwiceOnto(w_[0], w_[1], shoulder_, E3 * wrist_, wrist_target);
    for (size_t s = 0; s < q12s.size(); ++s) {
      const auto [q1, q2] = q12s[s];
      const Pose3 E123 = Exp(w_[0], r_[0], q1) * Exp(w_[1], r_[1], q2) * E3;
      const Pose3 h = E123.inverse() * g;  // e^(xi_4 q_4) e^(xi_5 q_5) e^(xi_6 q_6)
      const auto q45s = RotateTwiceOnto(w_[3], w_[4], wrist_, on6, h * on6);
      for (size_t k = 0; k < q45s.size(); ++k) {
        const auto [q4, q5] = q45s[k];
        const Pose3 E6 = (Exp(w_[3], r_[3], q4) * Exp(w_[4], r_[4], q5)).inverse() * h;
        const double q6 = RotateOnto(w_[5], wrist_, off6, E6 * off6);
        ArmIkSolution sol;
        sol.q << Wrap(q1), Wrap(q2), Wrap(q3s[e]), Wrap(q4), Wrap(q5), Wrap(q6);
        sol.shoulder = s == 1;
        sol.elbow = e == 1;
        sol.wrist = k == 1;
        // A tangent subproblem gives one solution twice: keep one.
        const bool duplicate = std::any_of(out.begin(), out.end(), [&](const ArmIkSolution& o) {
          return (o.q - sol.q).cwiseAbs().maxCoeff() < 1e-12;
        });
        if (!duplicate) out.push_back(sol);
      }
    }
  }
  return out;
}

bool ArmKinematics::WithinLimits(const device::Joint6& q) const {
  for (int i = 0; i < 6; ++i) {
    if (!(q[i] >= lower_[i] && q[i] <= upper_[i])) return false;
  }
  return true;
}

}  // namespace hgrasp::robot
