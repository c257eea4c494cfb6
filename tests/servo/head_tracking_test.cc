#include "servo/head_tracking.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "common/error.h"
#include "common/paths.h"
#include "common/pinhole_camera.h"
#include "robot/calibration.h"
#include "servo/control_law.h"
#include "servo/pose_filter.h"

namespace hgrasp::servo {
namespace {

using robot::HeadKinematics;

class HeadTrackingTest : public ::testing::Test {
 protected:
  HeadTrackingTest()
      : kinematics_(HeadKinematics::FromUrdfFile(ResolveDataPath("models/humanoid.urdf"))),
        intrinsics_(robot::LoadStereoIntrinsics(ResolveDataPath("calibration/sim/cameras.yaml"))) {}

  // Pixel of p_WQ in `camera` at joints q.
  Eigen::Vector2d Pixel(int camera, const device::HeadJoints& q, const Eigen::Vector3d& p_WQ) {
    const PinholeCamera& cam =
        camera == HeadKinematics::kLeft ? intrinsics_.left : intrinsics_.right;
    const auto uv = cam.Project(kinematics_.X_WC(camera, q).inverse(Eigen::Isometry) * p_WQ);
    EXPECT_TRUE(uv.has_value());
    return uv.value_or(Eigen::Vector2d(-1e9, -1e9));
  }

  Eigen::Vector3d InLeft(const device::HeadJoints& q, const Eigen::Vector3d& p_WQ) {
    return kinematics_.X_WC(HeadKinematics::kLeft, q).inverse(Eigen::Isometry) * p_WQ;
  }

  HeadKinematics kinematics_;
  robot::StereoIntrinsics intrinsics_;
  // Looking down at the workspace (x 0.2-0.4 m in front of the pan axis), slightly verged.
  const device::HeadJoints q0_{0.0, 0.7, 0.1};
};

// Grippers above the workspace, all off-centre in the left image at q0_.
const Eigen::Vector3d kGrippers_W[] = {{0.25, 0.12, 0.15},
                                       {0.35, -0.10, 0.05},
                                       {0.40, 0.15, 0.20},
                                       {0.20, -0.15, 0.10},
                                       {0.30, 0.00, 0.25}};

TEST_F(HeadTrackingTest, BringsTheGripperToTheLeftImageCentre) {
  HeadTrackingOptions o;
  o.max_step = kPi;  // one move
  const HeadTracker tracker(kinematics_, o);
  const Eigen::Vector2d centre(intrinsics_.left.cx, intrinsics_.left.cy);
  for (const Eigen::Vector3d& p_WE : kGrippers_W) {
    const Eigen::Vector2d before = Pixel(HeadKinematics::kLeft, q0_, p_WE);
    const HeadTrackingResult r = tracker.Track(q0_, InLeft(q0_, p_WE));
    ASSERT_TRUE(r.moved);
    EXPECT_FALSE(r.at_limit);
    EXPECT_EQ(r.q.verge, q0_.verge);
    const Eigen::Vector2d after = Pixel(HeadKinematics::kLeft, r.q, p_WE);
    std::printf("left aim: (%.1f, %.1f) px -> (%.3f, %.3f) px; pan %.2f tilt %.2f deg\n",
                before.x(), before.y(), after.x(), after.y(), RadToDeg(r.q.pan),
                RadToDeg(r.q.tilt));
    EXPECT_GT((before - centre).norm(), 10.0);
    EXPECT_LT((after - centre).norm(), 0.5);
    EXPECT_LT(r.offset_after_rad, 1e-6);
  }
}

TEST_F(HeadTrackingTest, CyclopeanAimSplitsTheOffsetBetweenTheCameras) {
  HeadTrackingOptions o;
  o.aim = AimFrame::kCyclopean;
  o.max_step = kPi;
  const HeadTracker tracker(kinematics_, o);
  for (const Eigen::Vector3d& p_WE : kGrippers_W) {
    const HeadTrackingResult r = tracker.Track(q0_, InLeft(q0_, p_WE));
    const Eigen::Vector2d uv_L = Pixel(HeadKinematics::kLeft, r.q, p_WE);
    const Eigen::Vector2d uv_R = Pixel(HeadKinematics::kRight, r.q, p_WE);
    const Eigen::Vector2d d_L = uv_L - Eigen::Vector2d(intrinsics_.left.cx, intrinsics_.left.cy);
    const Eigen::Vector2d d_R = uv_R - Eigen::Vector2d(intrinsics_.right.cx, intrinsics_.right.cy);
    std::printf("cyclopean aim: left (%+.1f, %+.1f) px, right (%+.1f, %+.1f) px from centre\n",
                d_L.x(), d_L.y(), d_R.x(), d_R.y());
    // Disparity stays (the cameras see the point from 14 cm apart) but is split evenly.
    EXPECT_LT(std::abs(d_L.x() + d_R.x()), 2.0);
    EXPECT_LT(std::abs(d_L.y()), 2.0);
    EXPECT_LT(std::abs(d_R.y()), 2.0);
  }
}

TEST_F(HeadTrackingTest, RespectsTiltLimitAndStepLimit) {
  HeadTrackingOptions o;
  o.max_step = kPi;
  const HeadTracker tracker(kinematics_, o);
  const double tilt_upper = kinematics_.tree().Limits("head_tilt").upper;
  // Straight below the head: beyond the tilt range.
  const Eigen::Vector3d p_W(0.0, 0.05, 0.0);
  const HeadTrackingResult r = tracker.Track(q0_, InLeft(q0_, p_W));
  EXPECT_TRUE(r.at_limit);
  EXPECT_DOUBLE_EQ(r.q.tilt, tilt_upper);
  EXPECT_LT(r.offset_after_rad, r.offset_before_rad);

  o.max_step = DegToRad(2.0);
  const HeadTracker slow(kinematics_, o);
  const HeadTrackingResult s = slow.Track(q0_, InLeft(q0_, kGrippers_W[2]));
  EXPECT_LE(std::abs(s.q.pan - q0_.pan), o.max_step + 1e-12);
  EXPECT_LE(std::abs(s.q.tilt - q0_.tilt), o.max_step + 1e-12);
  EXPECT_LT(s.offset_after_rad, s.offset_before_rad);
}

TEST_F(HeadTrackingTest, DeadbandKeepsTheHeadStill) {
  const HeadTracker tracker(kinematics_);
  const Eigen::Vector3d p_C(0.002, -0.002, 0.5);  // 0.3 deg off axis
  const HeadTrackingResult r = tracker.Track(q0_, p_C);
  EXPECT_FALSE(r.moved);
  EXPECT_EQ(r.q.pan, q0_.pan);
  EXPECT_EQ(r.q.tilt, q0_.tilt);
}

TEST_F(HeadTrackingTest, RejectsBadOptions) {
  HeadTrackingOptions o;
  o.gain = 0.0;
  EXPECT_THROW(HeadTracker(kinematics_, o), InputError);
  o = {};
  o.measurement_camera = 2;
  EXPECT_THROW(HeadTracker(kinematics_, o), InputError);
}

TEST_F(HeadTrackingTest, CarriedTargetStaysFixedInTheWorld) {
  HeadTrackingOptions o;
  o.max_step = kPi;
  const HeadTracker tracker(kinematics_, o);
  Pose3 X_WT = Pose3::Identity();
  X_WT.linear() = ExpRotation(Eigen::Vector3d(0.3, -1.2, 0.4)).toRotationMatrix();
  X_WT.translation() = Eigen::Vector3d(0.3, 0.1, 0.12);
  const Pose3 X_WC0 = kinematics_.X_WC(HeadKinematics::kLeft, q0_);
  const Pose3 X_C0T = X_WC0.inverse(Eigen::Isometry) * X_WT;
  const HeadTrackingResult r = tracker.Track(q0_, X_C0T.translation());
  const Pose3 X_C1T = tracker.CarryThroughHeadMove(X_C0T, q0_, r.q);
  const Pose3 X_WC1 = kinematics_.X_WC(HeadKinematics::kLeft, r.q);
  EXPECT_TRUE((X_WC1 * X_C1T).isApprox(X_WT, 1e-12));
  EXPECT_GT((X_C1T.translation() - X_C0T.translation()).norm(), 0.01);  // the head did move
  EXPECT_TRUE(tracker.X_CnewC(q0_, q0_).isApprox(Pose3::Identity(), 1e-12));
}

// The whole servo loop with a moving head: the target is held in the camera frame and carried
// through every head move, the arm integrates its moves in its own frame.
TEST_F(HeadTrackingTest, ServoLoopWithHeadTrackingReachesTheWorldTarget) {
  HeadTrackingOptions ho;
  ho.max_step = DegToRad(5.0);
  const HeadTracker tracker(kinematics_, ho);
  const ControlLawOptions co;
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 5; ++trial) {
    Pose3 X_WT = Pose3::Identity();
    X_WT.linear() = ExpRotation(Eigen::Vector3d(n(rng), n(rng), n(rng))).toRotationMatrix();
    X_WT.translation() = kGrippers_W[trial];
    Pose3 X_TE0 = Pose3::Identity();
    X_TE0.linear() =
        ExpRotation(DegToRad(25) * Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized())
            .toRotationMatrix();
    X_TE0.translation() = 0.08 * Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
    Pose3 X_WE = X_WT * X_TE0;

    device::HeadJoints q = q0_;
    Pose3 X_CT = kinematics_.X_WC(HeadKinematics::kLeft, q).inverse(Eigen::Isometry) * X_WT;
    int it = 0;
    bool converged = false;
    for (; it < 40; ++it) {
      const Pose3 X_CE = kinematics_.X_WC(HeadKinematics::kLeft, q).inverse(Eigen::Isometry) * X_WE;
      const ServoCommand cmd = ComputeServoCommand(X_CE, X_CT, co);
      if (cmd.converged) {
        converged = true;
        break;
      }
      X_WE = X_WE * cmd.X_EEnew;
      const Pose3 X_CE_after =
          kinematics_.X_WC(HeadKinematics::kLeft, q).inverse(Eigen::Isometry) * X_WE;
      const HeadTrackingResult r = tracker.Track(q, X_CE_after.translation());
      X_CT = tracker.CarryThroughHeadMove(X_CT, q, r.q);
      q = r.q;
    }
    ASSERT_TRUE(converged) << "trial " << trial;
    const Eigen::Vector2d uv = Pixel(HeadKinematics::kLeft, q, X_WE.translation());
    std::printf("servo + head tracking: %d iterations, final %.2f mm, gripper at (%.1f, %.1f) px\n",
                it, (X_WE.translation() - X_WT.translation()).norm() * 1e3, uv.x(), uv.y());
    EXPECT_LE((X_WE.translation() - X_WT.translation()).norm(), co.translation_tolerance);
  }
}

}  // namespace
}  // namespace hgrasp::servo
