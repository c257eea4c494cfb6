#include "servo/pose_filter.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <cmath>
#include <string>

#include "common/error.h"

namespace hgrasp::servo {
namespace {

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// Left Jacobian of SO(3): Exp(phi + d) ~= Exp(J_l(phi) d) Exp(phi) for small d.
Eigen::Matrix3d LeftJacobian(const Eigen::Vector3d& phi) {
  const double th = phi.norm();
  const Eigen::Matrix3d K = Skew(phi);
  if (th < 1e-6) return Eigen::Matrix3d::Identity() + 0.5 * K + K * K / 6.0;
  return Eigen::Matrix3d::Identity() + (1.0 - std::cos(th)) / (th * th) * K +
         (th - std::sin(th)) / (th * th * th) * K * K;
}

void CheckPositive(double v, const char* field) {
  if (!std::isfinite(v) || v <= 0.0) {
    throw InputError("", std::string("PoseFilterOptions.") + field, std::to_string(v),
                     "a finite value > 0");
  }
}

void CheckStd(double v, const char* field) {
  if (!std::isfinite(v) || v <= 0.0) {
    throw InputError("", field, std::to_string(v), "a finite standard deviation > 0");
  }
}

}  // namespace

Eigen::Quaterniond ExpRotation(const Eigen::Vector3d& v) {
  const double th = v.norm();
  if (th < 1e-12)
    return Eigen::Quaterniond(1.0, 0.5 * v.x(), 0.5 * v.y(), 0.5 * v.z()).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(th, v / th));
}

Eigen::Vector3d LogRotation(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.normalized();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();  // same rotation, angle in [0, pi]
  const double s = q.vec().norm();
  if (s < 1e-12) return 2.0 * q.vec();  // small angle: 2 * sin(th/2) * axis ~= th * axis
  const double th = 2.0 * std::atan2(s, q.w());
  return th / s * q.vec();
}

PoseFilter::PoseFilter(const PoseFilterOptions& options) : options_(options) {
  CheckPositive(options.accel_psd, "accel_psd");
  CheckPositive(options.angular_accel_psd, "angular_accel_psd");
  CheckPositive(options.initial_velocity_std, "initial_velocity_std");
  CheckPositive(options.initial_angular_velocity_std, "initial_angular_velocity_std");
  CheckPositive(options.initial_rotation_std, "initial_rotation_std");
  CheckPositive(options.converged_position_std, "converged_position_std");
  CheckPositive(options.converged_rotation_std, "converged_rotation_std");
}

void PoseFilter::Initialise(const Pose3& X_CE, const PoseMeasurementNoise& noise) {
  CheckStd(noise.position_std, "PoseMeasurementNoise.position_std");
  CheckStd(noise.rotation_std, "PoseMeasurementNoise.rotation_std");
  if (!X_CE.matrix().allFinite()) {
    throw InputError("", "X_CE", "non-finite", "a finite rigid transform");
  }
  p_ = X_CE.translation();
  q_ = Eigen::Quaterniond(X_CE.rotation()).normalized();
  v_.setZero();
  w_.setZero();
  P_.setZero();
  const double sp = noise.position_std, sr = noise.rotation_std;
  const double sv = options_.initial_velocity_std, sw = options_.initial_angular_velocity_std;
  P_.block<3, 3>(0, 0).diagonal().setConstant(sp * sp);
  P_.block<3, 3>(3, 3).diagonal().setConstant(sv * sv);
  P_.block<3, 3>(6, 6).diagonal().setConstant(sr * sr);
  P_.block<3, 3>(9, 9).diagonal().setConstant(sw * sw);
  initialised_ = true;
}

void PoseFilter::InitialisePosition(const Eigen::Vector3d& p_CE, double position_std) {
  CheckStd(position_std, "position_std");
  if (!p_CE.allFinite()) throw InputError("", "p_CE", "non-finite", "a finite position (m)");
  Pose3 X = Pose3::Identity();
  X.translation() = p_CE;
  Initialise(X, {position_std, options_.initial_rotation_std});
}

void PoseFilter::Reset() {
  initialised_ = false;
  p_.setZero();
  v_.setZero();
  q_.setIdentity();
  w_.setZero();
  P_.setIdentity();
}

void PoseFilter::MoveBy(const Pose3& X_EEnew, const PoseMeasurementNoise& error) {
  HGRASP_DEMAND_MSG(initialised_, "PoseFilter::MoveBy before Initialise");
  CheckStd(error.position_std, "PoseMeasurementNoise.position_std");
  CheckStd(error.rotation_std, "PoseMeasurementNoise.rotation_std");
  if (!X_EEnew.matrix().allFinite()) {
    throw InputError("", "X_EEnew", "non-finite", "a finite rigid transform");
  }
  // p' = p + R t and R' = R R_EEnew; with R_true = Exp(dtheta) R, dp' = dp - [R t]x dtheta and
  // dtheta' = dtheta.
  const Eigen::Vector3d Rt = q_ * X_EEnew.translation();
  p_ += Rt;
  q_ = (q_ * Eigen::Quaterniond(X_EEnew.rotation())).normalized();
  Matrix12d J = Matrix12d::Identity();
  J.block<3, 3>(0, 6) = -Skew(Rt);
  P_ = J * P_ * J.transpose();
  P_.block<3, 3>(0, 0).diagonal().array() += error.position_std * error.position_std;
  P_.block<3, 3>(6, 6).diagonal().array() += error.rotation_std * error.rotation_std;
  // At rest again: zero velocities, as uncertain as they were, uncorrelated with the new pose.
  v_.setZero();
  w_.setZero();
  const Eigen::Matrix3d Pv = P_.block<3, 3>(3, 3), Pw = P_.block<3, 3>(9, 9);
  for (int block : {3, 9}) {
    P_.middleRows(block, 3).setZero();
    P_.middleCols(block, 3).setZero();
  }
  P_.block<3, 3>(3, 3) = Pv;
  P_.block<3, 3>(9, 9) = Pw;
}

void PoseFilter::Predict(double dt) {
  HGRASP_DEMAND_MSG(initialised_, "PoseFilter::Predict before Initialise");
  if (!std::isfinite(dt) || dt < 0.0) {
    throw InputError("", "dt", std::to_string(dt), "a finite time step >= 0 (s)");
  }
  if (dt == 0.0) return;

  const Eigen::Vector3d phi = w_ * dt;
  const Eigen::Quaterniond dq = ExpRotation(phi);
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();

  // Error-state transition: dp' = dp + dv dt; dv' = dv;
  // dtheta' = Exp(w dt) dtheta + J_l(w dt) dw dt; dw' = dw.
  Matrix12d F = Matrix12d::Identity();
  F.block<3, 3>(0, 3) = I * dt;
  F.block<3, 3>(6, 6) = dq.toRotationMatrix();
  F.block<3, 3>(6, 9) = LeftJacobian(phi) * dt;

  // Continuous white (angular) acceleration integrated over dt.
  Matrix12d Q = Matrix12d::Zero();
  const double dt2 = dt * dt, dt3 = dt2 * dt;
  for (int k = 0; k < 2; ++k) {
    const double q = k == 0 ? options_.accel_psd : options_.angular_accel_psd;
    const int o = 6 * k;
    Q.block<3, 3>(o, o) = I * (q * dt3 / 3.0);
    Q.block<3, 3>(o, o + 3) = I * (q * dt2 / 2.0);
    Q.block<3, 3>(o + 3, o) = I * (q * dt2 / 2.0);
    Q.block<3, 3>(o + 3, o + 3) = I * (q * dt);
  }

  p_ += v_ * dt;
  q_ = (dq * q_).normalized();
  P_ = F * P_ * F.transpose() + Q;
  P_ = 0.5 * (P_ + P_.transpose()).eval();
}

double PoseFilter::Update(const Pose3& X_CE, const Matrix6d& covariance) {
  HGRASP_DEMAND_MSG(initialised_, "PoseFilter::Update before Initialise");
  if (!X_CE.matrix().allFinite()) {
    throw InputError("", "X_CE", "non-finite", "a finite rigid transform");
  }
  if (!covariance.allFinite() || !covariance.isApprox(covariance.transpose(), 1e-9) ||
      Eigen::LLT<Matrix6d>(covariance).info() != Eigen::Success) {
    throw InputError("", "covariance", "not symmetric positive definite",
                     "a 6x6 symmetric positive definite covariance");
  }
  const Eigen::Quaterniond q_meas(X_CE.rotation());
  Eigen::VectorXd r(6);
  r.head<3>() = X_CE.translation() - p_;
  r.tail<3>() = LogRotation(q_meas * q_.conjugate());
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(6, 12);
  H.block<3, 3>(0, 0).setIdentity();
  H.block<3, 3>(3, 6).setIdentity();
  double nis = 0.0;
  Correct(r, H, covariance, &nis);
  return nis;
}

double PoseFilter::Update(const Pose3& X_CE, const PoseMeasurementNoise& noise) {
  CheckStd(noise.position_std, "PoseMeasurementNoise.position_std");
  CheckStd(noise.rotation_std, "PoseMeasurementNoise.rotation_std");
  Matrix6d R = Matrix6d::Zero();
  R.diagonal().head<3>().setConstant(noise.position_std * noise.position_std);
  R.diagonal().tail<3>().setConstant(noise.rotation_std * noise.rotation_std);
  return Update(X_CE, R);
}

double PoseFilter::UpdatePosition(const Eigen::Vector3d& p_CE, double position_std) {
  HGRASP_DEMAND_MSG(initialised_, "PoseFilter::UpdatePosition before Initialise");
  CheckStd(position_std, "position_std");
  if (!p_CE.allFinite()) throw InputError("", "p_CE", "non-finite", "a finite position (m)");
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(3, 12);
  H.block<3, 3>(0, 0).setIdentity();
  const Eigen::MatrixXd R = Eigen::Matrix3d::Identity() * (position_std * position_std);
  double nis = 0.0;
  Correct(p_CE - p_, H, R, &nis);
  return nis;
}

void PoseFilter::Correct(const Eigen::VectorXd& r, const Eigen::MatrixXd& H,
                         const Eigen::MatrixXd& R, double* nis) {
  const Eigen::MatrixXd S = H * P_ * H.transpose() + R;
  const Eigen::LDLT<Eigen::MatrixXd> S_ldlt(S);
  HGRASP_DEMAND_MSG(S_ldlt.info() == Eigen::Success, "innovation covariance not invertible");
  const Eigen::MatrixXd K = S_ldlt.solve(H * P_).transpose();  // P H^T S^-1 (P, S symmetric)
  *nis = r.dot(S_ldlt.solve(r));
  const Eigen::Matrix<double, 12, 1> dx = K * r;

  // Inject the error state into the nominal state.
  p_ += dx.segment<3>(0);
  v_ += dx.segment<3>(3);
  q_ = (ExpRotation(dx.segment<3>(6)) * q_).normalized();
  w_ += dx.segment<3>(9);

  // Joseph form keeps P symmetric positive semi-definite. The reset Jacobian of the rotation
  // error (I - 0.5 [dtheta]x) is taken as identity: dtheta is small after convergence.
  const Matrix12d IKH = Matrix12d::Identity() - K * H;
  P_ = IKH * P_ * IKH.transpose() + K * R * K.transpose();
  P_ = 0.5 * (P_ + P_.transpose()).eval();
}

bool PoseFilter::converged() const {
  return initialised_ && (position_std().array() < options_.converged_position_std).all() &&
         (rotation_std().array() < options_.converged_rotation_std).all();
}

void PoseFilter::ChangeFrame(const Pose3& X_NC) {
  HGRASP_DEMAND_MSG(initialised_, "PoseFilter::ChangeFrame before Initialise");
  const Eigen::Matrix3d R = X_NC.linear();
  p_ = R * p_ + X_NC.translation();
  v_ = R * v_;
  q_ = (Eigen::Quaterniond(R) * q_).normalized();
  w_ = R * w_;
  Matrix12d J = Matrix12d::Zero();
  for (int k = 0; k < 4; ++k) J.block<3, 3>(3 * k, 3 * k) = R;
  P_ = J * P_ * J.transpose();
}

Pose3 PoseFilter::pose() const {
  Pose3 X = Pose3::Identity();
  X.linear() = q_.toRotationMatrix();
  X.translation() = p_;
  return X;
}

Eigen::Vector3d PoseFilter::position_std() const {
  return P_.diagonal().segment<3>(0).cwiseMax(0.0).cwiseSqrt();
}

Eigen::Vector3d PoseFilter::rotation_std() const {
  return P_.diagonal().segment<3>(6).cwiseMax(0.0).cwiseSqrt();
}

}  // namespace hgrasp::servo
