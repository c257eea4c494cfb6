#include "robot/head_kinematics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "common/error.h"
#include "common/geometry.h"
#include "common/paths.h"
#include "robot/calibration.h"
#include "robot/kinematic_tree.h"

namespace hgrasp::robot {
namespace {

using device::HeadJoints;
using Eigen::Vector3d;

constexpr int kLeft = HeadKinematics::kLeft;
constexpr int kRight = HeadKinematics::kRight;

// Values from models/humanoid.urdf, written out here to check the model by hand.
constexpr double kPitch = DegToRad(20.0);            // camera_bracket pitched down on the tilt link
constexpr double kBracketHeight = 0.60;              // pan origin 0.53 + tilt origin 0.07, m
constexpr double kVergeAxisX = 0.03;                 // verge axes in H, m
constexpr double kHalfBaseline = 0.07;               // m
constexpr double kOpticalAhead = 0.015;              // optical centre in front of the verge axis, m
constexpr double kLensRoll = 0.0069813170079773184;  // laser lens mounting error about x, rad
const Vector3d kLaserAxisOrigin_H(0.03, 0.0, 0.06);  // m
constexpr double kLensSideways = 0.0015;             // m

void ExpectNear(const Vector3d& actual, const Vector3d& expected, double tol) {
  EXPECT_LE((actual - expected).cwiseAbs().maxCoeff(), tol)
      << "actual " << actual.transpose() << "\nexpected " << expected.transpose();
}

void ExpectNear(const Pose3& actual, const Pose3& expected, double tol) {
  EXPECT_LE((actual.matrix() - expected.matrix()).cwiseAbs().maxCoeff(), tol)
      << "actual\n"
      << actual.matrix() << "\nexpected\n"
      << expected.matrix();
}

class HeadKinematicsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const std::string urdf = ResolveDataPath("models/humanoid.urdf");
    head_ = new HeadKinematics(HeadKinematics::FromUrdfFile(urdf));
    tree_ = new KinematicTree(KinematicTree::FromUrdfFile(urdf));
  }
  static void TearDownTestSuite() {
    delete head_;
    delete tree_;
    head_ = nullptr;
    tree_ = nullptr;
  }

  // Random head joints within the URDF limits (fixed seed).
  static HeadJoints RandomJoints(std::mt19937* rng) {
    const auto draw = [&](const char* joint) {
      const KinematicTree::JointLimits l = tree_->Limits(joint);
      return std::uniform_real_distribution<double>(l.lower, l.upper)(*rng);
    };
    return HeadJoints{draw("head_pan"), draw("head_tilt"), draw("head_verge_left")};
  }

  static HeadKinematics* head_;
  static KinematicTree* tree_;
};
HeadKinematics* HeadKinematicsTest::head_ = nullptr;
KinematicTree* HeadKinematicsTest::tree_ = nullptr;

TEST_F(HeadKinematicsTest, MatchesKinematicTree) {
  std::mt19937 rng(20020);
  std::uniform_real_distribution<double> laser(-DegToRad(45.0), DegToRad(45.0));
  for (int trial = 0; trial < 50; ++trial) {
    const HeadJoints q = RandomJoints(&rng);
    const double laser_rad = laser(rng);
    const KinematicTree::JointValues values = {{"head_pan", q.pan},
                                               {"head_tilt", q.tilt},
                                               {"head_verge_left", q.verge},
                                               {"laser", laser_rad}};
    ExpectNear(head_->X_WH(q), tree_->LinkPose("camera_bracket", values), 1e-12);
    ExpectNear(head_->X_WC(kLeft, q), tree_->LinkPose("camera_left_optical", values), 1e-12);
    ExpectNear(head_->X_WC(kRight, q), tree_->LinkPose("camera_right_optical", values), 1e-12);
    ExpectNear(head_->X_WS(q, laser_rad), tree_->LinkPose("laser_plane", values), 1e-12);
  }
}

TEST_F(HeadKinematicsTest, CameraInHeadDependsOnVergeOnly) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    const HeadJoints q = RandomJoints(&rng);
    for (int camera : {kLeft, kRight}) {
      ExpectNear(head_->X_WH(q).inverse() * head_->X_WC(camera, q), head_->X_HC(camera, q.verge),
                 1e-12);
      ExpectNear(head_->X_WH(q) * head_->X_HC(camera, q.verge), head_->X_WC(camera, q), 1e-12);
    }
  }
}

TEST_F(HeadKinematicsTest, AtZeroBothCamerasLookAlongTheBracketPitched20DegDown) {
  const HeadJoints zero;
  const Vector3d forward_down(std::cos(kPitch), 0.0, -std::sin(kPitch));
  const Pose3 X_WH = head_->X_WH(zero);
  ExpectNear(X_WH.translation(), Vector3d(0, 0, kBracketHeight), 1e-15);
  ExpectNear(X_WH.linear().col(0), forward_down, 1e-15);
  ExpectNear(X_WH.linear().col(1), Vector3d::UnitY(), 1e-15);
  for (int camera : {kLeft, kRight}) {
    const Pose3 X_WC = head_->X_WC(camera, zero);
    ExpectNear(X_WC.linear().col(2), forward_down, 1e-15);        // z: looking direction
    ExpectNear(X_WC.linear().col(0), -Vector3d::UnitY(), 1e-15);  // x: image right = W -y
  }
  // The left optical centre: the bracket origin plus R_y(20 deg) (0.045, 0.07, 0).
  const double ahead = kVergeAxisX + kOpticalAhead;
  ExpectNear(
      head_->X_WC(kLeft, zero).translation(),
      Vector3d(ahead * std::cos(kPitch), kHalfBaseline, kBracketHeight - ahead * std::sin(kPitch)),
      1e-15);
}

TEST_F(HeadKinematicsTest, OpticalFramesInHeadAtVergeZero) {
  const double ahead = kVergeAxisX + kOpticalAhead;
  const Pose3 X_HCL = head_->X_HC(kLeft, 0.0);
  const Pose3 X_HCR = head_->X_HC(kRight, 0.0);
  ExpectNear(X_HCL.translation(), Vector3d(ahead, kHalfBaseline, 0.0), 1e-15);   // left at +y
  ExpectNear(X_HCR.translation(), Vector3d(ahead, -kHalfBaseline, 0.0), 1e-15);  // right at -y
  for (const Pose3& X_HC : {X_HCL, X_HCR}) {
    ExpectNear(X_HC.linear().col(0), -Vector3d::UnitY(), 1e-15);  // x right
    ExpectNear(X_HC.linear().col(1), -Vector3d::UnitZ(), 1e-15);  // y down
    ExpectNear(X_HC.linear().col(2), Vector3d::UnitX(), 1e-15);   // z forward
  }
  EXPECT_NEAR((X_HCL.translation() - X_HCR.translation()).norm(), 0.14, 1e-15);
}

TEST_F(HeadKinematicsTest, VergeTurnsTheCamerasTowardsEachOther) {
  for (double deg : {-5.0, 0.0, 5.0, 10.0, 17.0, 25.0}) {
    SCOPED_TRACE(deg);
    const double v = DegToRad(deg);
    const Pose3 X_HCL = head_->X_HC(kLeft, v);
    const Pose3 X_HCR = head_->X_HC(kRight, v);
    // Each optical centre swings on a 15 mm arm about its verge axis, inwards for v > 0.
    const double x = kVergeAxisX + kOpticalAhead * std::cos(v);
    const double y = kHalfBaseline - kOpticalAhead * std::sin(v);
    ExpectNear(X_HCL.translation(), Vector3d(x, y, 0.0), 1e-15);
    ExpectNear(X_HCR.translation(), Vector3d(x, -y, 0.0), 1e-15);
    EXPECT_NEAR((X_HCL.translation() - X_HCR.translation()).norm(), 0.14 - 0.03 * std::sin(v),
                1e-15);
    // Looking directions: the left camera turns to -y, the right one to +y.
    ExpectNear(X_HCL.linear().col(2), Vector3d(std::cos(v), -std::sin(v), 0.0), 1e-15);
    ExpectNear(X_HCR.linear().col(2), Vector3d(std::cos(v), std::sin(v), 0.0), 1e-15);
    // Image y stays down (the verge axes are H's z).
    ExpectNear(X_HCL.linear().col(1), -Vector3d::UnitZ(), 1e-15);
    ExpectNear(X_HCR.linear().col(1), -Vector3d::UnitZ(), 1e-15);
  }
}

TEST_F(HeadKinematicsTest, PanAndTiltMoveTheBracket) {
  // Pan 90 deg to the left: the bracket looks along W +y, still pitched 20 deg down.
  const Pose3 X_WH_pan = head_->X_WH(HeadJoints{DegToRad(90.0), 0.0, 0.3});
  ExpectNear(X_WH_pan.translation(), Vector3d(0, 0, kBracketHeight), 1e-15);
  ExpectNear(X_WH_pan.linear().col(0), Vector3d(0, std::cos(kPitch), -std::sin(kPitch)), 1e-15);
  // Tilt 25 deg down: 45 deg down in all.
  const Pose3 X_WH_tilt = head_->X_WH(HeadJoints{0.0, DegToRad(25.0), -0.05});
  ExpectNear(X_WH_tilt.translation(), Vector3d(0, 0, kBracketHeight), 1e-15);
  ExpectNear(X_WH_tilt.linear().col(0),
             Vector3d(std::cos(DegToRad(45.0)), 0, -std::sin(DegToRad(45.0))), 1e-15);
  // Verge does not move the bracket.
  ExpectNear(head_->X_WH(HeadJoints{0.2, 0.3, 0.0}), head_->X_WH(HeadJoints{0.2, 0.3, 0.4}), 0.0);
}

TEST_F(HeadKinematicsTest, LaserPlaneFrameByHand) {
  for (double deg : {-45.0, -10.0, 0.0, 5.3, 45.0}) {
    SCOPED_TRACE(deg);
    const double theta = DegToRad(deg);
    const HeadJoints q{0.3, -0.2, 0.1};
    const Pose3 X_HS = head_->X_WH(q).inverse() * head_->X_WS(q, theta);
    const Eigen::Matrix3d R_HL = RotZ(theta);  // laser_link in H
    ExpectNear(X_HS.translation(), kLaserAxisOrigin_H + R_HL * Vector3d(0, kLensSideways, 0),
               1e-15);
    // The light plane's normal (S's y) carries the 0.4 deg lens roll about the laser's x.
    ExpectNear(X_HS.linear().col(1), R_HL * Vector3d(0, std::cos(kLensRoll), std::sin(kLensRoll)),
               1e-15);
  }
}

// The URDF's light plane is exactly a LaserCalibration with the axis H's z through the laser
// joint, the encoder at 0.01 deg/count, offset = the 1.5 mm sideways lens error projected on the
// normal, and normal0_H rolled 0.4 deg out of the x-y plane. That normal0_H is NOT perpendicular
// to axis_H (axis . normal = sin 0.4 deg = 0.00698), so LoadLaserCalibration, which demands
// perpendicularity within 1e-6, would reject the simulator's own truth.
TEST_F(HeadKinematicsTest, UrdfLaserPlaneIsALaserCalibrationWithATiltedNormal) {
  LaserCalibration truth;
  truth.axis_H = Vector3d::UnitZ();
  truth.point_H = kLaserAxisOrigin_H;
  truth.normal0_H = Vector3d(0, std::cos(kLensRoll), std::sin(kLensRoll));
  truth.offset_m = kLensSideways * std::cos(kLensRoll);
  truth.rad_per_count = 2.0 * kPi / 36000.0;
  EXPECT_NEAR(truth.axis_H.dot(truth.normal0_H), std::sin(kLensRoll), 1e-18);

  const HeadJoints q{-0.4, 0.25, 0.05};
  for (std::int32_t count : {-4500, -800, 0, 1, 530, 4500}) {
    SCOPED_TRACE(count);
    const Pose3 X_HS = head_->X_WH(q).inverse() * head_->X_WS(q, count * truth.rad_per_count);
    Plane urdf_H;  // S's x-z plane in H
    urdf_H.n = X_HS.linear().col(1);
    urdf_H.d = -urdf_H.n.dot(X_HS.translation());
    const Plane model_H = truth.PlaneH(count);
    ExpectNear(model_H.n, urdf_H.n, 1e-15);
    EXPECT_NEAR(model_H.d, urdf_H.d, 1e-15);
  }
}

TEST(HeadKinematicsLoadTest, BadFilesThrowInputError) {
  EXPECT_THROW(HeadKinematics::FromUrdfFile("/nonexistent/humanoid.urdf"), InputError);

  // A valid URDF without the head's links.
  const std::string path = ::testing::TempDir() + "/hgrasp_headless.urdf";
  {
    std::ofstream out(path);
    out << R"(<?xml version="1.0"?>
<robot name="headless">
  <link name="world"/>
  <link name="torso"/>
  <joint name="head_pan" type="revolute">
    <parent link="world"/><child link="torso"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" velocity="1" effort="1"/>
  </joint>
</robot>
)";
  }
  try {
    HeadKinematics::FromUrdfFile(path);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(std::string(e.what()).find("camera_bracket"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
}

TEST(HeadKinematicsDeathTest, BadCameraIndexAborts) {
  const HeadKinematics head = HeadKinematics::FromUrdfFile(ResolveDataPath("models/humanoid.urdf"));
  EXPECT_DEATH(head.X_WC(2, HeadJoints{}), "camera index 2");
  EXPECT_DEATH(head.X_HC(-1, 0.0), "camera index -1");
}

}  // namespace
}  // namespace hgrasp::robot
