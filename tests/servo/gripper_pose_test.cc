#include "servo/gripper_pose.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "common/error.h"

namespace hgrasp::servo {
namespace {

// An LED layout like a gripper's: a few cm, not coplanar.
std::vector<Eigen::Vector3d> LedsInGripper() {
  return {{0.03, 0.0, 0.0},    {-0.03, 0.0, 0.0}, {0.0, 0.025, 0.01},
          {0.0, -0.025, 0.01}, {0.01, 0.0, 0.04}, {-0.015, 0.012, -0.02}};
}

Pose3 RandomPose(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  Pose3 X = Pose3::Identity();
  X.linear() = q.normalized().toRotationMatrix();
  X.translation() = Eigen::Vector3d(0.1 * n(rng), 0.1 * n(rng), 0.5 + 0.05 * n(rng));
  return X;
}

std::vector<Eigen::Vector3d> Transform(const Pose3& X, const std::vector<Eigen::Vector3d>& p) {
  std::vector<Eigen::Vector3d> out;
  for (const auto& q : p) out.push_back(X * q);
  return out;
}

double RotationAngle(const Eigen::Matrix3d& R) { return Eigen::AngleAxisd(R).angle(); }

TEST(FitGripperPoseTest, ExactRecoveryFromRandomPoses) {
  std::mt19937 rng(7);
  const auto p_E = LedsInGripper();
  for (int trial = 0; trial < 20; ++trial) {
    const Pose3 X_CE = RandomPose(rng);
    double rms = -1.0;
    const auto fit = FitGripperPose(p_E, Transform(X_CE, p_E), &rms);
    ASSERT_TRUE(fit.has_value());
    EXPECT_LT((fit->linear() - X_CE.linear()).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((fit->translation() - X_CE.translation()).norm(), 1e-12);
    EXPECT_NEAR(fit->linear().determinant(), 1.0, 1e-12);
    EXPECT_LT(rms, 1e-12);
  }
}

TEST(FitGripperPoseTest, ThreePointsAndCoplanarPointsAreEnough) {
  std::mt19937 rng(11);
  const std::vector<Eigen::Vector3d> p_E = {
      {0.03, 0.0, 0.0}, {-0.03, 0.01, 0.0}, {0.0, 0.04, 0.0}, {0.01, -0.02, 0.0}};
  for (size_t n : {3u, 4u}) {
    const std::vector<Eigen::Vector3d> sub(p_E.begin(), p_E.begin() + n);
    const Pose3 X_CE = RandomPose(rng);
    const auto fit = FitGripperPose(sub, Transform(X_CE, sub));
    ASSERT_TRUE(fit.has_value()) << n;
    EXPECT_LT((fit->linear() - X_CE.linear()).cwiseAbs().maxCoeff(), 1e-12) << n;
    EXPECT_LT((fit->translation() - X_CE.translation()).norm(), 1e-12) << n;
  }
}

// With noise sigma per coordinate on N points, the least-squares residual has 3N - 6 degrees of
// freedom: E[rms^2] = sigma^2 (3N - 6) / N; the error at the points' centroid is ~ sigma / sqrt(N)
// per axis.
TEST(FitGripperPoseTest, NoisyPointsGiveErrorsConsistentWithTheNoise) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 1.0);
  const double sigma = 0.001;  // 1 mm, a plausible triangulation error at 0.5 m
  const auto p_E = LedsInGripper();
  const double n = static_cast<double>(p_E.size());
  Eigen::Vector3d c_E = Eigen::Vector3d::Zero();
  for (const auto& q : p_E) c_E += q / n;
  const int trials = 500;
  double sum_rms2 = 0.0, sum_centroid_err2 = 0.0, sum_angle2 = 0.0;
  for (int t = 0; t < trials; ++t) {
    const Pose3 X_CE = RandomPose(rng);
    auto p_C = Transform(X_CE, p_E);
    for (auto& q : p_C) q += sigma * Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    double rms = 0.0;
    const auto fit = FitGripperPose(p_E, p_C, &rms);
    ASSERT_TRUE(fit.has_value());
    sum_rms2 += rms * rms;
    sum_centroid_err2 += ((*fit) * c_E - X_CE * c_E).squaredNorm();
    sum_angle2 += std::pow(RotationAngle(fit->linear() * X_CE.linear().transpose()), 2);
  }
  const double rms_residual = std::sqrt(sum_rms2 / trials);
  const double rms_centroid = std::sqrt(sum_centroid_err2 / trials);
  const double rms_angle = std::sqrt(sum_angle2 / trials);
  const double expected_residual = sigma * std::sqrt((3.0 * n - 6.0) / n);
  const double expected_centroid = sigma * std::sqrt(3.0 / n);
  std::printf(
      "noise %.1f mm, %d LEDs: rms residual %.3f mm (expected %.3f), centroid error "
      "%.3f mm (expected %.3f), rotation error %.2f mrad\n",
      sigma * 1e3, static_cast<int>(n), rms_residual * 1e3, expected_residual * 1e3,
      rms_centroid * 1e3, expected_centroid * 1e3, rms_angle * 1e3);
  EXPECT_NEAR(rms_residual / expected_residual, 1.0, 0.1);
  EXPECT_NEAR(rms_centroid / expected_centroid, 1.0, 0.15);
  // Lever arms of ~3 cm: the rotation error is of order sigma / 0.03 m ~ 33 mrad, and no worse.
  EXPECT_LT(rms_angle, 0.05);
}

TEST(FitGripperPoseTest, MirroredMeasurementStillGivesAProperRotation) {
  const auto p_E = LedsInGripper();
  Pose3 X_CE = Pose3::Identity();
  X_CE.translation() = Eigen::Vector3d(0.0, 0.0, 0.5);
  auto p_C = Transform(X_CE, p_E);
  for (auto& q : p_C) q.x() = -q.x();  // a reflection: no rotation maps p_E onto these exactly
  double rms = 0.0;
  const auto fit = FitGripperPose(p_E, p_C, &rms);
  ASSERT_TRUE(fit.has_value());
  EXPECT_NEAR(fit->linear().determinant(), 1.0, 1e-12);
  EXPECT_LT((fit->linear().transpose() * fit->linear() - Eigen::Matrix3d::Identity()).norm(),
            1e-12);
  EXPECT_GT(rms, 1e-3);  // the mismatch shows in the residual
}

TEST(FitGripperPoseTest, PlanarLedsUnderAReflectionAreNotFlipped) {
  // Coplanar points: the reflection through their plane fits them exactly, so an unguarded
  // Kabsch/Horn solution can return det = -1. The proper rotation must come back.
  std::mt19937 rng(5);
  const std::vector<Eigen::Vector3d> p_E = {
      {0.03, 0.0, 0.0}, {-0.03, 0.01, 0.0}, {0.0, 0.04, 0.0}, {0.01, -0.02, 0.0}};
  for (int t = 0; t < 20; ++t) {
    const Pose3 X_CE = RandomPose(rng);
    const auto fit = FitGripperPose(p_E, Transform(X_CE, p_E));
    ASSERT_TRUE(fit.has_value());
    EXPECT_NEAR(fit->linear().determinant(), 1.0, 1e-12);
    EXPECT_LT((fit->linear() - X_CE.linear()).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(FitGripperPoseTest, TooFewOrCollinearPointsAreRejected) {
  const Pose3 X = Pose3::Identity();
  const std::vector<Eigen::Vector3d> two = {{0, 0, 0}, {0.03, 0, 0}};
  EXPECT_FALSE(FitGripperPose(two, Transform(X, two)).has_value());
  EXPECT_FALSE(FitGripperPose({}, {}).has_value());

  const std::vector<Eigen::Vector3d> line = {
      {0, 0, 0}, {0.01, 0.01, 0}, {0.03, 0.03, 0}, {-0.02, -0.02, 0}};
  EXPECT_FALSE(FitGripperPose(line, Transform(X, line)).has_value());

  std::vector<Eigen::Vector3d> nearly = line;
  nearly[1].z() += 1e-12;  // 1 pm off the line: still not a usable pose
  EXPECT_FALSE(FitGripperPose(nearly, Transform(X, nearly)).has_value());

  // Model fine, measurements collinear (e.g. a bad triangulation): rejected as well.
  const auto p_E = LedsInGripper();
  std::vector<Eigen::Vector3d> p_C(p_E.size());
  for (size_t i = 0; i < p_C.size(); ++i) p_C[i] = Eigen::Vector3d(0.01 * i, 0, 0.5);
  EXPECT_FALSE(FitGripperPose(p_E, p_C).has_value());
}

TEST(FitGripperPoseTest, BadInputThrows) {
  const auto p_E = LedsInGripper();
  auto p_C = p_E;
  p_C.pop_back();
  EXPECT_THROW(FitGripperPose(p_E, p_C), InputError);
  p_C = p_E;
  p_C[2].y() = std::nan("");
  EXPECT_THROW(FitGripperPose(p_E, p_C), InputError);
}

}  // namespace
}  // namespace hgrasp::servo
