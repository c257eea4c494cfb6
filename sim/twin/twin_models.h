#pragma once
/// @file The device emulators' models backed by the physics twin: each byte-exact emulator of
/// drivers/emulators/ keeps its protocol and its controller, and the mechanism it drives is the
/// MuJoCo world's. The controllers' set-points go to the world's position actuators (which
/// track them with gravity compensation, as the real servo loops do); what the device reads
/// back (joint angles, encoder counts, finger opening and force) is the world's actual state.
///
/// Threading: none. The twin (sim/twin/twin.h) calls the emulators and these models from its
/// one loop, between physics steps; `Apply(dt)` runs before each step.

#include <array>
#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "device/arm.h"
#include "emulators/biclops_emulator.h"
#include "emulators/laser_board_emulator.h"
#include "emulators/sensorhand_emulator.h"
#include "emulators/val2_emulator.h"
#include "sim/world.h"

namespace hgrasp::sim {

/// A Puma arm under its VAL II controller: the controller's joint-interpolated moves are the
/// world's synchronised motion generator (as in the lockstep simulation); the joints read back
/// are the world's.
class TwinArmModel final : public drivers::Val2ArmModel {
 public:
  TwinArmModel(World* world, device::Side side);
  device::Joint6 q() const override;
  device::Joint6 qd() const override;
  bool moving() const override;
  void MoveJoints(const device::Joint6& q_target, double speed_fraction) override;
  void Stop() override;
  /// The world steps itself: nothing to do.
  void Advance(double dt) override {}

 private:
  World* world_;
  std::array<int, 6> qpos_, dof_;
  std::vector<int> actuator_;
};

/// A SensorHand's motor and gear on the world's thumb slide: the motor drives the finger
/// set-point at the commanded pad speed, and its stall force bounds the actuator's force; at
/// speed 0 the set-point and force bound stay (the worm gear does not back-drive, so a grip
/// keeps pressing).
class TwinHandModel final : public drivers::SensorHandModel {
 public:
  TwinHandModel(World* world, device::Side side);
  void Drive(double velocity_m_s, double stall_force_n) override;
  /// The world steps itself: nothing to do (Apply moves the set-point).
  void Advance(double dt_s) override {}
  double opening_m() const override;
  double grip_force_n() const override;
  double velocity_m_s() const override;
  double current_a() const override;

  /// The pad speed the motor is driven at (m/s; < 0 closing).
  double commanded_velocity() const { return velocity_m_s_; }
  /// Moves the set-point by dt of the commanded speed; call before each physics step.
  void Apply(double dt_s);

 private:
  World* world_;
  int qpos_, dof_, actuator_, thumb_body_;
  double lo_, hi_;  ///< set-point range (thumb slide, m)
  double velocity_m_s_ = 0.0;        ///< commanded pad speed
  double motor_velocity_m_s_ = 0.0;  ///< the set-point's pad rate over the last step
  double max_speed_m_s_ = 0.30;
};

/// The laser board's hardware on the world: the motor controller's profile (a TrapezoidAxis
/// in counts) is the laser joint's set-point, the encoder reads the joint's actual angle, the
/// laser diode and the LEDs are the world's; VSYNC pulses come from the twin's camera clock
/// (Latch), not from a clock of the board's own.
class TwinBoardHardware final : public drivers::LaserBoardHardware {
 public:
  TwinBoardHardware(World* world, const drivers::AxisLimits& motor);

  void Advance(double t_s, std::vector<drivers::VsyncLatch>* latches) override;
  std::int32_t EncoderCount() const override;
  bool Moving() const override { return motor_.moving(); }
  bool LaserOn() const override { return world_->laser_on(); }
  void SetLaser(bool on) override { world_->set_laser_on(on); }
  void MoveAt(double counts_s) override;
  void MoveTo(std::int32_t count, double speed_counts_s) override;
  std::uint32_t LedMask(int side) const override { return leds_[side == 0 ? 0 : 1]; }
  void SetLeds(int side, std::uint32_t mask) override;

  /// A camera exposure at the world's time now: the encoder and laser latched, handed to the
  /// board at its next Advance. Returns the count latched.
  std::int32_t Latch();
  /// Advances the motor's profile by dt and sets the joint's set-point; before each step.
  void Apply(double dt_s);

 private:
  World* world_;
  drivers::TrapezoidAxis motor_;
  int actuator_;
  std::deque<drivers::VsyncLatch> pending_;
  std::uint32_t leds_[2] = {0, 0};
};

/// The Biclops head's mechanism: the PMD chips' trajectory generators are the head joints'
/// set-points (mechanism counts from the true home, 0.03 deg per count).
class TwinHeadMirror {
 public:
  TwinHeadMirror(World* world, const drivers::BiclopsEmulator* chip, double rad_per_count);
  /// Sets the head's set-points from the chip; before each step.
  void Apply();
  /// The head's joints (pan, tilt, verge) in `world` now, in mechanism counts: where the chip's
  /// mechanism starts.
  static std::array<double, 3> Counts(const World& world, double rad_per_count);

 private:
  World* world_;
  const drivers::BiclopsEmulator* chip_;
  double rad_per_count_;
  std::array<int, 3> actuator_;
};

}  // namespace hgrasp::sim
