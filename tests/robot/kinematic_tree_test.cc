#include "robot/kinematic_tree.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>

#include "common/error.h"
#include "common/geometry.h"
#include "common/paths.h"

namespace hgrasp::robot {
namespace {

using Eigen::Vector3d;

// A planar two-link arm (link lengths 1 and 0.5, joints about z), a slider whose origin is
// turned 90 deg about z, a mimic joint and a mimic of that mimic, and a continuous joint.
constexpr char kToyUrdf[] = R"(<?xml version="1.0"?>
<robot name="toy">
  <link name="base"/>
  <link name="upper"/>
  <link name="lower"/>
  <link name="tip"/>
  <link name="carriage"/>
  <link name="follower"/>
  <link name="follower2"/>
  <link name="wheel"/>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/>
    <axis xyz="0 0 1"/>
    <limit lower="-1.5" upper="2.5" velocity="2" effort="30"/>
  </joint>
  <joint name="elbow" type="revolute">
    <parent link="upper"/><child link="lower"/>
    <origin xyz="1 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" velocity="3" effort="10"/>
  </joint>
  <joint name="lower_to_tip" type="fixed">
    <parent link="lower"/><child link="tip"/>
    <origin xyz="0.5 0 0"/>
  </joint>
  <joint name="slide" type="prismatic">
    <parent link="base"/><child link="carriage"/>
    <origin xyz="0 0 2" rpy="0 0 1.5707963267948966"/>
    <axis xyz="0 1 0"/>
    <limit lower="0" upper="0.2" velocity="0.5" effort="100"/>
  </joint>
  <joint name="follow" type="prismatic">
    <parent link="base"/><child link="follower"/>
    <axis xyz="1 0 0"/>
    <limit lower="0" upper="1" velocity="1" effort="1"/>
    <mimic joint="slide" multiplier="2" offset="0.1"/>
  </joint>
  <joint name="follow2" type="prismatic">
    <parent link="base"/><child link="follower2"/>
    <axis xyz="0 0 1"/>
    <limit lower="0" upper="1" velocity="1" effort="1"/>
    <mimic joint="follow" multiplier="3" offset="-0.2"/>
  </joint>
  <joint name="spin" type="continuous">
    <parent link="base"/><child link="wheel"/>
    <origin xyz="0 0 -1"/>
    <axis xyz="1 0 0"/>
  </joint>
</robot>
)";

KinematicTree Toy() { return KinematicTree::FromUrdfString(kToyUrdf, "toy.urdf"); }

TEST(KinematicTreeTest, ReadsTheStructure) {
  const KinematicTree tree = Toy();
  EXPECT_EQ(tree.name(), "toy");
  EXPECT_EQ(tree.root(), "base");
  EXPECT_EQ(tree.LinkNames().size(), 8u);
  EXPECT_EQ(tree.LinkNames().front(), "base");
  const std::vector<std::string> joints = tree.JointNames();
  EXPECT_EQ(joints.size(), 6u);  // the fixed joint is not movable
  EXPECT_EQ(std::count(joints.begin(), joints.end(), "lower_to_tip"), 0);
  EXPECT_FALSE(tree.IsMimic("shoulder"));
  EXPECT_FALSE(tree.IsMimic("spin"));
  EXPECT_TRUE(tree.IsMimic("follow"));
  EXPECT_TRUE(tree.IsMimic("follow2"));
}

TEST(KinematicTreeTest, ParentsComeBeforeChildren) {
  const KinematicTree tree = Toy();
  const std::vector<std::string> links = tree.LinkNames();
  const auto pos = [&](const std::string& n) {
    return std::find(links.begin(), links.end(), n) - links.begin();
  };
  EXPECT_LT(pos("upper"), pos("lower"));
  EXPECT_LT(pos("lower"), pos("tip"));
}

TEST(KinematicTreeTest, PlanarArmEndPositions) {
  const KinematicTree tree = Toy();
  struct Case {
    double shoulder, elbow;
    Vector3d tip;
  };
  const double h = kPi / 2;
  for (const Case& c : {Case{0, 0, {1.5, 0, 0}}, Case{h, -h, {0.5, 1, 0}}, Case{h, h, {-0.5, 1, 0}},
                        Case{kPi / 4, 0, {1.5 / std::sqrt(2.0), 1.5 / std::sqrt(2.0), 0}}}) {
    const Pose3 X = tree.LinkPose("tip", {{"shoulder", c.shoulder}, {"elbow", c.elbow}});
    EXPECT_NEAR((X.translation() - c.tip).norm(), 0.0, 1e-12)
        << c.shoulder << " " << c.elbow << ": " << X.translation().transpose();
    // The tip's x axis points along the forearm.
    const double yaw = c.shoulder + c.elbow;
    EXPECT_NEAR((X.linear() - RotZ(yaw)).norm(), 0.0, 1e-12);
  }
  // The elbow sits at the end of the upper arm.
  const Pose3 X_lower = tree.LinkPose("lower", {{"shoulder", h}});
  EXPECT_NEAR((X_lower.translation() - Vector3d(0, 1, 0)).norm(), 0.0, 1e-12);
}

TEST(KinematicTreeTest, MissingJointsAreZero) {
  const KinematicTree tree = Toy();
  const Pose3 X = tree.LinkPose("tip", {});
  EXPECT_NEAR((X.translation() - Vector3d(1.5, 0, 0)).norm(), 0.0, 1e-12);
  EXPECT_TRUE(tree.LinkPose("base", {}).isApprox(Pose3::Identity()));
}

TEST(KinematicTreeTest, PrismaticMovesAlongItsAxisInTheJointFrame) {
  const KinematicTree tree = Toy();
  // The origin is turned +90 deg about z, so the joint's y axis is the root's -x.
  const Pose3 X = tree.LinkPose("carriage", {{"slide", 0.15}});
  EXPECT_NEAR((X.translation() - Vector3d(-0.15, 0, 2)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((X.linear() - RotZ(kPi / 2)).norm(), 0.0, 1e-12);
}

TEST(KinematicTreeTest, MimicJointsFollowTheirMaster) {
  const KinematicTree tree = Toy();
  // follow = 2 slide + 0.1; follow2 = 3 follow - 0.2. Values given for mimics are ignored.
  const auto poses = tree.LinkPoses({{"slide", 0.1}, {"follow", 99.0}, {"follow2", -5.0}});
  EXPECT_NEAR((poses.at("follower").translation() - Vector3d(0.3, 0, 0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((poses.at("follower2").translation() - Vector3d(0, 0, 0.7)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(
      (tree.LinkPose("follower2", {{"slide", 0.1}}).translation() - Vector3d(0, 0, 0.7)).norm(),
      0.0, 1e-12);
}

TEST(KinematicTreeTest, ContinuousJointRotatesAboutItsAxis) {
  const KinematicTree tree = Toy();
  const Pose3 X = tree.LinkPose("wheel", {{"spin", 7.0}});  // beyond 2 pi: no limits
  EXPECT_NEAR((X.translation() - Vector3d(0, 0, -1)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((X.linear() - Eigen::AngleAxisd(7.0, Vector3d::UnitX()).toRotationMatrix()).norm(),
              0.0, 1e-12);
}

TEST(KinematicTreeTest, LinkPosesAgreesWithLinkPose) {
  const KinematicTree tree = Toy();
  const KinematicTree::JointValues q = {
      {"shoulder", 0.3}, {"elbow", -1.1}, {"slide", 0.05}, {"spin", 2.0}};
  const auto poses = tree.LinkPoses(q);
  EXPECT_EQ(poses.size(), tree.LinkNames().size());
  for (const std::string& link : tree.LinkNames()) {
    EXPECT_TRUE(poses.at(link).isApprox(tree.LinkPose(link, q), 1e-14)) << link;
  }
}

TEST(KinematicTreeTest, ReadsLimits) {
  const KinematicTree tree = Toy();
  const KinematicTree::JointLimits s = tree.Limits("shoulder");
  EXPECT_DOUBLE_EQ(s.lower, -1.5);
  EXPECT_DOUBLE_EQ(s.upper, 2.5);
  EXPECT_DOUBLE_EQ(s.velocity, 2.0);
  EXPECT_DOUBLE_EQ(s.effort, 30.0);
  const KinematicTree::JointLimits p = tree.Limits("slide");
  EXPECT_DOUBLE_EQ(p.upper, 0.2);
  EXPECT_DOUBLE_EQ(p.effort, 100.0);
  const KinematicTree::JointLimits c = tree.Limits("spin");
  EXPECT_EQ(c.lower, -std::numeric_limits<double>::infinity());
  EXPECT_EQ(c.upper, std::numeric_limits<double>::infinity());
  EXPECT_EQ(c.velocity, std::numeric_limits<double>::infinity());
}

// --- errors -------------------------------------------------------------------------------

TEST(KinematicTreeErrorTest, BadXmlNamesTheFile) {
  try {
    KinematicTree::FromUrdfString("<robot name='x'><link name='a'>", "broken.urdf");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "broken.urdf");
    EXPECT_NE(std::string(e.what()).find("broken.urdf"), std::string::npos) << e.what();
  }
  EXPECT_THROW(KinematicTree::FromUrdfString("", "empty.urdf"), InputError);
  EXPECT_THROW(KinematicTree::FromUrdfString("<notarobot/>", "x.urdf"), InputError);
}

TEST(KinematicTreeErrorTest, UrdfdomMessageIsPassedOn) {
  // Two roots: urdfdom refuses, and says why.
  const char* two_roots = R"(<robot name="r"><link name="a"/><link name="b"/></robot>)";
  try {
    KinematicTree::FromUrdfString(two_roots, "two_roots.urdf");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "two_roots.urdf");
    EXPECT_FALSE(e.value().empty()) << e.what();
  }
}

TEST(KinematicTreeErrorTest, UnreadableFile) {
  try {
    KinematicTree::FromUrdfFile("/nonexistent/dir/robot.urdf");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "/nonexistent/dir/robot.urdf");
  }
}

TEST(KinematicTreeErrorTest, UnsupportedJointType) {
  const char* floating = R"(<robot name="r"><link name="a"/><link name="b"/>
    <joint name="free" type="floating"><parent link="a"/><child link="b"/></joint></robot>)";
  try {
    KinematicTree::FromUrdfString(floating, "floating.urdf");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "joint[free].type");
  }
}

TEST(KinematicTreeErrorTest, MimicOfUnknownJoint) {
  const char* bad_mimic = R"(<robot name="r"><link name="a"/><link name="b"/>
    <joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" velocity="1" effort="1"/><mimic joint="nope"/></joint></robot>)";
  try {
    KinematicTree::FromUrdfString(bad_mimic, "mimic.urdf");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "joint[j].mimic.joint");
    EXPECT_EQ(e.value(), "nope");
  }
}

TEST(KinematicTreeErrorTest, UnknownNames) {
  const KinematicTree tree = Toy();
  EXPECT_THROW(tree.Limits("nope"), InputError);
  EXPECT_THROW(tree.Limits("lower_to_tip"), InputError);  // fixed: no limits
  EXPECT_THROW(tree.IsMimic("nope"), InputError);
  EXPECT_THROW(tree.LinkPose("nope", {}), InputError);
  EXPECT_THROW(tree.LinkPoses({{"sholder", 1.0}}), InputError);  // a typo is not ignored
  EXPECT_THROW(tree.LinkPose("tip", {{"lower_to_tip", 1.0}}), InputError);
}

// --- models/humanoid.urdf ----------------------------------------------------------------

class HumanoidTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    tree_ = new KinematicTree(KinematicTree::FromUrdfFile(ResolveDataPath("models/humanoid.urdf")));
  }
  static void TearDownTestSuite() {
    delete tree_;
    tree_ = nullptr;
  }
  static KinematicTree* tree_;
};
KinematicTree* HumanoidTest::tree_ = nullptr;

// Standard DH for the Puma 260 (Penn MEAM520 model, d1 = 0 on a shoulder mount), written out
// here independently of the URDF: A_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i).
struct DhRow {
  double a, alpha_deg, d, offset_deg;
};
constexpr DhRow kPumaDh[6] = {{0, 90, 0, 0},      {0.2032, 0, -0.0635, 0}, {0, -90, -0.0635, 0},
                              {0, 90, 0.2032, 0}, {0, 90, 0, 90},          {0, 0, 0.0635, 0}};

Pose3 DhTransform(const DhRow& row, double q) {
  const double theta = q + DegToRad(row.offset_deg);
  const double alpha = DegToRad(row.alpha_deg);
  const double ct = std::cos(theta), st = std::sin(theta);
  const double ca = std::cos(alpha), sa = std::sin(alpha);
  Eigen::Matrix4d A;
  A << ct, -st * ca, st * sa, row.a * ct,  //
      st, ct * ca, -ct * sa, row.a * st,   //
      0, sa, ca, row.d,                    //
      0, 0, 0, 1;
  return Pose3(A);
}

double RotationAngle(const Eigen::Matrix3d& R_a, const Eigen::Matrix3d& R_b) {
  return Eigen::AngleAxisd(R_a.transpose() * R_b).angle();
}

TEST(KinematicTreeTest, ReadsTheVisualCylinders) {
  const KinematicTree tree = KinematicTree::FromUrdfString(R"(<?xml version="1.0"?>
<robot name="shapes">
  <link name="base">
    <visual><origin xyz="0 0 0.5" rpy="1.5707963267948966 0 0"/>
      <geometry><cylinder radius="0.1" length="0.4"/></geometry></visual>
    <visual><geometry><box size="1 1 1"/></geometry></visual>
    <visual><origin xyz="1 2 3"/><geometry><cylinder radius="0.2" length="0.6"/></geometry></visual>
  </link>
  <link name="bare"/>
  <joint name="j" type="fixed"><parent link="base"/><child link="bare"/></joint>
</robot>)",
                                                           "shapes");
  const std::vector<KinematicTree::Cylinder>& c = tree.Cylinders("base");
  ASSERT_EQ(c.size(), 2u);  // the box is not a cylinder
  EXPECT_NEAR(c[0].radius, 0.1, 1e-12);
  EXPECT_NEAR(c[0].length, 0.4, 1e-12);
  EXPECT_LT((c[0].X_LG.translation() - Vector3d(0, 0, 0.5)).norm(), 1e-12);
  // Rolled 90 deg about x: the cylinder's axis (z) lies along -y.
  EXPECT_LT((c[0].X_LG.linear().col(2) - Vector3d(0, -1, 0)).norm(), 1e-12);
  EXPECT_LT((c[1].X_LG.translation() - Vector3d(1, 2, 3)).norm(), 1e-12);
  EXPECT_TRUE(tree.Cylinders("bare").empty());
  EXPECT_THROW(tree.Cylinders("nowhere"), InputError);
}

TEST_F(HumanoidTest, Structure) {
  EXPECT_EQ(tree_->root(), "world");
  EXPECT_EQ(tree_->JointNames().size(), 21u);  // 5 head + 2 x (6 arm + 2 fingers)
  EXPECT_TRUE(tree_->IsMimic("head_verge_right"));
  EXPECT_TRUE(tree_->IsMimic("left_index_slide"));
  EXPECT_TRUE(tree_->IsMimic("right_index_slide"));
  EXPECT_FALSE(tree_->IsMimic("head_verge_left"));
  EXPECT_FALSE(tree_->IsMimic("left_thumb_slide"));
  for (const char* link :
       {"torso", "head_pan_link", "head_tilt_link", "camera_bracket", "camera_left_link",
        "camera_right_link", "camera_left_optical", "camera_right_optical", "laser_link",
        "laser_plane", "left_base", "left_gripper", "right_gripper", "left_thumb", "right_index",
        "left_led0", "right_led7"}) {
    EXPECT_NO_THROW(tree_->LinkPose(link, {})) << link;
  }
}

TEST_F(HumanoidTest, LimitsFromTheDesign) {
  const KinematicTree::JointLimits j2 = tree_->Limits("left_j2");
  EXPECT_NEAR(j2.lower, DegToRad(-225), 1e-12);
  EXPECT_NEAR(j2.upper, DegToRad(45), 1e-12);
  EXPECT_NEAR(j2.velocity, DegToRad(120), 1e-12);
  EXPECT_NEAR(tree_->Limits("right_j4").velocity, DegToRad(575), 1e-12);
  EXPECT_NEAR(tree_->Limits("head_pan").upper, kPi, 1e-12);
  EXPECT_NEAR(tree_->Limits("head_tilt").lower, DegToRad(-60), 1e-12);
  EXPECT_NEAR(tree_->Limits("left_thumb_slide").upper, 0.05, 1e-12);
}

TEST_F(HumanoidTest, PumaChainMatchesStandardDh) {
  std::mt19937 rng(260);
  double max_dp = 0.0, max_angle = 0.0;
  for (const std::string side : {"left", "right"}) {
    for (int trial = 0; trial < 200; ++trial) {
      KinematicTree::JointValues q;
      Pose3 X_BE = Pose3::Identity();  // base -> gripper by the DH product A1 ... A6
      for (int i = 0; i < 6; ++i) {
        const std::string joint = side + "_j" + std::to_string(i + 1);
        const KinematicTree::JointLimits lim = tree_->Limits(joint);
        const double qi = std::uniform_real_distribution<double>(lim.lower, lim.upper)(rng);
        q[joint] = qi;
        X_BE = X_BE * DhTransform(kPumaDh[i], qi);
      }
      const Pose3 X_WB = tree_->LinkPose(side + "_base", q);
      const Pose3 X_WE = tree_->LinkPose(side + "_gripper", q);
      const Pose3 X_BE_urdf = X_WB.inverse() * X_WE;
      max_dp = std::max(max_dp, (X_BE_urdf.translation() - X_BE.translation()).norm());
      max_angle = std::max(max_angle, RotationAngle(X_BE.linear(), X_BE_urdf.linear()));
    }
  }
  EXPECT_LT(max_dp, 1e-9);
  EXPECT_LT(max_angle, 1e-9);
  char text[64];
  std::snprintf(text, sizeof text, "%.3g", max_dp);
  RecordProperty("max_position_error_m", text);
  std::snprintf(text, sizeof text, "%.3g", max_angle);
  RecordProperty("max_angle_error_rad", text);
}

TEST_F(HumanoidTest, ArmBasesAreOnTheShoulders) {
  for (const auto& [side, s] : {std::pair<std::string, double>{"left", 1.0}, {"right", -1.0}}) {
    const Pose3 X_WB = tree_->LinkPose(side + "_base", {});
    EXPECT_NEAR((X_WB.translation() - Vector3d(0.07, s * 0.28, 0.30)).norm(), 0.0, 1e-12);
    EXPECT_TRUE(X_WB.linear().isIdentity(1e-12));
  }
}

TEST_F(HumanoidTest, CameraOpticalFrames) {
  for (const auto& [side, s] : {std::pair<std::string, double>{"left", 1.0}, {"right", -1.0}}) {
    const Pose3 X_WL = tree_->LinkPose("camera_" + side + "_link", {});
    const Pose3 X_WC = tree_->LinkPose("camera_" + side + "_optical", {});
    const Pose3 X_LC = X_WL.inverse() * X_WC;
    EXPECT_NEAR((X_LC.translation() - Vector3d(0.015, 0, 0)).norm(), 0.0, 1e-12);
    Eigen::Matrix3d R_LC;
    R_LC.col(0) = -Vector3d::UnitY();  // x right
    R_LC.col(1) = -Vector3d::UnitZ();  // y down
    R_LC.col(2) = Vector3d::UnitX();   // z forward
    EXPECT_NEAR(RotationAngle(X_LC.linear(), R_LC), 0.0, 1e-12);
  }
  // At zero the cameras look 20 deg below the horizon, 0.14 m apart.
  const Pose3 X_WCL = tree_->LinkPose("camera_left_optical", {});
  const Pose3 X_WCR = tree_->LinkPose("camera_right_optical", {});
  EXPECT_NEAR((X_WCL.translation() - X_WCR.translation()).norm(), 0.14, 1e-12);
  const Vector3d z_W = X_WCL.linear().col(2);
  EXPECT_NEAR(std::asin(-z_W.z()), DegToRad(20), 1e-12);
}

TEST_F(HumanoidTest, VergeTurnsTheCamerasTowardsEachOther) {
  const KinematicTree::JointValues q = {{"head_verge_left", DegToRad(10)}};
  const Vector3d zl = tree_->LinkPose("camera_left_optical", q).linear().col(2);
  const Vector3d zr = tree_->LinkPose("camera_right_optical", q).linear().col(2);
  EXPECT_LT(zl.y(), 0.0);  // left camera looks to the right
  EXPECT_NEAR(zr.y(), -zl.y(), 1e-12);
}

TEST_F(HumanoidTest, HeadTiltPositiveLooksDown) {
  const Vector3d z0 = tree_->LinkPose("camera_left_optical", {}).linear().col(2);
  const Vector3d z1 = tree_->LinkPose("camera_left_optical", {{"head_tilt", 0.3}}).linear().col(2);
  EXPECT_LT(z1.z(), z0.z());
}

TEST_F(HumanoidTest, LaserPlaneMountingError) {
  const Pose3 X_WL = tree_->LinkPose("laser_link", {});
  const Pose3 X_LS = X_WL.inverse() * tree_->LinkPose("laser_plane", {});
  EXPECT_NEAR((X_LS.translation() - Vector3d(0, 0.0015, 0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(RotationAngle(Eigen::Matrix3d::Identity(), X_LS.linear()), DegToRad(0.4), 1e-12);
  EXPECT_NEAR(X_LS.linear().col(0).x(), 1.0, 1e-12);  // about x
}

TEST_F(HumanoidTest, LedsAndFingersInTheGripperFrame) {
  const Vector3d kLeds[8] = {{0.066, 0.031, -0.006},  {-0.066, 0.031, -0.006},
                             {0.066, -0.031, -0.006}, {-0.066, -0.031, -0.006},
                             {0.03, 0.031, 0.046},    {-0.03, 0.031, 0.046},
                             {0.03, -0.031, 0.046},   {-0.03, -0.031, 0.046}};
  const KinematicTree::JointValues q = {
      {"right_j3", 0.4}, {"right_j5", -0.7}, {"right_thumb_slide", 0.03}};
  const Pose3 X_WE = tree_->LinkPose("right_gripper", q);
  for (int k = 0; k < 8; ++k) {
    const Pose3 X_WLed = tree_->LinkPose("right_led" + std::to_string(k), q);
    EXPECT_NEAR(((X_WE.inverse() * X_WLed).translation() - kLeds[k]).norm(), 0.0, 1e-12) << k;
  }
  // The fingers open symmetrically along E's x: thumb at -q, index at +q.
  const Pose3 X_ET = X_WE.inverse() * tree_->LinkPose("right_thumb", q);
  const Pose3 X_EI = X_WE.inverse() * tree_->LinkPose("right_index", q);
  EXPECT_NEAR((X_ET.translation() - Vector3d(-0.03, 0, 0.04)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((X_EI.translation() - Vector3d(0.03, 0, 0.04)).norm(), 0.0, 1e-12);
}

}  // namespace
}  // namespace hgrasp::robot
