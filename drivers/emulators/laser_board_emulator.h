#pragma once
/// @file An emulator of the laser board (drivers/laser_board/PROTOCOL.md), byte for byte: the
/// board's firmware (strict frame checking, NAKs with error codes, the sequence-number memory
/// that answers a retransmission without executing it again, the ring of frame latches) over
/// a model of the hardware it drives (LaserBoardHardware): the laser motor as a trapezoidal
/// axis in encoder counts, the laser diode, the gripper LEDs and the cameras' 25 Hz VSYNC.
/// The hardware model is an interface so that the simulation can back it later.

#include <cstdint>
#include <deque>
#include <memory>
#include <vector>

#include "emulators/emulator.h"
#include "emulators/motion.h"
#include "laser_board/laser_board_codec.h"

namespace hgrasp::drivers {

/// The encoder count latched in hardware at one camera VSYNC pulse.
struct VsyncLatch {
  double t_s = 0.0;                ///< time of the pulse (s, emulator clock)
  std::int32_t encoder_count = 0;  ///< counts
  bool laser_on = false;
};

/// What the board's firmware drives and reads. Sides: 0 left gripper, 1 right.
class LaserBoardHardware {
 public:
  virtual ~LaserBoardHardware() = default;
  /// Advances to `t_s` (s, non-decreasing); appends a latch for every VSYNC pulse on the way.
  virtual void Advance(double t_s, std::vector<VsyncLatch>* latches) = 0;
  /// Motor angle, whole encoder counts (0: straight ahead).
  virtual std::int32_t EncoderCount() const = 0;
  virtual bool Moving() const = 0;
  virtual bool LaserOn() const = 0;
  virtual void SetLaser(bool on) = 0;
  /// Runs the motor at `counts_s` (signed) until a limit; 0 stops.
  virtual void MoveAt(double counts_s) = 0;
  /// Moves the motor to `count` cruising at `speed_counts_s` (> 0).
  virtual void MoveTo(std::int32_t count, double speed_counts_s) = 0;
  virtual std::uint32_t LedMask(int side) const = 0;
  virtual void SetLeds(int side, std::uint32_t mask) = 0;
};

/// The board and the robot around it. Defaults: models/humanoid.xml and sim/world.{h,cc}.
struct LaserBoardEmulatorConfig {
  /// Motor travel, top speed and acceleration in encoder counts (0.01 deg/count,
  /// sim::kLaserRadPerCount): joint range +-45 deg = +-4500 counts; 90 deg/s = 9000 counts/s
  /// (the laser joint's velocity limit in models/humanoid.urdf); full speed in 0.04 s (sim/world.cc
  /// kRampS, the motor's ramp) = 225000 counts/s^2.
  AxisLimits motor{-4500.0, 4500.0, 9000.0, 225000.0};
  std::int32_t start_count = 0;
  /// LEDs per gripper: 6 (models/humanoid.xml: left_led0..5, right_led0..5).
  int leds_per_gripper = 8;
  /// Camera frame period (PAL, 25 frames/s) and the time of the first VSYNC pulse (s).
  double frame_period_s = 0.04;
  double first_frame_s = 0.04;
  /// Silence after which a half-received frame is given up (s): about 115 byte times.
  double interbyte_timeout_s = 0.01;
  std::uint8_t firmware_major = 1, firmware_minor = 0;
};

/// The hardware as kinematics: motor on a TrapezoidAxis, VSYNC from a fixed-period clock.
class KinematicLaserBoardHardware final : public LaserBoardHardware {
 public:
  explicit KinematicLaserBoardHardware(const LaserBoardEmulatorConfig& config);

  void Advance(double t_s, std::vector<VsyncLatch>* latches) override;
  std::int32_t EncoderCount() const override;
  bool Moving() const override { return motor_.moving(); }
  bool LaserOn() const override { return laser_on_; }
  void SetLaser(bool on) override { laser_on_ = on; }
  void MoveAt(double counts_s) override;
  void MoveTo(std::int32_t count, double speed_counts_s) override;
  std::uint32_t LedMask(int side) const override { return leds_[side == 0 ? 0 : 1]; }
  void SetLeds(int side, std::uint32_t mask) override { leds_[side == 0 ? 0 : 1] = mask; }

  const TrapezoidAxis& motor() const { return motor_; }

 private:
  TrapezoidAxis motor_;
  double t_s_ = 0.0;
  double frame_period_s_;
  double next_frame_s_;
  bool laser_on_ = false;
  std::uint32_t leds_[2] = {0, 0};
};

/// A state-changing command the board executed.
struct LaserBoardLogEntry {
  double t_s = 0.0;
  std::uint8_t seq = 0;
  laser_board::Command command;
};

struct LaserBoardEmulatorCounts {
  std::uint64_t frames = 0;      ///< frames that passed the CRC
  std::uint64_t crc_errors = 0;  ///< candidates that failed it (each NAKed)
  std::uint64_t naks = 0;        ///< NAKs sent (bad CRC included)
  std::uint64_t replayed = 0;    ///< retransmissions answered from memory, not executed
  std::uint64_t executed = 0;    ///< commands executed (reads included)
};

class LaserBoardEmulator final : public DeviceEmulator {
 public:
  /// Number of frame latches the board keeps.
  static constexpr std::size_t kLatchRing = 16;

  /// `hardware`: the model to drive; null: a KinematicLaserBoardHardware from `config`.
  explicit LaserBoardEmulator(const LaserBoardEmulatorConfig& config = {},
                              std::unique_ptr<LaserBoardHardware> hardware = nullptr);

  void Receive(std::span<const std::uint8_t> in, double t_s,
               std::vector<std::uint8_t>* out) override;
  void Advance(double t_s, std::vector<std::uint8_t>* out) override;

  const LaserBoardEmulatorConfig& config() const { return config_; }
  LaserBoardHardware& hardware() { return *hardware_; }
  /// State-changing commands executed, in order.
  const std::vector<LaserBoardLogEntry>& log() const { return log_; }
  /// The same, commands only (to compare with what a test commanded).
  std::vector<laser_board::Command> ExecutedCommands() const;
  const std::deque<FrameLatch>& latches() const { return latches_; }
  std::uint32_t frame() const { return frame_; }
  std::uint8_t last_seq() const { return last_seq_; }
  const LaserBoardEmulatorCounts& counts() const { return counts_; }

 private:
  void Handle(const laser_board::DecodeEvent& event, double t_s, std::vector<std::uint8_t>* out);
  laser_board::Frame Execute(std::uint8_t seq, const laser_board::Command& command, double t_s);

  LaserBoardEmulatorConfig config_;
  std::unique_ptr<LaserBoardHardware> hardware_;
  laser_board::FrameDecoder decoder_;
  std::vector<laser_board::DecodeEvent> events_;
  std::vector<VsyncLatch> vsync_;
  double t_s_ = 0.0, last_rx_s_ = 0.0;
  std::uint32_t frame_ = 0;  ///< VSYNC pulses counted (the last frame's number)
  std::deque<FrameLatch> latches_;
  /// The sequence-number memory: last sequenced frame executed and the reply it got.
  std::uint8_t last_seq_ = laser_board::kUnsequenced;
  laser_board::Frame last_request_;
  std::vector<std::uint8_t> last_reply_;
  std::vector<LaserBoardLogEntry> log_;
  LaserBoardEmulatorCounts counts_;
};

/// The board with default configuration (for `hgrasp emulate laser_board`).
std::unique_ptr<DeviceEmulator> MakeLaserBoardEmulator();

}  // namespace hgrasp::drivers
