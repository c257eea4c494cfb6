#include "servo/pose_filter.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <random>

#include "common/error.h"

namespace hgrasp::servo {
namespace {

constexpr double kDt = 0.04;  // 25 frames/s, the cameras' rate

// A gripper moving with constant linear and angular velocity in C, and noisy measured poses.
struct Truth {
  Eigen::Vector3d p0{0.05, -0.02, 0.45};
  Eigen::Vector3d v{0.04, -0.03, 0.02};  // m/s
  Eigen::Quaterniond q0{Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())};
  Eigen::Vector3d w{0.15, -0.1, 0.2};  // rad/s, in C

  Pose3 At(double t) const {
    Pose3 X = Pose3::Identity();
    X.translation() = p0 + v * t;
    X.linear() = (ExpRotation(w * t) * q0).toRotationMatrix();
    return X;
  }
};

class Noise {
 public:
  Noise(unsigned seed, PoseMeasurementNoise sigma) : rng_(seed), sigma_(sigma) {}
  Pose3 Measure(const Pose3& X) {
    Pose3 Z = X;
    Z.translation() += sigma_.position_std * Draw();
    Z.linear() = ExpRotation(sigma_.rotation_std * Draw()).toRotationMatrix() * X.linear();
    return Z;
  }

 private:
  Eigen::Vector3d Draw() { return {n_(rng_), n_(rng_), n_(rng_)}; }
  std::mt19937 rng_;
  std::normal_distribution<double> n_{0.0, 1.0};
  PoseMeasurementNoise sigma_;
};

// The truth moves at exactly constant velocity, so the filter is tuned for little acceleration:
// tracking index sqrt(q dt^3) / sigma ~ 0.04 (position) and 0.013 (rotation).
PoseFilterOptions SmoothOptions() {
  PoseFilterOptions o;
  o.accel_psd = 1e-4;
  o.angular_accel_psd = 1e-3;
  return o;
}

double RotationError(const Pose3& A, const Pose3& B) {
  return Eigen::AngleAxisd(A.linear() * B.linear().transpose()).angle();
}

struct RunFigures {
  double raw_pos_rms = 0, filt_pos_rms = 0, raw_rot_rms = 0, filt_rot_rms = 0, mean_nis = 0;
  Pose3 final_pose;
  Eigen::Vector3d final_v, final_w;
};

// Runs `steps` frames; statistics over frames >= `settle`.
RunFigures RunTrack(unsigned seed, int steps, int settle, PoseFilter* filter) {
  const Truth truth;
  const PoseMeasurementNoise sigma{0.002, 0.02};
  Noise noise(seed, sigma);
  RunFigures f;
  filter->Initialise(noise.Measure(truth.At(0.0)), sigma);
  int n = 0;
  for (int k = 1; k < steps; ++k) {
    const double t = k * kDt;
    filter->Predict(kDt);
    const Pose3 z = noise.Measure(truth.At(t));
    const double nis = filter->Update(z, sigma);
    if (k < settle) continue;
    ++n;
    const Pose3 X = truth.At(t);
    f.raw_pos_rms += (z.translation() - X.translation()).squaredNorm();
    f.filt_pos_rms += (filter->pose().translation() - X.translation()).squaredNorm();
    f.raw_rot_rms += std::pow(RotationError(z, X), 2);
    f.filt_rot_rms += std::pow(RotationError(filter->pose(), X), 2);
    f.mean_nis += nis;
  }
  f.raw_pos_rms = std::sqrt(f.raw_pos_rms / n);
  f.filt_pos_rms = std::sqrt(f.filt_pos_rms / n);
  f.raw_rot_rms = std::sqrt(f.raw_rot_rms / n);
  f.filt_rot_rms = std::sqrt(f.filt_rot_rms / n);
  f.mean_nis /= n;
  f.final_pose = filter->pose();
  f.final_v = filter->velocity();
  f.final_w = filter->angular_velocity();
  return f;
}

TEST(PoseFilterTest, ConstantVelocityTargetIsSmoothedWellBelowTheMeasurementNoise) {
  PoseFilter filter(SmoothOptions());
  const RunFigures f = RunTrack(42, 400, 100, &filter);
  std::printf(
      "position rms: raw %.3f mm, filtered %.3f mm (ratio %.2f); rotation rms: raw %.2f "
      "mrad, filtered %.2f mrad (ratio %.2f); mean NIS %.2f (6 expected)\n",
      f.raw_pos_rms * 1e3, f.filt_pos_rms * 1e3, f.filt_pos_rms / f.raw_pos_rms,
      f.raw_rot_rms * 1e3, f.filt_rot_rms * 1e3, f.filt_rot_rms / f.raw_rot_rms, f.mean_nis);
  EXPECT_LT(f.filt_pos_rms / f.raw_pos_rms, 0.6);
  EXPECT_LT(f.filt_rot_rms / f.raw_rot_rms, 0.6);
  EXPECT_TRUE(filter.converged());
}

TEST(PoseFilterTest, VelocitiesAreEstimated) {
  PoseFilter filter(SmoothOptions());
  const Truth truth;
  const RunFigures f = RunTrack(43, 400, 100, &filter);
  std::printf("velocity error %.2f mm/s, angular velocity error %.1f mrad/s\n",
              (f.final_v - truth.v).norm() * 1e3, (f.final_w - truth.w).norm() * 1e3);
  EXPECT_LT((f.final_v - truth.v).norm(), 0.005);
  EXPECT_LT((f.final_w - truth.w).norm(), 0.05);
}

TEST(PoseFilterTest, InnovationsAreConsistentWithTheirCovariance) {
  PoseFilter filter(SmoothOptions());
  const RunFigures f = RunTrack(44, 600, 100, &filter);
  // Normalised innovation squared of a 6-dof measurement: mean 6 when the filter is consistent.
  EXPECT_GT(f.mean_nis, 4.5);
  EXPECT_LT(f.mean_nis, 7.5);
}

TEST(PoseFilterTest, PredictionBridgesTenMissingMeasurements) {
  PoseFilter filter(SmoothOptions());
  const Truth truth;
  RunTrack(45, 200, 100, &filter);
  const double pos_std_before = filter.position_std().maxCoeff();
  const Eigen::Matrix<double, 12, 1> var_before = filter.covariance().diagonal();
  for (int k = 200; k < 210; ++k) filter.Predict(kDt);  // frames 200..209 have no measurement
  const Pose3 X = truth.At(209 * kDt);
  const double pos_err = (filter.pose().translation() - X.translation()).norm();
  const double rot_err = RotationError(filter.pose(), X);
  std::printf(
      "after 10 missed frames (0.4 s): position error %.3f mm (std %.3f -> %.3f mm), "
      "rotation error %.2f mrad\n",
      pos_err * 1e3, pos_std_before * 1e3, filter.position_std().maxCoeff() * 1e3, rot_err * 1e3);
  // Dead reckoning over 0.4 s: the target moved ~21 mm; the estimate stays within the raw
  // measurement noise (3.5 mm rms) and within 3 of its own standard deviations.
  EXPECT_GT((truth.At(209 * kDt).translation() - truth.At(199 * kDt).translation()).norm(), 0.015);
  EXPECT_LT(pos_err, 0.0035);
  EXPECT_LT(pos_err, 3.0 * filter.position_std().norm());
  EXPECT_LT(rot_err, 0.03);
  // Uncertainty grows while blind, in every state, and shrinks again once measurements return.
  EXPECT_TRUE((filter.covariance().diagonal().array() > var_before.array()).all());
  const double pos_std_blind = filter.position_std().maxCoeff();
  const PoseMeasurementNoise sigma{0.002, 0.02};
  Noise noise(145, sigma);
  for (int k = 210; k < 215; ++k) {
    filter.Predict(kDt);
    filter.Update(noise.Measure(truth.At(k * kDt)), sigma);
  }
  EXPECT_LT(filter.position_std().maxCoeff(), 0.5 * pos_std_blind);
}

TEST(PoseFilterTest, AngularMotionIsTracked) {
  // A fast spin (1 rad/s about a tilted axis): without the angular velocity state the estimate
  // would lag; with it the error stays at the smoothed noise level.
  PoseFilter filter(SmoothOptions());
  Truth truth;
  truth.w = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  const PoseMeasurementNoise sigma{0.002, 0.02};
  Noise noise(46, sigma);
  filter.Initialise(noise.Measure(truth.At(0.0)), sigma);
  double sum_err2 = 0.0;
  int n = 0;
  for (int k = 1; k < 300; ++k) {
    filter.Predict(kDt);
    filter.Update(noise.Measure(truth.At(k * kDt)), sigma);
    if (k >= 100) {
      sum_err2 += std::pow(RotationError(filter.pose(), truth.At(k * kDt)), 2);
      ++n;
    }
  }
  const double rms = std::sqrt(sum_err2 / n);
  std::printf(
      "spin at 1 rad/s (%.1f rad in all): rotation rms %.2f mrad, "
      "angular velocity error %.1f mrad/s\n",
      299 * kDt, rms * 1e3, (filter.angular_velocity() - truth.w).norm() * 1e3);
  EXPECT_LT(rms, 0.6 * std::sqrt(3.0) * sigma.rotation_std);
  EXPECT_LT((filter.angular_velocity() - truth.w).norm(), 0.05);
}

TEST(PoseFilterTest, CovarianceShrinksWithMeasurementsAndConverges) {
  PoseFilterOptions options = SmoothOptions();
  options.converged_position_std = 0.003;
  options.converged_rotation_std = 0.03;
  PoseFilter filter(options);
  const PoseMeasurementNoise sigma{0.005, 0.05};  // coarser than the convergence limits
  const Truth truth;
  Noise noise(47, sigma);
  filter.Initialise(noise.Measure(truth.At(0.0)), sigma);
  EXPECT_FALSE(filter.converged());
  double prev_pos = filter.position_std().maxCoeff();
  double prev_rot = filter.rotation_std().maxCoeff();
  int converged_at = -1;
  for (int k = 1; k < 50; ++k) {
    filter.Predict(kDt);
    filter.Update(noise.Measure(truth.At(k * kDt)), sigma);
    const double pos = filter.position_std().maxCoeff();
    const double rot = filter.rotation_std().maxCoeff();
    if (k < 10) {  // early on each update removes more than the prediction adds
      EXPECT_LT(pos, prev_pos) << k;
      EXPECT_LT(rot, prev_rot) << k;
    }
    prev_pos = pos;
    prev_rot = rot;
    if (converged_at < 0 && filter.converged()) converged_at = k;
  }
  std::printf("converged after %d updates: position std %.3f mm, rotation std %.2f mrad\n",
              converged_at, prev_pos * 1e3, prev_rot * 1e3);
  EXPECT_GT(converged_at, 0);
  EXPECT_LT(converged_at, 30);
  const PoseFilter::Matrix12d& P = filter.covariance();
  EXPECT_LT((P - P.transpose()).norm(), 1e-15);
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<PoseFilter::Matrix12d>(P).eigenvalues().minCoeff(), 0);
}

TEST(PoseFilterTest, StartsFromTheLedsMeanPositionWithUnknownOrientation) {
  // Paper section 3: the filter is initialised with the LEDs' average position, then pose
  // measurements bring in the orientation.
  PoseFilter filter(SmoothOptions());
  const Truth truth;
  filter.InitialisePosition(truth.At(0.0).translation() + Eigen::Vector3d(0.01, 0, 0), 0.02);
  EXPECT_FALSE(filter.converged());
  EXPECT_GT(filter.rotation_std().minCoeff(), 1.0);
  filter.UpdatePosition(truth.At(0.0).translation(), 0.005);
  const PoseMeasurementNoise sigma{0.002, 0.02};
  Noise noise(48, sigma);
  for (int k = 1; k < 60; ++k) {
    filter.Predict(kDt);
    filter.Update(noise.Measure(truth.At(k * kDt)), sigma);
  }
  const Pose3 X = truth.At(59 * kDt);
  EXPECT_LT((filter.pose().translation() - X.translation()).norm(), 0.003);
  EXPECT_LT(RotationError(filter.pose(), X), 0.03);
  EXPECT_TRUE(filter.converged());
}

TEST(PoseFilterTest, IsDeterministic) {
  PoseFilter a(SmoothOptions()), b(SmoothOptions());
  const RunFigures fa = RunTrack(99, 150, 50, &a);
  const RunFigures fb = RunTrack(99, 150, 50, &b);
  EXPECT_EQ(fa.final_pose.matrix(), fb.final_pose.matrix());
  EXPECT_EQ(a.covariance(), b.covariance());
}

TEST(PoseFilterTest, ResetForgetsTheState) {
  PoseFilter filter(SmoothOptions());
  RunTrack(1, 20, 10, &filter);
  EXPECT_TRUE(filter.initialised());
  filter.Reset();
  EXPECT_FALSE(filter.initialised());
  EXPECT_FALSE(filter.converged());
}

TEST(PoseFilterTest, BadInputThrows) {
  PoseFilterOptions bad;
  bad.accel_psd = -1.0;
  EXPECT_THROW(PoseFilter{bad}, InputError);
  PoseFilter filter(SmoothOptions());
  filter.Initialise(Pose3::Identity(), {});
  EXPECT_THROW(filter.Predict(-0.01), InputError);
  EXPECT_THROW(filter.Update(Pose3::Identity(), PoseMeasurementNoise{0.0, 0.01}), InputError);
  PoseFilter::Matrix6d not_pd = PoseFilter::Matrix6d::Identity();
  not_pd(2, 2) = -1.0;
  EXPECT_THROW(filter.Update(Pose3::Identity(), not_pd), InputError);
}

// By hand: a gripper turned 90 deg about z in C, moved 10 mm along its own x, ends 10 mm along
// C's y; a rotation error about z then moves that end sideways (dp' = dp - [R t]x dtheta), so
// the end's x variance gains (10 mm)^2 var(theta_z); the move's own error adds; velocities
// are zero, as uncertain as before, and uncorrelated with the pose.
TEST(PoseFilterTest, MoveByCarriesThePoseAndItsUncertaintyThroughARelativeMove) {
  PoseFilter filter(SmoothOptions());
  Pose3 X_CE = Pose3::Identity();
  X_CE.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  X_CE.translation() = Eigen::Vector3d(0.1, 0.2, 0.5);
  filter.Initialise(X_CE, {0.001, 0.01});
  Pose3 move = Pose3::Identity();
  move.translation() = Eigen::Vector3d(0.01, 0.0, 0.0);
  move.linear() = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  filter.MoveBy(move, {0.002, 0.03});
  EXPECT_LT((filter.position() - Eigen::Vector3d(0.1, 0.21, 0.5)).norm(), 1e-12);
  EXPECT_LT((filter.pose().linear() - (X_CE.linear() * move.linear())).norm(), 1e-12);
  const PoseFilter::Matrix12d& P = filter.covariance();
  EXPECT_NEAR(P(0, 0), 1e-6 + 0.01 * 0.01 * 1e-4 + 4e-6, 1e-15);  // x: dp, [R t]x dtheta_z, move
  EXPECT_NEAR(P(1, 1), 1e-6 + 4e-6, 1e-15);                      // y: along the move
  EXPECT_NEAR(P(8, 8), 1e-4 + 9e-4, 1e-15);                      // theta_z
  EXPECT_NEAR(P(0, 8), -0.01 * 1e-4, 1e-15);                     // x and theta_z correlate
  EXPECT_EQ(filter.velocity(), Eigen::Vector3d::Zero());
  EXPECT_EQ(filter.angular_velocity(), Eigen::Vector3d::Zero());
  EXPECT_TRUE((P.block<3, 3>(3, 0).isZero(0.0)));
  EXPECT_NEAR(P(3, 3), filter.options().initial_velocity_std * filter.options().initial_velocity_std,
              1e-15);  // as uncertain as at Initialise
  Pose3 bad = move;
  bad.translation().x() = NAN;
  EXPECT_THROW(filter.MoveBy(bad, {}), InputError);
  EXPECT_THROW(filter.MoveBy(move, {0.0, 0.01}), InputError);
}

TEST(RotationMapsTest, ExpAndLogAreInverse) {
  for (const Eigen::Vector3d& v : {Eigen::Vector3d(0.1, -0.2, 0.3), Eigen::Vector3d(1e-14, 0, 0),
                                   Eigen::Vector3d(0, 3.1, 0)}) {
    EXPECT_LT((LogRotation(ExpRotation(v)) - v).norm(), 1e-12) << v.transpose();
  }
}

// The head turns mid-track: a filter carried into the new camera frame N and fed the same
// measurements seen from N ends exactly where the filter that stayed in C ends, seen from N.
TEST(PoseFilterTest, ChangeFrameCarriesStateAndCovariance) {
  const Truth truth;
  Noise noise(11, {0.002, 0.02});
  Pose3 X_NC = Pose3::Identity();
  X_NC.linear() = ExpRotation(Eigen::Vector3d(0.1, -0.25, 0.05)).toRotationMatrix();
  X_NC.translation() = Eigen::Vector3d(0.03, 0.01, -0.02);
  // Anisotropic measurement covariance (in C), and the same seen from N.
  PoseFilter::Matrix6d cov_C = PoseFilter::Matrix6d::Zero();
  cov_C.diagonal() << 1e-6, 4e-6, 16e-6, 1e-4, 4e-4, 9e-4;
  PoseFilter::Matrix6d J = PoseFilter::Matrix6d::Zero();
  J.topLeftCorner<3, 3>() = J.bottomRightCorner<3, 3>() = X_NC.linear();
  const PoseFilter::Matrix6d cov_N = J * cov_C * J.transpose();
  PoseFilter in_c, carried;
  in_c.Initialise(truth.At(0), {0.002, 0.02});
  carried.Initialise(truth.At(0), {0.002, 0.02});
  for (int k = 1; k <= 40; ++k) {
    const Pose3 z = noise.Measure(truth.At(k * kDt));
    in_c.Predict(kDt);
    in_c.Update(z, cov_C);
    carried.Predict(kDt);
    if (k < 20) {
      carried.Update(z, cov_C);
    } else {
      if (k == 20) carried.ChangeFrame(X_NC);
      carried.Update(X_NC * z, cov_N);
    }
  }
  const Pose3 expected = X_NC * in_c.pose();
  EXPECT_LT((carried.pose().translation() - expected.translation()).norm(), 1e-9);
  EXPECT_LT(RotationError(carried.pose(), expected), 1e-9);
  EXPECT_LT((carried.velocity() - X_NC.linear() * in_c.velocity()).norm(), 1e-9);
  EXPECT_LT((carried.angular_velocity() - X_NC.linear() * in_c.angular_velocity()).norm(), 1e-9);
  PoseFilter::Matrix12d J12 = PoseFilter::Matrix12d::Zero();
  for (int b = 0; b < 4; ++b) J12.block<3, 3>(3 * b, 3 * b) = X_NC.linear();
  EXPECT_LT((carried.covariance() - J12 * in_c.covariance() * J12.transpose()).norm(),
            1e-9 * in_c.covariance().norm());
}

}  // namespace
}  // namespace hgrasp::servo
