#include "emulators/sensorhand_emulator.h"

#include <algorithm>
#include <cmath>

namespace hgrasp::drivers {
namespace {

using sensorhand::Command;
using sensorhand::SpeedSetting;

constexpr double kStepS = 1e-3;         // mechanics sub-step
constexpr double kIdleCurrentA = 0.05;  // electronics alone
constexpr double kStillM_s = 1e-3;      // slower than this: the fingers do not move

AxisLimits Limits(const SensorHandMechanics& m) {
  AxisLimits l;
  l.min = 0.0;
  l.max = m.max_opening_m;
  l.max_speed = m.max_speed_m_s;
  l.max_accel = m.accel_m_s2;
  return l;
}

}  // namespace

// --- Mechanics --------------------------------------------------------------------------------

KinematicSensorHand::KinematicSensorHand(const SensorHandMechanics& m)
    : m_(m), axis_(Limits(m), m.opening_m) {}

void KinematicSensorHand::Drive(double velocity_m_s, double stall_force_n) {
  velocity_cmd_ = std::clamp(velocity_m_s, -m_.max_speed_m_s, m_.max_speed_m_s);
  // Only closing sets the stall force: stopped or opening, the gear holds what it pressed with.
  if (velocity_m_s < 0.0) stall_force_n_ = std::max(0.0, stall_force_n);
}

double KinematicSensorHand::grip_force_n() const {
  if (m_.object_width_m <= 0.0) return 0.0;
  return std::max(0.0, m_.object_stiffness_n_m * (m_.object_width_m - axis_.position()));
}

double KinematicSensorHand::current_a() const {
  if (velocity_cmd_ == 0.0) return kIdleCurrentA;
  // Ours: about 1.1 A at a 100 N stall, 0.35 A running free at full speed.
  return kIdleCurrentA + 1.0 * grip_force_n() / 100.0 +
         0.3 * std::abs(axis_.velocity()) / m_.max_speed_m_s;
}

void KinematicSensorHand::Advance(double dt_s) {
  while (dt_s > 0.0) {
    const double h = std::min(dt_s, kStepS);
    dt_s -= h;
    const double force = grip_force_n();
    double v = velocity_cmd_;
    if (v < 0.0 && force > 0.0) {
      // The motor's torque-speed line: slower the harder it presses, stalled at the stall force.
      v *= stall_force_n_ > 0.0 ? std::max(0.0, 1.0 - force / stall_force_n_) : 0.0;
    }
    const double y_before = axis_.position();
    axis_.MoveAt(v, m_.accel_m_s2);
    axis_.Advance(h);
    if (m_.object_width_m > 0.0 && m_.object_stiffness_n_m > 0.0) {
      // Running on into the object after a stop or at a stall never presses harder than the
      // motor can: the gear stops at the stall force. It never moves the fingers back out: a
      // weaker close speed on a stronger grip stalls at once and holds (the gear does not
      // back-drive; it once sprang back to the weaker stall force's opening).
      const double y_min =
          m_.object_width_m - std::max(stall_force_n_, 0.0) / m_.object_stiffness_n_m;
      if (axis_.position() < y_min && axis_.velocity() <= 0.0) {
        axis_ = TrapezoidAxis(Limits(m_), std::max(axis_.position(), std::min(y_before, y_min)));
      }
    }
  }
}

// --- Protocol ---------------------------------------------------------------------------------

SensorHandEmulator::SensorHandEmulator(std::unique_ptr<SensorHandModel> model,
                                       SensorHandScale scale)
    : model_(std::move(model)), scale_(scale) {}

std::vector<SpeedSetting> SensorHandEmulator::speed_log() const {
  std::vector<SpeedSetting> v;
  for (const SensorHandLogEntry& e : log_) {
    if (e.command.kind == Command::Kind::kSpeed) v.push_back(e.command.speed);
  }
  return v;
}

void SensorHandEmulator::StepModel(double t_s) {
  if (!started_) {
    started_ = true;
    model_t_ = t_s;
    next_sample_t_ = t_s;
    return;
  }
  if (t_s > model_t_) {
    model_->Advance(t_s - model_t_);
    model_t_ = t_s;
  }
  const bool still = std::abs(model_->velocity_m_s()) < kStillM_s;
  if (still && !still_) still_since_t_ = t_s;
  still_ = still;
}

void SensorHandEmulator::Advance(double t_s, std::vector<std::uint8_t>* out) {
  StepModel(t_s);
  if (!streaming_ || t_s < next_sample_t_) return;
  // One frame per period, and at most one per call: a late call does not make up for the
  // frames it missed (a real hand's timer would have sent them; a late host cannot).
  const auto frame = sensorhand::EncodeDump(Sample());
  out->insert(out->end(), frame.begin(), frame.end());
  ++samples_sent_;
  next_sample_t_ += sensorhand::kDumpPeriodS;
  if (next_sample_t_ <= t_s) next_sample_t_ = t_s + sensorhand::kDumpPeriodS;
}

void SensorHandEmulator::Receive(std::span<const std::uint8_t> in, double t_s,
                                 std::vector<std::uint8_t>* out) {
  StepModel(t_s);
  if (decoder_.buffered() > 0 && t_s - last_rx_t_ > kFrameGapS) decoder_.Reset();
  last_rx_t_ = t_s;
  std::vector<Command> commands;
  decoder_.Push(in, &commands);
  for (const Command& c : commands) Execute(c, t_s, out);
}

void SensorHandEmulator::Execute(const Command& c, double t_s, std::vector<std::uint8_t>* out) {
  log_.push_back({t_s, c});
  std::vector<std::uint8_t> echo;
  switch (c.kind) {
    case Command::Kind::kSpeed: {
      speed_ = c.speed;
      ++counter_;
      still_since_t_ = t_s;  // the stall detector's window starts again
      const double open = sensorhand::SpeedFraction(c.speed.open);
      const double close = sensorhand::SpeedFraction(c.speed.close);
      model_->Drive(scale_.full_speed_m_s * (open - close),
                    scale_.full_force_n * std::max(open, close));
      echo = sensorhand::EncodeSpeedEcho(c.speed);
      break;
    }
    case Command::Kind::kDumpStart:
      if (!streaming_) next_sample_t_ = t_s;
      streaming_ = true;
      echo = sensorhand::EncodeDumpStart();
      break;
    case Command::Kind::kDumpStop:
      streaming_ = false;
      echo = sensorhand::EncodeDumpStop();
      break;
  }
  out->insert(out->end(), echo.begin(), echo.end());
}

void SensorHandEmulator::PowerCycle() {
  streaming_ = false;
  speed_ = sensorhand::kStop;
  counter_ = 0;
  decoder_.Reset();
  model_->Drive(0.0, 0.0);
}

sensorhand::DumpSample SensorHandEmulator::Sample() const {
  using sensorhand::MotionState;
  const double v = model_->velocity_m_s();
  const double force = model_->grip_force_n();
  MotionState state;
  if (speed_.stopped()) {
    state = std::abs(v) < kStillM_s ? MotionState::kIdle
            : v > 0.0               ? MotionState::kOpening
                                    : MotionState::kClosing;
  } else if (std::abs(v) >= kStillM_s) {
    state = v > 0.0 ? MotionState::kOpening : MotionState::kClosing;
  } else if (still_ && model_t_ - still_since_t_ >= kBlockedAfterS) {
    state = MotionState::kBlocked;
  } else {
    // Told to move, still, not yet long enough to call it blocked: the state of the command.
    state = speed_.open != 0 ? MotionState::kOpening : MotionState::kClosing;
  }
  sensorhand::DumpSample d;
  d.v_open = 0;  // communications mode: no electrodes
  d.v_close = 0;
  d.v_bat = sensorhand::BatteryRaw(scale_.battery_v);
  d.state = static_cast<std::uint8_t>(state);
  d.f_bracket = sensorhand::ForceRaw(force);
  const std::uint8_t pad = sensorhand::ForceRaw(force / 3.0);  // ours: shared by three pads
  d.f_pad = {pad, pad, pad};
  d.current = sensorhand::CurrentRaw(model_->current_a());
  // That is all a stock hand sends: no opening, speed setting or counter on the wire.
  return d;
}

std::unique_ptr<DeviceEmulator> MakeSensorHandEmulator() {
  SensorHandMechanics m;
  m.object_width_m = 0.05;
  return std::make_unique<SensorHandEmulator>(std::make_unique<KinematicSensorHand>(m));
}

}  // namespace hgrasp::drivers
