#pragma once
/// @file Kalman filter for the gripper's pose X_CE with constant-velocity dynamics (paper
/// section 3: "The filter employs a constant velocity dynamics model, assuming the motion of the
/// gripper to be smooth").
///
/// Form chosen. The paper (and Taylor & Kleeman 2001) filters the LEDs' *image* measurements with
/// an iterated extended Kalman filter whose measurement model projects the LED model through the
/// pose into both cameras. Here the filter runs at the *pose* level on measured poses: the LEDs
/// are already triangulated to 3D points by scan/ and FitGripperPose turns them into X_CE in
/// closed form, so the filter sees a direct, linear measurement of its own state:
///  - translation: a linear Kalman filter on (p_CE, v_CE), exact for constant-velocity motion;
///  - rotation: an error-state (multiplicative) filter. The nominal state keeps the unit
///    quaternion q_CE and the angular velocity w_C (in C); the covariance is over the rotation
///    error dtheta with R_true = Exp(dtheta) * R_est (left error, in C). A measured R_CE gives the
///    residual Log(R_meas * R_est^T); the correction Exp(K r) is multiplied on, so the quaternion
///    stays unit without constraints or singularities.
/// Trade-off: the pose-level filter is cheap (12-state, no projection Jacobians, no iteration)
/// and independent of the camera model, but it needs >= 3 non-collinear LEDs seen in both cameras
/// in a frame to produce a measurement, and it treats the fitted pose's noise as Gaussian with a
/// fixed covariance (given per update), ignoring how the triangulation error grows with depth and
/// varies with LED geometry. The image-level IEKF can use any single visible LED (partial
/// observations, as when the paper flashes LEDs one at a time at start-up) and weighs each pixel
/// correctly; UpdatePosition() below covers the paper's start-up step (the LEDs' mean position).
///
/// State order of the 12 x 12 covariance: [dp_C (3), dv_C (3), dtheta_C (3), dw_C (3)].
/// Process noise: white acceleration and white angular acceleration with spectral densities
/// q_a (m^2/s^3) and q_alpha (rad^2/s^3) per axis (the continuous Wiener-process model).

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "common/geometry.h"

namespace hgrasp::servo {

/// Defaults: q ~ a^2 * tau for accelerations a over a time tau. A Puma-held gripper under a
/// proportional servo changes speed by ~0.1 m/s and ~0.3 rad/s over ~1 s, so q_a ~ 0.01 and
/// q_alpha ~ 0.1. Lower values smooth more but lag when the arm accelerates; tune against the
/// innovations (Update's return value should average 6 for pose updates).
struct PoseFilterOptions {
  double accel_psd = 0.01;            ///< q_a, m^2/s^3: spectral density of the white acceleration
  double angular_accel_psd = 0.1;     ///< q_alpha, rad^2/s^3: same for angular acceleration
  double initial_velocity_std = 0.2;  ///< m/s, per axis, at Initialise
  double initial_angular_velocity_std = 1.0;  ///< rad/s, per axis, at Initialise
  double initial_rotation_std = 3.0;          ///< rad, per axis, after InitialisePosition (unknown)
  double converged_position_std = 0.002;      ///< m: converged() when every position std is below
  double converged_rotation_std = 0.02;       ///< rad: ... and every rotation std is below this
};

/// Standard deviations of a measured pose, per axis (position in m, rotation in rad, in C).
struct PoseMeasurementNoise {
  double position_std = 0.002;
  double rotation_std = 0.02;
};

class PoseFilter {
 public:
  using Matrix12d = Eigen::Matrix<double, 12, 12>;
  using Matrix6d = Eigen::Matrix<double, 6, 6>;

  /// @throws InputError when an option is not finite or not positive.
  explicit PoseFilter(const PoseFilterOptions& options = {});

  /// Starts from a first measured pose: pose = X_CE, zero velocities, covariance from `noise` and
  /// the options' initial velocity std devs.
  void Initialise(const Pose3& X_CE, const PoseMeasurementNoise& noise);

  /// Starts from a position only (the paper's start-up: the LEDs' mean position): orientation
  /// identity with options.initial_rotation_std, zero velocities.
  void InitialisePosition(const Eigen::Vector3d& p_CE, double position_std);

  /// Forgets everything; initialised() becomes false.
  void Reset();

  /// Propagates the state by dt (s) under constant velocity and adds process noise.
  /// dt == 0 does nothing. @throws InputError for dt < 0 or non-finite; aborts if not
  /// initialised.
  void Predict(double dt);

  /// Fuses a measured pose X_CE (e.g. from FitGripperPose) with 6x6 covariance
  /// [position (m^2); rotation error (rad^2) as Log(R_meas R_true^T)].
  /// @return the normalised innovation squared r^T S^-1 r (chi-square, 6 dof), for gating.
  /// Aborts if not initialised. @throws InputError for a non-finite pose or covariance.
  double Update(const Pose3& X_CE, const Matrix6d& covariance);
  double Update(const Pose3& X_CE, const PoseMeasurementNoise& noise);

  /// Fuses a measured position only (3 dof), e.g. the LEDs' mean. @return NIS (3 dof).
  double UpdatePosition(const Eigen::Vector3d& p_CE, double position_std);

  /// The gripper was moved by X_EEnew, expressed in its own frame (a relative move commanded to
  /// the arm, not watched): the pose becomes X_CE X_EEnew with its covariance carried, plus the
  /// move's own error (`error`, per axis); the velocities become zero (the arm has stopped
  /// again), as uncertain as they were and uncorrelated with the new pose.
  void MoveBy(const Pose3& X_EEnew, const PoseMeasurementNoise& error);

  /// Re-expresses the state in another frame N, given X_NC (the camera moved: N is the camera's
  /// new pose, X_NC where the old one is seen from it). Position, velocity, orientation,
  /// angular velocity and the covariance (all in C, left rotation error) are carried exactly.
  void ChangeFrame(const Pose3& X_NC);

  bool initialised() const { return initialised_; }
  /// True when every position std dev and every rotation std dev is below the options' limits.
  bool converged() const;

  Pose3 pose() const;                                             ///< X_CE estimate
  const Eigen::Vector3d& position() const { return p_; }          ///< p_CE, m
  const Eigen::Quaterniond& orientation() const { return q_; }    ///< R_CE
  const Eigen::Vector3d& velocity() const { return v_; }          ///< in C, m/s
  const Eigen::Vector3d& angular_velocity() const { return w_; }  ///< in C, rad/s
  const Matrix12d& covariance() const { return P_; }
  Eigen::Vector3d position_std() const;  ///< m, per C axis
  Eigen::Vector3d rotation_std() const;  ///< rad, per C axis
  const PoseFilterOptions& options() const { return options_; }

 private:
  void Correct(const Eigen::VectorXd& r, const Eigen::MatrixXd& H, const Eigen::MatrixXd& R,
               double* nis);

  PoseFilterOptions options_;
  bool initialised_ = false;
  Eigen::Vector3d p_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_ = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_ = Eigen::Quaterniond::Identity();
  Eigen::Vector3d w_ = Eigen::Vector3d::Zero();
  Matrix12d P_ = Matrix12d::Identity();
};

/// Exp map of so(3): the rotation by angle |v| about v / |v|.
Eigen::Quaterniond ExpRotation(const Eigen::Vector3d& v);
/// Log map: the rotation vector (angle in [0, pi]) of q.
Eigen::Vector3d LogRotation(const Eigen::Quaterniond& q);

}  // namespace hgrasp::servo
