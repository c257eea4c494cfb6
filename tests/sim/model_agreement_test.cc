// models/humanoid.xml (MuJoCo) and models/humanoid.urdf (the pipeline's kinematics) must describe
// the same robot: every URDF link frame equals the MuJoCo body or site of the same name for random
// joint values. Also checks the MJCF on its own: it loads without warnings, the home keyframe
// points both cameras at the workspace and keeps the arms out of their view, and the servos
// settle without overshoot.

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "common/geometry.h"
#include "common/paths.h"
#include "common/pinhole_camera.h"
#include "robot/kinematic_tree.h"

namespace hgrasp {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using robot::KinematicTree;

struct ModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct DataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using ModelPtr = std::unique_ptr<mjModel, ModelDeleter>;
using DataPtr = std::unique_ptr<mjData, DataDeleter>;

const std::string kArmJoints[] = {"left_j1",  "left_j2",  "left_j3",  "left_j4",
                                  "left_j5",  "left_j6",  "right_j1", "right_j2",
                                  "right_j3", "right_j4", "right_j5", "right_j6"};

ModelPtr LoadModel(const std::string& path, std::string* error) {
  char buffer[1024] = "";
  ModelPtr m(mj_loadXML(path.c_str(), nullptr, buffer, sizeof buffer));
  *error = buffer;
  return m;
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

Matrix3d Mat3(const mjtNum* m) {
  Matrix3d R;
  R << m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8];
  return R;
}

double RotationAngle(const Matrix3d& R_a, const Matrix3d& R_b) {
  return Eigen::AngleAxisd(R_a.transpose() * R_b).angle();
}

std::string Fmt(double x) {
  char text[64];
  std::snprintf(text, sizeof text, "%.3g", x);
  return text;
}

class ModelAgreementTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    std::string error;
    model_ = LoadModel(ResolveDataPath("models/humanoid.xml"), &error).release();
    load_error_ = new std::string(error);
    tree_ = new KinematicTree(KinematicTree::FromUrdfFile(ResolveDataPath("models/humanoid.urdf")));
  }
  static void TearDownTestSuite() {
    mj_deleteModel(model_);
    model_ = nullptr;
    delete load_error_;
    delete tree_;
  }
  void SetUp() override {
    ASSERT_NE(model_, nullptr) << *load_error_;
    data_.reset(mj_makeData(model_));
  }

  int Joint(const std::string& name) const {
    const int id = mj_name2id(model_, mjOBJ_JOINT, name.c_str());
    EXPECT_GE(id, 0) << "MJCF has no joint " << name;
    return id;
  }
  int Actuator(const std::string& name) const {
    const int id = mj_name2id(model_, mjOBJ_ACTUATOR, name.c_str());
    EXPECT_GE(id, 0) << "MJCF has no actuator " << name;
    return id;
  }
  double& Qpos(const std::string& joint) { return data_->qpos[model_->jnt_qposadr[Joint(joint)]]; }

  /// Puts the model into keyframe "home" with the key's controls.
  void ResetToHome() {
    const int key = mj_name2id(model_, mjOBJ_KEY, "home");
    ASSERT_GE(key, 0);
    mj_resetDataKeyframe(model_, data_.get(), key);
    mj_forward(model_, data_.get());
  }

  /// One step with gravity (and Coriolis) compensation on every joint, as the simulator does.
  void StepCompensated() {
    mj_step1(model_, data_.get());
    for (int i = 0; i < model_->nv; ++i) data_->qfrc_applied[i] = data_->qfrc_bias[i];
    mj_step2(model_, data_.get());
  }

  void ExpectNoWarnings() const {
    for (int i = 0; i < mjNWARNING; ++i) {
      EXPECT_EQ(data_->warning[i].number, 0) << "MuJoCo warning " << i;
    }
  }

  static mjModel* model_;
  static std::string* load_error_;
  static KinematicTree* tree_;
  DataPtr data_;
};
mjModel* ModelAgreementTest::model_ = nullptr;
std::string* ModelAgreementTest::load_error_ = nullptr;
KinematicTree* ModelAgreementTest::tree_ = nullptr;

TEST_F(ModelAgreementTest, LoadsWithoutErrorsOrWarnings) {
  EXPECT_EQ(*load_error_, "");
  EXPECT_GE(mj_name2id(model_, mjOBJ_GEOM, "table"), 0);
  EXPECT_EQ(model_->opt.timestep, 0.002);
  EXPECT_EQ(model_->opt.integrator, mjINT_IMPLICIT);
  // The simulator inserts objects before the closing worldbody tag: it must be unique.
  const std::string xml = ReadFile(ResolveDataPath("models/humanoid.xml"));
  const size_t first = xml.find("</worldbody>");
  ASSERT_NE(first, std::string::npos);
  EXPECT_EQ(xml.find("</worldbody>", first + 1), std::string::npos);
}

TEST_F(ModelAgreementTest, JointsAndLimitsAgree) {
  const std::vector<std::string> joints = tree_->JointNames();
  EXPECT_EQ(static_cast<int>(joints.size()), model_->njnt);
  for (const std::string& name : joints) {
    const int j = Joint(name);
    if (j < 0) continue;
    const KinematicTree::JointLimits lim = tree_->Limits(name);
    EXPECT_TRUE(model_->jnt_limited[j]) << name;
    EXPECT_NEAR(model_->jnt_range[2 * j], lim.lower, 1e-12) << name;
    EXPECT_NEAR(model_->jnt_range[2 * j + 1], lim.upper, 1e-12) << name;
    EXPECT_GT(lim.velocity, 0.0) << name;
    // Every movable non-mimic joint has a position servo whose range is the joint's.
    if (tree_->IsMimic(name)) continue;
    const int a = Actuator(name);
    if (a < 0) continue;
    EXPECT_EQ(model_->actuator_trnid[2 * a], j) << name;
    EXPECT_TRUE(model_->actuator_ctrllimited[a]) << name;
    EXPECT_NEAR(model_->actuator_ctrlrange[2 * a], lim.lower, 1e-12) << name;
    EXPECT_NEAR(model_->actuator_ctrlrange[2 * a + 1], lim.upper, 1e-12) << name;
  }
  // The hand's grip force is limited.
  for (const char* hand : {"left_thumb_slide", "right_thumb_slide"}) {
    const int a = Actuator(hand);
    EXPECT_TRUE(model_->actuator_forcelimited[a]);
    EXPECT_NEAR(model_->actuator_forcerange[2 * a + 1], 40.0, 1e-12);
  }
}

TEST_F(ModelAgreementTest, EveryUrdfLinkFrameEqualsTheMujocoFrame) {
  // Coupled joints: MJCF equality constraints joint1 = c0 + c1 joint2.
  struct Coupling {
    int joint1, joint2;
    double c0, c1;
  };
  std::vector<Coupling> couplings;
  for (int e = 0; e < model_->neq; ++e) {
    ASSERT_EQ(model_->eq_type[e], mjEQ_JOINT);
    couplings.push_back({model_->eq_obj1id[e], model_->eq_obj2id[e], model_->eq_data[e * mjNEQDATA],
                         model_->eq_data[e * mjNEQDATA + 1]});
  }
  EXPECT_EQ(couplings.size(), 3u);  // verge and two hands

  // Every URDF link but the root has a MuJoCo body or site of that name.
  struct Frame {
    std::string name;
    int body = -1, site = -1;
  };
  std::vector<Frame> frames;
  for (const std::string& link : tree_->LinkNames()) {
    if (link == tree_->root()) continue;
    Frame f{link, mj_name2id(model_, mjOBJ_BODY, link.c_str()),
            mj_name2id(model_, mjOBJ_SITE, link.c_str())};
    EXPECT_TRUE(f.body >= 0 || f.site >= 0) << "URDF link " << link << " has no MJCF body or site";
    frames.push_back(f);
  }
  EXPECT_GE(frames.size(), 40u);

  std::mt19937 rng(2002);
  double max_dp = 0.0, max_angle = 0.0;
  std::string worst;
  for (int trial = 0; trial < 1000; ++trial) {
    KinematicTree::JointValues q;
    mj_resetData(model_, data_.get());
    for (const std::string& name : tree_->JointNames()) {
      if (tree_->IsMimic(name)) continue;
      const KinematicTree::JointLimits lim = tree_->Limits(name);
      q[name] = std::uniform_real_distribution<double>(lim.lower, lim.upper)(rng);
      Qpos(name) = q[name];
    }
    for (const Coupling& c : couplings) {
      data_->qpos[model_->jnt_qposadr[c.joint1]] =
          c.c0 + c.c1 * data_->qpos[model_->jnt_qposadr[c.joint2]];
    }
    mj_kinematics(model_, data_.get());
    const auto poses = tree_->LinkPoses(q);
    for (const Frame& f : frames) {
      const Pose3& X = poses.at(f.name);
      Vector3d p_mj;
      Matrix3d R_mj;
      if (f.body >= 0) {
        p_mj = Vector3d(data_->xpos + 3 * f.body);
        R_mj = Mat3(data_->xmat + 9 * f.body);
      } else {
        p_mj = Vector3d(data_->site_xpos + 3 * f.site);
        R_mj = Mat3(data_->site_xmat + 9 * f.site);
      }
      const double dp = (p_mj - X.translation()).norm();
      const double da = RotationAngle(R_mj, X.linear());
      if (dp > max_dp || da > max_angle) worst = f.name;
      max_dp = std::max(max_dp, dp);
      max_angle = std::max(max_angle, da);
    }
  }
  EXPECT_LT(max_dp, 1e-6) << worst;
  EXPECT_LT(max_angle, 1e-6) << worst;
  RecordProperty("max_position_error_m", Fmt(max_dp));
  RecordProperty("max_angle_error_rad", Fmt(max_angle));
}

TEST_F(ModelAgreementTest, MujocoCamerasMatchTheOpticalFrames) {
  // MuJoCo cameras look along their -z with y up; the optical frame has z forward, y down.
  ResetToHome();
  for (const std::string side : {"left", "right"}) {
    const int cam = mj_name2id(model_, mjOBJ_CAMERA, ("camera_" + side).c_str());
    const int site = mj_name2id(model_, mjOBJ_SITE, ("camera_" + side + "_optical").c_str());
    ASSERT_GE(cam, 0);
    ASSERT_GE(site, 0);
    EXPECT_NEAR(model_->cam_fovy[cam], 55.0, 1e-12);
    const Matrix3d R_cam = Mat3(data_->cam_xmat + 9 * cam);
    const Matrix3d R_opt = Mat3(data_->site_xmat + 9 * site);
    EXPECT_NEAR(
        (Vector3d(data_->cam_xpos + 3 * cam) - Vector3d(data_->site_xpos + 3 * site)).norm(), 0.0,
        1e-12);
    EXPECT_NEAR((R_cam.col(0) - R_opt.col(0)).norm(), 0.0, 1e-9);
    EXPECT_NEAR((R_cam.col(1) + R_opt.col(1)).norm(), 0.0, 1e-9);
    EXPECT_NEAR((R_cam.col(2) + R_opt.col(2)).norm(), 0.0, 1e-9);
  }
}

TEST_F(ModelAgreementTest, HomeAimsBothCamerasAtTheWorkspace) {
  ResetToHome();
  const Vector3d p_WTarget(0.30, 0.0, 0.05);
  const PinholeCamera camera = PinholeCamera::FromFovy(320, 240, DegToRad(55.0));
  for (const std::string side : {"left", "right"}) {
    const int site = mj_name2id(model_, mjOBJ_SITE, ("camera_" + side + "_optical").c_str());
    Pose3 X_WC = Pose3::Identity();
    X_WC.translation() = Vector3d(data_->site_xpos + 3 * site);
    X_WC.linear() = Mat3(data_->site_xmat + 9 * site);
    // The optical axis passes through the target.
    const Vector3d p_CTarget = X_WC.inverse() * p_WTarget;
    EXPECT_GT(p_CTarget.z(), 0.3);
    EXPECT_NEAR(std::hypot(p_CTarget.x(), p_CTarget.y()), 0.0, 1e-6) << side;
    // Any box of up to 15 cm anywhere in the workspace (x 0.20..0.40, y -0.15..0.15) is in view.
    double margin_px = 1e9;
    for (double x : {0.20, 0.40}) {
      for (double y : {-0.15, 0.15}) {
        for (double z : {0.0, 0.15}) {
          const auto uv = camera.Project(X_WC.inverse() * Vector3d(x, y, z));
          ASSERT_TRUE(uv.has_value());
          margin_px =
              std::min({margin_px, uv->x() + 0.5, 319.5 - uv->x(), uv->y() + 0.5, 239.5 - uv->y()});
          EXPECT_TRUE(camera.Contains(*uv)) << side << " camera does not see (" << x << ", " << y
                                            << ", " << z << "): pixel " << uv->transpose();
        }
      }
    }
    RecordProperty(side + "_min_margin_px", Fmt(margin_px));
  }
}

TEST_F(ModelAgreementTest, HomeKeepsTheArmsOffTheTable) {
  ResetToHome();
  EXPECT_EQ(data_->ncon, 0) << "something touches at home";
  const int left_base = mj_name2id(model_, mjOBJ_BODY, "left_base");
  const int right_base = mj_name2id(model_, mjOBJ_BODY, "right_base");
  int checked = 0;
  for (int g = 0; g < model_->ngeom; ++g) {
    // The moving parts of the arms: the bodies below {side}_base (fixed to the torso).
    const int body = model_->geom_bodyid[g];
    int b = body;
    while (b != 0 && b != left_base && b != right_base) b = model_->body_parentid[b];
    if (b == 0 || body == b) continue;
    // Points bounding the geom: the ends of capsules/cylinders (+- radius), box corners, and
    // sphere centres (+- radius).
    const Vector3d c(data_->geom_xpos + 3 * g);
    const Matrix3d R = Mat3(data_->geom_xmat + 9 * g);
    const mjtNum* size = model_->geom_size + 3 * g;
    std::vector<Vector3d> points;
    double r = 0.0;
    switch (model_->geom_type[g]) {
      case mjGEOM_BOX:
        for (int k = 0; k < 8; ++k) {
          points.push_back(c + R * Vector3d((k & 1 ? 1 : -1) * size[0], (k & 2 ? 1 : -1) * size[1],
                                            (k & 4 ? 1 : -1) * size[2]));
        }
        break;
      case mjGEOM_CAPSULE:
      case mjGEOM_CYLINDER:
        r = size[0];
        points.push_back(c + R.col(2) * size[1]);
        points.push_back(c - R.col(2) * size[1]);
        break;
      default:
        r = size[0];
        points.push_back(c);
    }
    for (const Vector3d& p : points) {
      const std::string where = std::string(mj_id2name(model_, mjOBJ_BODY, body)) + " geom " +
                                std::to_string(g) + " at " + Fmt(p.x()) + " " + Fmt(p.y()) + " " +
                                Fmt(p.z());
      // Out of view is checked by rendering (SimRobotTest.AtHomeTheCamerasSeeNoPartOfTheRobot).
      EXPECT_GT(p.z() - r, 0.01) << where;
    }
    ++checked;
  }
  EXPECT_GT(checked, 20);
}

TEST_F(ModelAgreementTest, HomeIsHeldForOneSecond) {
  ResetToHome();
  while (data_->time < 1.0) StepCompensated();
  ExpectNoWarnings();
  for (const std::string& joint : kArmJoints) {
    const int a = Actuator(joint);
    EXPECT_NEAR(Qpos(joint), data_->ctrl[a], 1e-3) << joint;
  }
  for (const char* joint : {"head_pan", "head_tilt", "head_verge_left", "laser", "left_thumb_slide",
                            "right_thumb_slide"}) {
    EXPECT_NEAR(Qpos(joint), data_->ctrl[Actuator(joint)], 1e-3) << joint;
  }
  // The coupled joints follow.
  EXPECT_NEAR(Qpos("head_verge_right"), Qpos("head_verge_left"), 1e-4);
  EXPECT_NEAR(Qpos("left_index_slide"), Qpos("left_thumb_slide"), 1e-4);
  EXPECT_NEAR(Qpos("right_index_slide"), Qpos("right_thumb_slide"), 1e-4);
}

/// A step of `step` (rad or m) on one servo from home: returns the largest excursion past the
/// target (in the step's direction) and the final error.
struct StepResult {
  double overshoot = 0.0;
  double final_error = 0.0;
  double time_to_90_percent = -1.0;
};

class StepResponseTest : public ModelAgreementTest,
                         public ::testing::WithParamInterface<std::string> {
 protected:
  StepResult Step(const std::string& joint, double step, double duration_s) {
    ResetToHome();
    const int a = Actuator(joint);
    const double start = data_->ctrl[a];
    const double* range = model_->actuator_ctrlrange + 2 * a;
    // Step away from the nearer end of the range.
    const double sign = (start + step <= range[1]) ? 1.0 : -1.0;
    const double target = start + sign * step;
    data_->ctrl[a] = target;
    StepResult r;
    while (data_->time < duration_s) {
      StepCompensated();
      const double past = sign * (Qpos(joint) - target);
      r.overshoot = std::max(r.overshoot, past);
      if (r.time_to_90_percent < 0 && sign * (Qpos(joint) - start) >= 0.9 * step) {
        r.time_to_90_percent = data_->time;
      }
    }
    ExpectNoWarnings();
    r.final_error = std::abs(Qpos(joint) - target);
    return r;
  }
};

TEST_P(StepResponseTest, SettlesWithoutOvershoot) {
  const std::string joint = GetParam();
  const bool finger = joint.find("thumb") != std::string::npos;
  const double step = finger ? 0.01 : 0.3;  // m or rad
  const StepResult r = Step(joint, step, 2.0);
  EXPECT_LT(r.overshoot, 0.02 * step) << joint;
  EXPECT_LT(r.final_error, 1e-3 * step / 0.3) << joint;
  EXPECT_GT(r.time_to_90_percent, 0.0) << joint;
  EXPECT_LT(r.time_to_90_percent, 0.5) << joint;  // and not sluggish
  RecordProperty("overshoot_fraction", Fmt(r.overshoot / step));
  RecordProperty("t90_s", Fmt(r.time_to_90_percent));
}

INSTANTIATE_TEST_SUITE_P(
    Servos, StepResponseTest,
    ::testing::Values("left_j1", "left_j2", "left_j3", "left_j4", "left_j5", "left_j6", "right_j1",
                      "right_j2", "right_j3", "right_j4", "right_j5", "right_j6", "head_pan",
                      "head_tilt", "head_verge_left", "laser", "left_thumb_slide"),
    [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

TEST(ModelGripTest, HandHoldsABoxAgainstGravity) {
  // A free 0.3 kg box, 6 cm wide along the fingers' closing direction, between the left hand's
  // fingers; the hand turned (left_j6 = 0) so that they close horizontally: gravity pulls across
  // the grip and only friction holds the box.
  const std::string path = ResolveDataPath("models/humanoid.xml");
  std::string error;
  const ModelPtr robot = LoadModel(path, &error);
  ASSERT_NE(robot, nullptr) << error;
  const int home = mj_name2id(robot.get(), mjOBJ_KEY, "home");
  ASSERT_GE(home, 0);
  std::string xml = ReadFile(path);
  // The keyframe's qpos would lack the box's: drop it (the simulator does the same).
  const size_t k0 = xml.find("<keyframe>"), k1 = xml.find("</keyframe>");
  ASSERT_TRUE(k0 != std::string::npos && k1 != std::string::npos);
  xml.erase(k0, k1 + std::string("</keyframe>").size() - k0);
  // Insert the box the way the simulator adds objects: before the closing worldbody tag. Being
  // last, its free joint comes after the robot's joints in qpos and qvel.
  xml.insert(xml.find("</worldbody>"),
             "<body name=\"probe_box\" pos=\"0 0 1\"><freejoint/><geom type=\"box\" "
             "size=\"0.03 0.02 0.03\" mass=\"0.3\" contype=\"1\" conaffinity=\"1\"/></body>\n");
  const std::string probe_path = ::testing::TempDir() + "/humanoid_grip_probe.xml";
  std::ofstream(probe_path) << xml;
  ModelPtr m = LoadModel(probe_path, &error);
  ASSERT_NE(m, nullptr) << error;
  EXPECT_EQ(error, "");
  DataPtr d(mj_makeData(m.get()));
  const auto id = [&](mjtObj type, const char* name) {
    const int i = mj_name2id(m.get(), type, name);
    EXPECT_GE(i, 0) << name;
    return i;
  };
  const auto qpos = [&](const char* joint) -> double& {
    return d->qpos[m->jnt_qposadr[id(mjOBJ_JOINT, joint)]];
  };
  const int box_joint = m->body_jntadr[id(mjOBJ_BODY, "probe_box")];
  const int box_q = m->jnt_qposadr[box_joint];
  const int robot_nv = m->jnt_dofadr[box_joint];
  ASSERT_EQ(robot->nq, box_q);
  ASSERT_EQ(robot->nu, m->nu);
  std::copy_n(robot->key_qpos + home * robot->nq, robot->nq, d->qpos);
  std::copy_n(robot->key_ctrl + home * robot->nu, robot->nu, d->ctrl);
  // The left arm in a pose of its own (not the keyframe's): upper arm down, forearm out to the
  // side, hand forward, turned so that the fingers close horizontally.
  const double arm_deg[6] = {90, -90, 0, -90, 0, 0};
  for (int i = 0; i < 6; ++i) {
    const std::string joint = "left_j" + std::to_string(i + 1);
    qpos(joint.c_str()) = arm_deg[i] * M_PI / 180.0;
    d->ctrl[id(mjOBJ_ACTUATOR, joint.c_str())] = arm_deg[i] * M_PI / 180.0;
  }
  qpos("left_thumb_slide") = qpos("left_index_slide") = 0.0305;
  mj_kinematics(m.get(), d.get());
  const int grip = id(mjOBJ_BODY, "left_gripper");
  const Vector3d p_WE(d->xpos + 3 * grip);
  const Matrix3d R_WE = Mat3(d->xmat + 9 * grip);
  ASSERT_LT(std::abs(R_WE.col(0).z()), 1e-9) << "the fingers should close horizontally";
  const Vector3d p_WBox = p_WE + R_WE * Vector3d(0, 0, 0.10);
  const Eigen::Quaterniond q_WBox(R_WE);
  Eigen::Map<Vector3d>(d->qpos + box_q) = p_WBox;
  d->qpos[box_q + 3] = q_WBox.w();
  d->qpos[box_q + 4] = q_WBox.x();
  d->qpos[box_q + 5] = q_WBox.y();
  d->qpos[box_q + 6] = q_WBox.z();

  // Close: command the fingers 2 cm inside the box, so that the grip force saturates at 40 N.
  const int hand = id(mjOBJ_ACTUATOR, "left_thumb_slide");
  d->ctrl[hand] = 0.01;
  const auto p_EBox = [&]() -> Vector3d {
    return Mat3(d->xmat + 9 * grip).transpose() *
           (Vector3d(d->qpos + box_q) - Vector3d(d->xpos + 3 * grip));
  };
  Vector3d p_EBox_held = Vector3d::Zero();
  // 0.5 s to close, then held 30 s: a run through the twin's wires holds the box 60 s and more
  // (its serial lines take their baud rate's time), and soft contacts creep.
  for (int step = 1; step <= 15250; ++step) {
    mj_step1(m.get(), d.get());
    for (int i = 0; i < robot_nv; ++i) d->qfrc_applied[i] = d->qfrc_bias[i];
    mj_step2(m.get(), d.get());
    if (step == 250) p_EBox_held = p_EBox();  // 0.5 s: closed
  }
  for (int i = 0; i < mjNWARNING; ++i) EXPECT_EQ(d->warning[i].number, 0) << "warning " << i;
  // It drops a little while the fingers close, then stays put in the hand (it crept 0.09 mm/s
  // without the noslip solver: 2.7 mm in 30 s).
  const Vector3d p_WBoxNow(d->qpos + box_q);
  EXPECT_LT((p_WBoxNow - p_WBox).norm(), 0.005) << "the box fell: " << p_WBoxNow.transpose();
  EXPECT_LT((p_EBox() - p_EBox_held).norm(), 1e-4) << "the box slipped in the hand";
  EXPECT_NEAR(qpos("left_thumb_slide") + qpos("left_index_slide"), 0.06, 0.002);
  EXPECT_NEAR(qpos("left_thumb_slide"), qpos("left_index_slide"), 5e-4) << "coupling too soft";
  EXPECT_GT(std::abs(d->actuator_force[hand]), 35.0) << "grip force near its 40 N limit";
  RecordProperty("box_slip_m", Fmt((p_EBox() - p_EBox_held).norm()));
  RecordProperty("finger_asymmetry_m", Fmt(qpos("left_thumb_slide") - qpos("left_index_slide")));
  RecordProperty("grip_force_n", Fmt(d->actuator_force[hand]));
}

}  // namespace
}  // namespace hgrasp
