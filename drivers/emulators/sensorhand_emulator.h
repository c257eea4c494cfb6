#pragma once
/// @file An Otto Bock SensorHand Speed on a pty (drivers/sensorhand/PROTOCOL.md): the serial
/// protocol byte for byte as a stock hand speaks it (0x75 speeds, 0x73/0x7A stream start/stop,
/// their echoes, one stream frame of the published 9 data bytes every 12 ms while the stream is
/// on, and nothing more) over a model of the hand's mechanics. The model's opening stays inside
/// (tests read it as ground truth); it is never put on the wire.
///
/// The mechanics sit behind SensorHandModel so that the simulation can stand in for them later;
/// KinematicSensorHand is the stand-alone one: a speed-driven finger pair (TrapezoidAxis:
/// acceleration, range 0..max_opening_m), an optional object of given width and stiffness
/// between the pads, and a motor whose speed falls linearly with the grip force to zero at its
/// stall force (a DC motor's torque-speed line), so a grip settles at the stall force of the
/// speed byte it was closed with.

#include <cstdint>
#include <memory>
#include <vector>

#include "emulators/emulator.h"
#include "emulators/motion.h"
#include "sensorhand/sensorhand_codec.h"

namespace hgrasp::drivers {

/// The hand's mechanics as the emulator drives them.
class SensorHandModel {
 public:
  virtual ~SensorHandModel() = default;
  /// The motor's command: finger velocity (m/s of pad distance; + opens, - closes, 0 stops and
  /// holds: the gear does not back-drive) and the grip force at which the motor stalls (N).
  virtual void Drive(double velocity_m_s, double stall_force_n) = 0;
  /// Advances the mechanics by dt_s >= 0 seconds.
  virtual void Advance(double dt_s) = 0;
  virtual double opening_m() const = 0;     ///< pad distance (m)
  virtual double grip_force_n() const = 0;  ///< force the pads press with (N)
  virtual double velocity_m_s() const = 0;  ///< rate of the pad distance (m/s)
  virtual double current_a() const = 0;     ///< motor supply current (A)
};

/// KinematicSensorHand's parameters. Defaults: the robot's hand.
struct SensorHandMechanics {
  /// models/humanoid.xml: thumb slide range 0..0.05 m, opening = 2 q.
  double max_opening_m = 0.10;
  /// Otto Bock: the SensorHand Speed opens and closes at up to 300 mm/s.
  double max_speed_m_s = 0.30;
  /// Ours: full speed within 30 ms.
  double accel_m_s2 = 10.0;
  /// Where the fingers start: models/humanoid.xml's start pose, opening 0.08 m.
  double opening_m = 0.08;
  /// Width of the object between the pads (m); 0: none (the fingers close to 0).
  double object_width_m = 0.0;
  /// Its stiffness (N/m): 5000 N/m, a cardboard box behind rubber pads, 8 mm in at 40 N.
  double object_stiffness_n_m = 5000.0;
};

/// The stand-alone mechanics (see the file comment).
class KinematicSensorHand final : public SensorHandModel {
 public:
  explicit KinematicSensorHand(const SensorHandMechanics& m = {});
  void Drive(double velocity_m_s, double stall_force_n) override;
  void Advance(double dt_s) override;
  double opening_m() const override { return axis_.position(); }
  double grip_force_n() const override;
  double velocity_m_s() const override { return axis_.velocity(); }
  double current_a() const override;

  /// Puts an object of this width between the pads (0 takes it away).
  void set_object_width(double width_m) { m_.object_width_m = width_m; }
  const SensorHandMechanics& mechanics() const { return m_; }

 private:
  SensorHandMechanics m_;
  TrapezoidAxis axis_;
  double velocity_cmd_ = 0.0;
  double stall_force_n_ = 0.0;
};

/// How the emulated hand turns speed bytes into motion (sensorhand::SpeedFraction of these).
struct SensorHandScale {
  double full_speed_m_s = 0.30;  ///< at speed byte 0x85
  double full_force_n = 100.0;   ///< stall force at close speed 0x85 (DESIGN.md: 10-100 N)
  double battery_v = 7.4;        ///< reported supply voltage (a 2-cell Otto Bock battery)
};

/// One command the hand executed.
struct SensorHandLogEntry {
  double t_s = 0.0;             ///< host time of execution (s)
  sensorhand::Command command;  ///< what it was
};

class SensorHandEmulator final : public DeviceEmulator {
 public:
  explicit SensorHandEmulator(std::unique_ptr<SensorHandModel> model, SensorHandScale scale = {});

  void Receive(std::span<const std::uint8_t> in, double t_s,
               std::vector<std::uint8_t>* out) override;
  void Advance(double t_s, std::vector<std::uint8_t>* out) override;

  /// Every command executed, in order.
  const std::vector<SensorHandLogEntry>& log() const { return log_; }
  /// The 0x75 commands executed, in order.
  std::vector<sensorhand::SpeedSetting> speed_log() const;

  SensorHandModel& model() { return *model_; }
  bool streaming() const { return streaming_; }
  /// The speed setting in force (not on the wire: the echo shows each command once).
  sensorhand::SpeedSetting speed() const { return speed_; }
  /// 0x75 commands executed since power-up, mod 256 (ground truth for tests; not on the wire).
  std::uint8_t counter() const { return counter_; }
  std::uint64_t samples_sent() const { return samples_sent_; }
  /// Bytes the hand threw away (damaged or partial frames).
  std::uint64_t discarded_bytes() const { return decoder_.discarded(); }

  /// A power cycle: the stream stops, the speeds and counters go to 0; the fingers stay put.
  void PowerCycle();

  /// A partial frame older than this is forgotten (s) (ours: the source gives no timeout).
  static constexpr double kFrameGapS = 0.05;
  /// A speed set and the fingers still for this long: the state byte says blocked (s) (ours: a
  /// stall detector needs a time window; at once, every start from rest would look blocked).
  static constexpr double kBlockedAfterS = 0.02;

 private:
  void Execute(const sensorhand::Command& c, double t_s, std::vector<std::uint8_t>* out);
  void StepModel(double t_s);
  sensorhand::DumpSample Sample() const;

  std::unique_ptr<SensorHandModel> model_;
  SensorHandScale scale_;
  sensorhand::CommandDecoder decoder_;
  std::vector<SensorHandLogEntry> log_;
  bool started_ = false;
  double model_t_ = 0.0;
  double last_rx_t_ = 0.0;
  bool streaming_ = false;
  double next_sample_t_ = 0.0;
  sensorhand::SpeedSetting speed_;
  std::uint8_t counter_ = 0;
  std::uint64_t samples_sent_ = 0;
  double still_since_t_ = 0.0;  ///< since when the fingers have been still (if still_)
  bool still_ = true;
};

/// A hand with defaults: KinematicSensorHand with a 5 cm object between the pads (so Close has
/// something to press), fingers at 0.08 m, stream off until a host starts it.
std::unique_ptr<DeviceEmulator> MakeSensorHandEmulator();

}  // namespace hgrasp::drivers
