#pragma once
/// @file Poses, planes and small geometry helpers. Names follow monogram notation (DESIGN.md
/// rule 4): X_AB is the pose of frame B in frame A, p_AQ point Q in A, R_AB a rotation.

#include <Eigen/Geometry>

namespace hgrasp {

using Pose3 = Eigen::Isometry3d;  ///< rigid transform X_AB; p_AQ = X_AB * p_BQ

/// A plane {p : n.dot(p) + d = 0} with unit normal n, in the frame named by the variable.
struct Plane {
  Eigen::Vector3d n = Eigen::Vector3d::UnitX();
  double d = 0.0;

  /// Signed distance of p from the plane (m), positive on the side n points to.
  double SignedDistance(const Eigen::Vector3d& p) const { return n.dot(p) + d; }

  /// The plane expressed in frame A, given this plane in frame B and X_AB.
  Plane TransformedBy(const Pose3& X_AB) const {
    Plane out;
    out.n = X_AB.linear() * n;
    out.d = d - out.n.dot(X_AB.translation());
    return out;
  }

  /// Mirror image of point p across the plane.
  Eigen::Vector3d Reflect(const Eigen::Vector3d& p) const {
    return p - 2.0 * SignedDistance(p) * n;
  }

  /// Mirror image of another plane across this one.
  Plane Reflect(const Plane& other) const {
    const Eigen::Vector3d p0 = -other.d * other.n;  // a point of `other`
    Plane out;
    out.n = other.n - 2.0 * n.dot(other.n) * n;
    out.d = -out.n.dot(Reflect(p0));
    return out;
  }
};

constexpr double kPi = 3.14159265358979323846;
constexpr double DegToRad(double deg) { return deg * kPi / 180.0; }
constexpr double RadToDeg(double rad) { return rad * 180.0 / kPi; }

/// Rotation about W z by yaw (rad).
inline Eigen::Matrix3d RotZ(double yaw) {
  return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

}  // namespace hgrasp
