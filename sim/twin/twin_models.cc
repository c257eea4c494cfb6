#include "sim/twin/twin_models.h"

#include <algorithm>
#include <cmath>

namespace hgrasp::sim {

namespace {

std::string SideName(device::Side s) { return std::string(device::ToString(s)); }

constexpr const char* kHeadJoints[3] = {"head_pan", "head_tilt", "head_verge_left"};

}  // namespace

// ----- TwinArmModel -----

TwinArmModel::TwinArmModel(World* world, device::Side side) : world_(world) {
  const mjModel* m = world->model();
  for (int i = 0; i < 6; ++i) {
    const std::string name = SideName(side) + "_j" + std::to_string(i + 1);
    const int joint = world->Id(mjOBJ_JOINT, name);
    qpos_[i] = m->jnt_qposadr[joint];
    dof_[i] = m->jnt_dofadr[joint];
    actuator_.push_back(world->Id(mjOBJ_ACTUATOR, name));
  }
}

device::Joint6 TwinArmModel::q() const {
  device::Joint6 q;
  for (int i = 0; i < 6; ++i) q[i] = world_->EncoderReading(actuator_[i]);
  return q;
}

device::Joint6 TwinArmModel::qd() const {
  device::Joint6 qd;
  for (int i = 0; i < 6; ++i) qd[i] = world_->data()->qvel[dof_[i]];
  return qd;
}

bool TwinArmModel::moving() const { return world_->Moving(actuator_); }

void TwinArmModel::MoveJoints(const device::Joint6& q_target, double speed_fraction) {
  std::vector<double> goal(q_target.data(), q_target.data() + 6), limit(6);
  const double f = std::clamp(speed_fraction, 1e-3, 1.0);
  for (int i = 0; i < 6; ++i) limit[i] = f * world_->SpeedLimit(actuator_[i]);
  world_->StartMotion(actuator_, goal, limit, false);
}

void TwinArmModel::Stop() {
  // The controller decelerates to rest where the arm is: the set-point held at the joints now.
  world_->StopMotion(actuator_);
  for (int i = 0; i < 6; ++i) world_->data()->ctrl[actuator_[i]] = world_->data()->qpos[qpos_[i]];
}

// ----- TwinHandModel -----

TwinHandModel::TwinHandModel(World* world, device::Side side) : world_(world) {
  const std::string name = SideName(side) + "_thumb_slide";
  const mjModel* m = world->model();
  const int joint = world->Id(mjOBJ_JOINT, name);
  qpos_ = m->jnt_qposadr[joint];
  dof_ = m->jnt_dofadr[joint];
  actuator_ = world->Id(mjOBJ_ACTUATOR, name);
  thumb_body_ = m->jnt_bodyid[joint];
  lo_ = m->jnt_range[2 * joint];
  hi_ = m->jnt_range[2 * joint + 1];
}

void TwinHandModel::Drive(double velocity_m_s, double stall_force_n) {
  velocity_m_s_ = velocity_m_s;
  if (velocity_m_s != 0.0) {
    // The motor's stall force bounds what the fingers press with; at rest the gear holds the
    // force the motor left (the bound stays).
    mjModel* m = world_->mutable_model();
    const double f = std::max(stall_force_n, 1.0);
    m->actuator_forcerange[2 * actuator_] = -f;
    m->actuator_forcerange[2 * actuator_ + 1] = f;
  }
}

void TwinHandModel::Apply(double dt_s) {
  if (velocity_m_s_ == 0.0) {
    motor_velocity_m_s_ = 0.0;
    return;
  }
  world_->StopMotion({actuator_});
  const mjModel* m = world_->model();
  double& ctrl = world_->data()->ctrl[actuator_];
  const double ctrl_before = ctrl;
  // Pad distance = 2 x thumb slide.
  ctrl = std::clamp(ctrl + 0.5 * velocity_m_s_ * dt_s, lo_, hi_);
  // Closing on something: a geared motor against a stiff object stalls within milliseconds at
  // its stall force, and the worm gear holds it there when it stops. The world's finger is a
  // position servo (kp 2000 N/m), so the stall is the set-point that far inside the finger:
  // without this the set-point crept in at the closing speed and the driver, seeing the
  // fingers blocked, stopped it a few newtons in (a grip too weak to lift a box).
  const double q = world_->data()->qpos[qpos_];
  const double qd = world_->data()->qvel[dof_];
  // Blocked: the set-point 2 mm inside the finger and the finger all but still (5% of the
  // commanded speed). A finger starting from rest lags its set-point by less and moves faster
  // by the time the lag is 2 mm (the servo accelerates it at 4 m/s^2 per mm of lag).
  const bool blocked =
      std::abs(qd) < 0.05 * std::abs(0.5 * velocity_m_s_) && ctrl < q - 0.002;
  if (velocity_m_s_ < 0.0 && blocked) {
    const double kp = m->actuator_gainprm[mjNGAIN * actuator_];
    const double stall_n = m->actuator_forcerange[2 * actuator_ + 1];
    if (kp > 0.0) ctrl = std::clamp(std::min(ctrl, q - stall_n / kp), lo_, hi_);
  }
  motor_velocity_m_s_ = dt_s > 0.0 ? 2.0 * (ctrl - ctrl_before) / dt_s : 0.0;
}

double TwinHandModel::opening_m() const { return 2.0 * world_->data()->qpos[qpos_]; }

double TwinHandModel::grip_force_n() const {
  // What the hand's force sensor reads: the thumb's contact forces along their normals (the
  // actuator's force would read the 6 N that drive the free finger through its damping, and
  // the driver would take it for a grip).
  const mjModel* m = world_->model();
  const mjData* d = world_->data();
  double force = 0.0;
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& c = d->contact[i];
    const int b1 = m->geom_bodyid[c.geom1], b2 = m->geom_bodyid[c.geom2];
    if (b1 != thumb_body_ && b2 != thumb_body_) continue;
    mjtNum f[6];
    mj_contactForce(m, d, i, f);
    force += std::abs(f[0]);
  }
  return force;
}

double TwinHandModel::velocity_m_s() const {
  // The motor's speed (its worm gear is the set-point; the world's finger servo models the
  // fingers' and pads' compliance): what the hand's own sensing sees.
  return motor_velocity_m_s_;
}

double TwinHandModel::current_a() const {
  // As KinematicSensorHand: idle current, plus about 1 A at a 100 N stall and 0.3 A running
  // free at full speed, while the motor is driven.
  constexpr double kIdleCurrentA = 0.05;
  if (velocity_m_s_ == 0.0) return kIdleCurrentA;
  return kIdleCurrentA + 1.0 * grip_force_n() / 100.0 +
         0.3 * std::abs(velocity_m_s()) / max_speed_m_s_;
}

// ----- TwinBoardHardware -----

TwinBoardHardware::TwinBoardHardware(World* world, const drivers::AxisLimits& motor)
    : world_(world),
      motor_(motor, world->JointPosition("laser") / kLaserRadPerCount),
      actuator_(world->Id(mjOBJ_ACTUATOR, "laser")) {}

void TwinBoardHardware::Advance(double t_s, std::vector<drivers::VsyncLatch>* latches) {
  while (!pending_.empty() && pending_.front().t_s <= t_s + 1e-9) {
    latches->push_back(pending_.front());
    pending_.pop_front();
  }
}

std::int32_t TwinBoardHardware::EncoderCount() const {
  return static_cast<std::int32_t>(std::lround(world_->JointPosition("laser") / kLaserRadPerCount));
}

void TwinBoardHardware::MoveAt(double counts_s) {
  if (counts_s == 0) {
    motor_.Stop();
  } else {
    motor_.MoveAt(counts_s, motor_.limits().max_accel);
  }
}

void TwinBoardHardware::MoveTo(std::int32_t count, double speed_counts_s) {
  motor_.MoveTo(count, speed_counts_s, motor_.limits().max_accel);
}

void TwinBoardHardware::SetLeds(int side, std::uint32_t mask) {
  const int s = side == 0 ? 0 : 1;
  leds_[s] = mask;
  const std::string name = s == 0 ? "left" : "right";
  const int n = world_->LedCount(name);
  for (int i = 0; i < n; ++i) world_->SetLed(name, i, (mask >> i) & 1u);
}

std::int32_t TwinBoardHardware::Latch() {
  const std::int32_t count = EncoderCount();
  pending_.push_back({world_->time(), count, world_->laser_on()});
  return count;
}

void TwinBoardHardware::Apply(double dt_s) {
  motor_.Advance(dt_s);
  world_->StopMotion({actuator_});
  world_->data()->ctrl[actuator_] = motor_.position() * kLaserRadPerCount;
}

// ----- TwinHeadMirror -----

TwinHeadMirror::TwinHeadMirror(World* world, const drivers::BiclopsEmulator* chip,
                               double rad_per_count)
    : world_(world), chip_(chip), rad_per_count_(rad_per_count) {
  for (int i = 0; i < 3; ++i) actuator_[i] = world->Id(mjOBJ_ACTUATOR, kHeadJoints[i]);
}

void TwinHeadMirror::Apply() {
  for (int i = 0; i < 3; ++i) {
    world_->data()->ctrl[actuator_[i]] = chip_->chip().position_counts(i) * rad_per_count_;
  }
}

std::array<double, 3> TwinHeadMirror::Counts(const World& world, double rad_per_count) {
  std::array<double, 3> c;
  for (int i = 0; i < 3; ++i) c[i] = world.JointPosition(kHeadJoints[i]) / rad_per_count;
  return c;
}

}  // namespace hgrasp::sim
