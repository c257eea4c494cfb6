#include "sim/sim_devices.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "common/error.h"

namespace hgrasp::sim {
namespace {

using device::Joint6;
using device::Side;
using device::Status;

std::string SideName(Side s) { return std::string(device::ToString(s)); }

bool WithinRange(const mjModel* m, int joint, double q) {
  return q >= m->jnt_range[2 * joint] - 1e-9 && q <= m->jnt_range[2 * joint + 1] + 1e-9;
}

class SimArm final : public device::Arm {
 public:
  SimArm(World* world, Side side) : world_(world), side_(side) {
    const std::string s = SideName(side);
    for (int i = 0; i < 6; ++i) {
      const std::string name = s + "_j" + std::to_string(i + 1);
      joint_[i] = world->Id(mjOBJ_JOINT, name);
      actuator_.push_back(world->Id(mjOBJ_ACTUATOR, name));
    }
  }

  Status Read(device::ArmState* state) override {
    const mjModel* m = world_->model();
    const mjData* d = world_->data();
    state->t_s = d->time;
    for (int i = 0; i < 6; ++i) {
      state->q[i] = world_->EncoderReading(actuator_[i]);
      state->qd[i] = d->qvel[m->jnt_dofadr[joint_[i]]];
    }
    state->moving = world_->Moving(actuator_);
    return Status::kOk;
  }

  Status MoveJoints(const Joint6& q_target) override {
    for (int i = 0; i < 6; ++i) {
      if (!WithinRange(world_->model(), joint_[i], q_target[i])) return Status::kRejected;
    }
    std::vector<double> goal(q_target.data(), q_target.data() + 6), limit(6);
    for (int i = 0; i < 6; ++i) limit[i] = speed_ * world_->SpeedLimit(actuator_[i]);
    world_->StartMotion(actuator_, goal, limit, false);
    return Status::kOk;
  }

  Status MoveRelative(const Pose3& X_EEnew) override {
    // The controller's own (nominal) inverse kinematics, from the set-point it holds now as
    // its encoders count it.
    Joint6 q_now;
    for (int i = 0; i < 6; ++i) q_now[i] = world_->EncoderSetpoint(actuator_[i]);
    const Pose3 X_WE = ArmForwardKinematics(*world_, side_, q_now);
    const auto q = ArmInverseKinematics(*world_, side_, X_WE * X_EEnew, q_now);
    if (!q) return Status::kRejected;
    return MoveJoints(*q);
  }

  Status SetSpeed(double fraction) override {
    if (!(fraction > 0.0 && fraction <= 1.0)) return Status::kRejected;
    speed_ = fraction;
    return Status::kOk;
  }

  Status Stop() override {
    world_->StopMotion(actuator_);
    return Status::kOk;
  }

 private:
  World* world_;
  Side side_;
  int joint_[6];
  std::vector<int> actuator_;
  double speed_ = 1.0;
};

class SimHand final : public device::Hand {
 public:
  SimHand(World* world, Side side) : world_(world) {
    const std::string name = SideName(side) + "_thumb_slide";
    joint_ = world->Id(mjOBJ_JOINT, name);
    actuator_ = world->Id(mjOBJ_ACTUATOR, name);
  }

  Status Read(device::HandState* state) override {
    const mjModel* m = world_->model();
    state->t_s = world_->time();
    state->opening_m = 2.0 * world_->data()->qpos[m->jnt_qposadr[joint_]];
    state->grip_force_n = std::abs(world_->data()->actuator_force[actuator_]);
    state->moving = world_->Moving({actuator_});
    return Status::kOk;
  }

  Status Open(double opening_m) override {
    const mjModel* m = world_->model();
    SetForceLimit(kMaxForceN);
    const double q =
        std::clamp(0.5 * opening_m, m->jnt_range[2 * joint_], m->jnt_range[2 * joint_ + 1]);
    world_->StartMotion({actuator_}, {q}, {world_->SpeedLimit(actuator_)}, false);
    return Status::kOk;
  }

  Status Close(double max_force_n) override {
    if (!(max_force_n > 0.0)) return Status::kRejected;
    SetForceLimit(std::min(max_force_n, kMaxForceN));
    world_->StartMotion({actuator_}, {world_->model()->jnt_range[2 * joint_]},
                        {world_->SpeedLimit(actuator_)}, false);
    return Status::kOk;
  }

 private:
  static constexpr double kMaxForceN = 100.0;  // DESIGN.md: grip force 10-100 N
  void SetForceLimit(double f) {
    mjModel* m = world_->mutable_model();
    m->actuator_forcerange[2 * actuator_] = -f;
    m->actuator_forcerange[2 * actuator_ + 1] = f;
  }
  World* world_;
  int joint_, actuator_;
};

class SimHead final : public device::Head {
 public:
  explicit SimHead(World* world) : world_(world) {
    for (const char* name : {"head_pan", "head_tilt", "head_verge_left"}) {
      joint_.push_back(world->Id(mjOBJ_JOINT, name));
      actuator_.push_back(world->Id(mjOBJ_ACTUATOR, name));
    }
  }

  Status Read(device::HeadState* state) override {
    state->t_s = world_->time();
    state->q = Joints(world_);
    state->moving = world_->Moving(actuator_);
    return Status::kOk;
  }

  Status MoveTo(const device::HeadJoints& target) override {
    const std::vector<double> goal = {target.pan, target.tilt, target.verge};
    std::vector<double> limit;
    for (int i = 0; i < 3; ++i) {
      if (!WithinRange(world_->model(), joint_[i], goal[i])) return Status::kRejected;
      limit.push_back(world_->SpeedLimit(actuator_[i]));
    }
    world_->StartMotion(actuator_, goal, limit, false);
    return Status::kOk;
  }

  Status Stop() override {
    world_->StopMotion(actuator_);
    return Status::kOk;
  }

  /// As the head's encoders read them.
  static device::HeadJoints Joints(const World* world) {
    return {world->EncoderReading(world->Id(mjOBJ_ACTUATOR, "head_pan")),
            world->EncoderReading(world->Id(mjOBJ_ACTUATOR, "head_tilt")),
            world->EncoderReading(world->Id(mjOBJ_ACTUATOR, "head_verge_left"))};
  }

 private:
  World* world_;
  std::vector<int> joint_, actuator_;
};

class SimStripeLaser final : public device::StripeLaser {
 public:
  explicit SimStripeLaser(World* world)
      : world_(world),
        joint_(world->Id(mjOBJ_JOINT, "laser")),
        actuator_(world->Id(mjOBJ_ACTUATOR, "laser")) {}

  Status Read(device::StripeLaserState* state) override {
    state->t_s = world_->time();
    state->encoder_count = Count(world_);
    state->laser_on = world_->laser_on();
    state->moving = world_->Moving({actuator_});
    return Status::kOk;
  }

  Status SetLaser(bool on) override {
    world_->set_laser_on(on);
    return Status::kOk;
  }

  Status MoveTo(std::int32_t count, double speed_counts_s) override {
    const double goal = count * kLaserRadPerCount;
    if (!(speed_counts_s > 0) || !WithinRange(world_->model(), joint_, goal))
      return Status::kRejected;
    const double speed =
        std::min(speed_counts_s * kLaserRadPerCount, world_->SpeedLimit(actuator_));
    world_->StartMotion({actuator_}, {goal}, {speed}, true);
    return Status::kOk;
  }

  Status Stop() override {
    world_->StopMotion({actuator_});
    return Status::kOk;
  }

  /// The encoder: the motor angle in whole counts.
  static std::int32_t Count(const World* world) {
    return static_cast<std::int32_t>(
        std::lround(world->JointPosition("laser") / kLaserRadPerCount));
  }

 private:
  World* world_;
  int joint_, actuator_;
};

class SimLeds final : public device::Leds {
 public:
  explicit SimLeds(World* world) : world_(world) {}
  int Count(Side side) const override { return world_->LedCount(SideName(side)); }
  Status Set(Side side, std::uint32_t mask) override {
    const int n = Count(side);
    if (n < 32 && (mask >> n) != 0) return Status::kRejected;
    for (int i = 0; i < n; ++i) world_->SetLed(SideName(side), i, (mask >> i) & 1u);
    return Status::kOk;
  }

 private:
  World* world_;
};

class SimStereoCamera final : public device::StereoCamera {
 public:
  SimStereoCamera(World* world, StereoRig* rig) : world_(world), rig_(rig) {}

  Status Grab(device::StereoFrame* frame) override { return NextFrame(frame, true); }
  Status GrabWithoutImages(device::StereoFrame* frame) override { return NextFrame(frame, false); }

 private:
  // One frame period on, the readings latched; the exposure composed, or (without images) left
  // to the rig's pending renders, so that later frames are the same either way.
  Status NextFrame(device::StereoFrame* frame, bool images) {
    world_->Step(kFramePeriodS);
    frame->t_s = world_->time();
    frame->sequence = sequence_++;
    frame->laser_encoder_count = SimStripeLaser::Count(world_);
    frame->laser_on = world_->laser_on();
    frame->head = SimHead::Joints(world_);
    if (!images) {
      rig_->SkipExposure();
      frame->left.release();
      frame->right.release();
      return Status::kOk;
    }
    StereoImages exposure = rig_->Expose(frame->sequence);
    frame->left = std::move(exposure.image[kLeft]);
    frame->right = std::move(exposure.image[kRight]);
    return Status::kOk;
  }

  World* world_;
  StereoRig* rig_;
  std::uint64_t sequence_ = 0;
};

}  // namespace

namespace {

// The arm's joint ids and gripper body, and a scratch state at the world's current state.
struct ArmChain {
  int joint[6];
  int gripper;
};

ArmChain Chain(const World& world, Side side) {
  ArmChain c;
  const std::string s = SideName(side);
  for (int i = 0; i < 6; ++i) c.joint[i] = world.Id(mjOBJ_JOINT, s + "_j" + std::to_string(i + 1));
  c.gripper = world.Id(mjOBJ_BODY, s + "_gripper");
  return c;
}

Pose3 GripperPose(const mjData* d, int body) {
  return PoseFromMujoco(d->xpos + 3 * body, d->xmat + 9 * body);
}

}  // namespace

Pose3 ArmForwardKinematics(const World& world, Side side, const Joint6& q) {
  const mjModel* m = world.nominal_model();
  const ArmChain chain = Chain(world, side);
  mjData* scratch = mj_makeData(m);
  mju_copy(scratch->qpos, world.data()->qpos, m->nq);
  for (int i = 0; i < 6; ++i) scratch->qpos[m->jnt_qposadr[chain.joint[i]]] = q[i];
  mj_kinematics(m, scratch);
  const Pose3 X = GripperPose(scratch, chain.gripper);
  mj_deleteData(scratch);
  return X;
}

std::optional<Joint6> ArmInverseKinematics(const World& world, Side side, const Pose3& X_WE,
                                           const Joint6& q_start) {
  // Damped least squares on the gripper's Jacobian (MuJoCo's), as a Puma controller solves
  // its tool moves: local, from the configuration it holds.
  const mjModel* m = world.nominal_model();
  const ArmChain chain = Chain(world, side);
  mjData* scratch = mj_makeData(m);
  mju_copy(scratch->qpos, world.data()->qpos, m->nq);
  for (int i = 0; i < 6; ++i) scratch->qpos[m->jnt_qposadr[chain.joint[i]]] = q_start[i];
  std::vector<mjtNum> jacp(3 * m->nv), jacr(3 * m->nv);
  bool converged = false;
  for (int iter = 0; iter < 300 && !converged; ++iter) {
    mj_kinematics(m, scratch);
    mj_comPos(m, scratch);
    const Pose3 X = GripperPose(scratch, chain.gripper);
    Eigen::Matrix<double, 6, 1> e;
    e.head<3>() = X_WE.translation() - X.translation();
    const Eigen::AngleAxisd aa(X_WE.linear() * X.linear().transpose());
    e.tail<3>() = aa.angle() * aa.axis();
    if (e.head<3>().norm() < 1e-7 && e.tail<3>().norm() < 1e-6) {
      converged = true;
      break;
    }
    mj_jacBody(m, scratch, jacp.data(), jacr.data(), chain.gripper);
    Eigen::Matrix<double, 6, 6> J;
    for (int i = 0; i < 6; ++i) {
      const int dof = m->jnt_dofadr[chain.joint[i]];
      for (int r = 0; r < 3; ++r) {
        J(r, i) = jacp[r * m->nv + dof];
        J(r + 3, i) = jacr[r * m->nv + dof];
      }
    }
    // Damping grows with the error: long steps stay stable, the last ones are Gauss-Newton.
    const double lambda2 = 1e-6 + 1e-3 * e.squaredNorm();
    const Eigen::Matrix<double, 6, 1> dq =
        J.transpose() *
        (J * J.transpose() + lambda2 * Eigen::Matrix<double, 6, 6>::Identity()).ldlt().solve(e);
    for (int i = 0; i < 6; ++i) scratch->qpos[m->jnt_qposadr[chain.joint[i]]] += dq[i];
  }
  Joint6 q;
  for (int i = 0; i < 6; ++i) q[i] = scratch->qpos[m->jnt_qposadr[chain.joint[i]]];
  mj_deleteData(scratch);
  if (!converged) return std::nullopt;
  for (int i = 0; i < 6; ++i) {
    if (!WithinRange(m, chain.joint[i], q[i])) return std::nullopt;
  }
  return q;
}

device::RobotDevices MakeSimDevices(World* world, StereoRig* rig) {
  device::RobotDevices d;
  for (Side s : {Side::kLeft, Side::kRight}) {
    d.arm[static_cast<int>(s)] = std::make_unique<SimArm>(world, s);
    d.hand[static_cast<int>(s)] = std::make_unique<SimHand>(world, s);
  }
  d.head = std::make_unique<SimHead>(world);
  d.laser = std::make_unique<SimStripeLaser>(world);
  d.leds = std::make_unique<SimLeds>(world);
  d.cameras = std::make_unique<SimStereoCamera>(world, rig);
  return d;
}

SimRobot::SimRobot(Scenario scenario, const WorldOptions& options)
    : world_(std::make_unique<World>(std::move(scenario), options)),
      rig_(std::make_unique<StereoRig>(world_.get())) {}

device::RobotDevices SimRobot::TakeDevices() { return MakeSimDevices(world_.get(), rig_.get()); }

}  // namespace hgrasp::sim
