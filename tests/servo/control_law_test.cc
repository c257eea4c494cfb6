#include "servo/control_law.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "common/error.h"
#include "servo/pose_filter.h"

namespace hgrasp::servo {
namespace {

Pose3 MakePose(const Eigen::Vector3d& theta, const Eigen::Vector3d& p) {
  Pose3 X = Pose3::Identity();
  X.linear() = ExpRotation(theta).toRotationMatrix();
  X.translation() = p;
  return X;
}

Eigen::Vector3d RandomUnit(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
}

// A random pose of the gripper as the cameras see it: 0.3-0.6 m in front, any orientation.
Pose3 RandomCameraPose(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-0.15, 0.15), z(0.3, 0.6), a(0.0, kPi);
  return MakePose(a(rng) * RandomUnit(rng), Eigen::Vector3d(u(rng), u(rng), z(rng)));
}

// A random offset of up to max_m and max_rad.
Pose3 RandomOffset(std::mt19937& rng, double max_m, double max_rad) {
  std::uniform_real_distribution<double> f(0.0, 1.0);
  return MakePose(f(rng) * max_rad * RandomUnit(rng), f(rng) * max_m * RandomUnit(rng));
}

double TranslationError(const Pose3& A, const Pose3& B) {
  return (A.translation() - B.translation()).norm();
}
double RotationError(const Pose3& A, const Pose3& B) {
  return Eigen::AngleAxisd(A.linear().transpose() * B.linear()).angle();
}

TEST(ControlLawTest, ZeroErrorAtTarget) {
  std::mt19937 rng(1);
  for (int i = 0; i < 10; ++i) {
    const Pose3 X_CT = RandomCameraPose(rng);
    const ServoCommand cmd = ComputeServoCommand(X_CT, X_CT);
    EXPECT_LT(cmd.error.translation_m, 1e-12);
    EXPECT_LT(cmd.error.rotation_rad, 1e-7);
    EXPECT_TRUE(cmd.converged);
    EXPECT_TRUE(cmd.X_EEnew.isApprox(Pose3::Identity(), 1e-12));
  }
}

TEST(ControlLawTest, ErrorIsExpressedInTheGripperFrame) {
  std::mt19937 rng(2);
  for (int i = 0; i < 10; ++i) {
    const Pose3 X_CE = RandomCameraPose(rng);
    // 1 cm along the gripper's own x, whatever the camera sees.
    const Pose3 X_CT = X_CE * MakePose(Eigen::Vector3d::Zero(), Eigen::Vector3d(0.01, 0, 0));
    const ServoError e = ComputeServoError(X_CE, X_CT);
    EXPECT_NEAR((e.p_ET - Eigen::Vector3d(0.01, 0, 0)).norm(), 0.0, 1e-12);
    EXPECT_LT(e.rotation_rad, 1e-7);
    const ServoCommand cmd = ComputeServoCommand(X_CE, X_CT);
    EXPECT_GT(cmd.X_EEnew.translation().x(), 0.0);
    EXPECT_NEAR(cmd.X_EEnew.translation().y(), 0.0, 1e-12);
    EXPECT_NEAR(cmd.X_EEnew.translation().z(), 0.0, 1e-12);

    // 10 deg about the gripper's own z.
    const Pose3 X_CT2 = X_CE * MakePose(Eigen::Vector3d(0, 0, DegToRad(10)), {0, 0, 0});
    const ServoError e2 = ComputeServoError(X_CE, X_CT2);
    EXPECT_NEAR((e2.theta_ET - Eigen::Vector3d(0, 0, DegToRad(10))).norm(), 0.0, 1e-9);
    EXPECT_LT(e2.translation_m, 1e-12);
  }
}

TEST(ControlLawTest, FullGainUnlimitedStepLandsOnTarget) {
  ControlLawOptions o;
  o.translation_gain = o.rotation_gain = 1.0;
  o.max_translation_step = 1.0;
  o.max_rotation_step = kPi;
  std::mt19937 rng(3);
  for (int i = 0; i < 10; ++i) {
    const Pose3 X_CE = RandomCameraPose(rng);
    const Pose3 X_CT = X_CE * RandomOffset(rng, 0.1, DegToRad(30));
    const ServoCommand cmd = ComputeServoCommand(X_CE, X_CT, o);
    EXPECT_TRUE((X_CE * cmd.X_EEnew).isApprox(X_CT, 1e-9));
  }
}

TEST(ControlLawTest, StepsRespectTheLimits) {
  ControlLawOptions o;
  o.translation_gain = o.rotation_gain = 1.0;
  std::mt19937 rng(4);
  for (int i = 0; i < 20; ++i) {
    const Pose3 X_CE = RandomCameraPose(rng);
    const Pose3 X_CT = X_CE * RandomOffset(rng, 0.2, DegToRad(90));
    const ServoCommand cmd = ComputeServoCommand(X_CE, X_CT, o);
    EXPECT_LE(cmd.X_EEnew.translation().norm(), o.max_translation_step + 1e-12);
    EXPECT_LE(Eigen::AngleAxisd(cmd.X_EEnew.linear()).angle(), o.max_rotation_step + 1e-9);
    // The step points along the error (scaled down, never turned).
    EXPECT_GT(cmd.X_EEnew.translation().dot(cmd.error.p_ET), 0.0);
  }
}

TEST(ControlLawTest, ValidateRejectsBadOptions) {
  ControlLawOptions o;
  EXPECT_NO_THROW(ValidateControlLawOptions(o));
  o.translation_gain = 1.5;
  EXPECT_THROW(ValidateControlLawOptions(o), InputError);
  o = {};
  o.max_rotation_step = 0.0;
  EXPECT_THROW(ValidateControlLawOptions(o), InputError);
  o = {};
  o.translation_tolerance = std::nan("");
  EXPECT_THROW(ValidateControlLawOptions(o), InputError);
}

// How the simulated arm executes a commanded MoveRelative.
struct ArmModel {
  double gain = 1.0;  // executed / commanded, translation and rotation angle alike
  Pose3 Execute(const Pose3& X_EEnew) const {
    const Eigen::Vector3d theta = LogRotation(Eigen::Quaterniond(X_EEnew.linear()));
    return MakePose(gain * theta, gain * X_EEnew.translation());
  }
};

struct LoopResult {
  int iterations = 0;  // MoveRelative commands issued
  bool converged = false;
  Pose3 X_BE = Pose3::Identity();  // the arm's final gripper pose in its base
};

// Servo loop: the arm keeps X_BE (its base B) and integrates each move in its gripper frame; the
// cameras see X_CE = X_CB * X_BE through the true camera-to-base transform X_CB, which the law
// never gets. `measure` adds measurement noise.
template <typename Measure>
LoopResult RunLoop(const Pose3& X_CB, Pose3 X_BE, const Pose3& X_CT, const ArmModel& arm,
                   const ControlLawOptions& o, Measure measure, int max_iterations) {
  LoopResult r;
  for (int it = 0; it <= max_iterations; ++it) {
    const ServoCommand cmd = ComputeServoCommand(measure(X_CB * X_BE), X_CT, o);
    if (cmd.converged) {
      r.converged = true;
      break;
    }
    X_BE = X_BE * arm.Execute(cmd.X_EEnew);
    ++r.iterations;
  }
  r.X_BE = X_BE;
  return r;
}

constexpr int kMaxIterations = 30;

TEST(ControlLawTest, ClosedLoopConvergesFromRandomStarts) {
  const ControlLawOptions o;
  std::mt19937 rng(5);
  std::vector<int> counts;
  for (int i = 0; i < 20; ++i) {
    const Pose3 X_CT = RandomCameraPose(rng);
    const Pose3 X_CE0 = X_CT * RandomOffset(rng, 0.10, DegToRad(30));
    const LoopResult r = RunLoop(
        Pose3::Identity(), X_CE0, X_CT, ArmModel{}, o, [](const Pose3& X) { return X; },
        kMaxIterations);
    ASSERT_TRUE(r.converged) << "start " << i;
    EXPECT_LE(TranslationError(r.X_BE, X_CT), o.translation_tolerance);
    EXPECT_LE(RotationError(r.X_BE, X_CT), o.rotation_tolerance);
    counts.push_back(r.iterations);
  }
  std::printf("ideal arm: iterations min %d max %d over %zu starts\n",
              *std::min_element(counts.begin(), counts.end()),
              *std::max_element(counts.begin(), counts.end()), counts.size());
}

TEST(ControlLawTest, NoCameraToBaseCalibrationNeeded) {
  const ControlLawOptions o;
  std::mt19937 rng(6);
  // Where the cameras are believed to be relative to the arm's base, and where they really are:
  // displaced by 2 cm and 3 deg. The law is given neither.
  const Pose3 X_CB_nominal =
      MakePose(Eigen::Vector3d(DegToRad(110), 0, 0), Eigen::Vector3d(0.2, 0.3, 0.5));
  const Pose3 X_CB_true =
      X_CB_nominal * MakePose(DegToRad(3) * Eigen::Vector3d(1, 1, 0).normalized(),
                              0.02 * Eigen::Vector3d(1, -1, 1).normalized());
  int worst = 0;
  for (int i = 0; i < 15; ++i) {
    const Pose3 X_CT = RandomCameraPose(rng);
    const Pose3 X_BE0 =
        X_CB_true.inverse(Eigen::Isometry) * X_CT * RandomOffset(rng, 0.10, DegToRad(30));
    const LoopResult r = RunLoop(
        X_CB_true, X_BE0, X_CT, ArmModel{}, o, [](const Pose3& X) { return X; }, kMaxIterations);
    ASSERT_TRUE(r.converged) << "start " << i;
    const Pose3 X_CE = X_CB_true * r.X_BE;  // what really happened, in the camera frame
    EXPECT_LE(TranslationError(X_CE, X_CT), o.translation_tolerance);
    EXPECT_LE(RotationError(X_CE, X_CT), o.rotation_tolerance);
    // A look-then-move controller using the nominal calibration would have sent the gripper to
    // X_CB_nominal^-1 * X_CT in the base: centimetres away from where it has to go.
    const Pose3 X_BT_nominal = X_CB_nominal.inverse(Eigen::Isometry) * X_CT;
    EXPECT_GT(TranslationError(r.X_BE, X_BT_nominal), 0.01);
    worst = std::max(worst, r.iterations);
  }
  std::printf("calibration off by 2 cm / 3 deg: worst %d iterations\n", worst);
}

TEST(ControlLawTest, ConvergesWithArmGainErrorAndMeasurementNoise) {
  const ControlLawOptions o;
  const double kSigmaP = 0.001, kSigmaR = DegToRad(0.5);  // per axis
  for (double gain : {0.9, 1.1}) {
    std::mt19937 rng(gain < 1.0 ? 7 : 8);
    std::normal_distribution<double> n(0.0, 1.0);
    auto measure = [&](const Pose3& X) {
      const Eigen::Vector3d dp(n(rng), n(rng), n(rng)), dr(n(rng), n(rng), n(rng));
      return MakePose(kSigmaR * dr, kSigmaP * dp) * X;
    };
    double worst_p = 0.0, worst_r = 0.0;
    int worst_it = 0;
    for (int i = 0; i < 15; ++i) {
      const Pose3 X_CT = RandomCameraPose(rng);
      const Pose3 X_CE0 = X_CT * RandomOffset(rng, 0.10, DegToRad(30));
      const LoopResult r =
          RunLoop(Pose3::Identity(), X_CE0, X_CT, ArmModel{gain}, o, measure, kMaxIterations);
      ASSERT_TRUE(r.converged) << "gain " << gain << " start " << i;
      worst_p = std::max(worst_p, TranslationError(r.X_BE, X_CT));
      worst_r = std::max(worst_r, RotationError(r.X_BE, X_CT));
      worst_it = std::max(worst_it, r.iterations);
    }
    std::printf(
        "arm gain %.1f, noise 1 mm / 0.5 deg per axis: worst %d iterations, true final error "
        "worst %.2f mm / %.2f deg\n",
        gain, worst_it, worst_p * 1e3, RadToDeg(worst_r));
    // Stopped on a noisy measurement: the true error is within the tolerance plus ~3 sigma.
    EXPECT_LT(worst_p, o.translation_tolerance + 3.0 * std::sqrt(3.0) * kSigmaP);
    EXPECT_LT(worst_r, o.rotation_tolerance + 3.0 * std::sqrt(3.0) * kSigmaR);
  }
}

}  // namespace
}  // namespace hgrasp::servo
