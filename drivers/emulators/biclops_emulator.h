#pragma once
/// @file The Biclops head's PMD motion chip, emulated byte for byte (drivers/biclops/PROTOCOL.md):
/// PmdChipModel is the chip (per-axis registers, trapezoidal profiles, event and signal status,
/// capture of index and home signals, breakpoints, the configuration registers TRACLabs' libPMD
/// sets) over a mechanism of TrapezoidAxis motors with relative encoders, one index pulse per
/// encoder cycle, a home sensor and limit switches at the hard stops; BiclopsEmulator puts the
/// serial protocol in front of it (packet framing for every opcode of the Navigator command set,
/// checksum check, replies) and logs every state-changing command it executed.

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <vector>

#include "biclops/pmd_codec.h"
#include "emulators/emulator.h"
#include "emulators/motion.h"

namespace hgrasp::drivers {

/// The emulated head. Positions are encoder counts, speeds counts/s (the chip's units). The
/// mechanism's positions are counted from its true home (the joint angle 0 of device/head.h);
/// the chip's position registers count from wherever the head powered up (relative encoders).
struct BiclopsEmulatorConfig {
  /// Per chip axis (0 pan, 1 tilt, 2 verge): the mechanism's hard range (counts from home) and
  /// motor limits (counts/s, counts/s^2). The limit switches close at the hard stops.
  std::array<AxisLimits, 3> limits;
  /// Mechanism position at power-up, counts from home; the encoder reads 0 there.
  std::array<double, 3> start_counts{};
  /// Encoder counts per encoder cycle: one index pulse per cycle, at home + k * this
  /// (BiclopsDefault.cfg: 2000 counts per encoder cycle, 6 cycles per joint turn).
  std::array<double, 3> index_spacing_counts{2000.0, 2000.0, 2000.0};
  /// False: the axis' index pulse never comes (a broken encoder channel; for tests).
  std::array<bool, 3> has_index{true, true, true};
  /// The home sensor: centre (counts from home) and width (counts). Widths: pan 50, tilt 860
  /// (BiclopsDefault.cfg homeSensorWidth); verge 300 and the centres (200, -300, 150: within a
  /// third of an encoder cycle of the home index, as libPMD's FindHomeBestWay expects) are ours.
  std::array<double, 3> home_center_counts{200.0, -300.0, 150.0};
  std::array<double, 3> home_width_counts{50.0, 860.0, 300.0};
  /// The home sensor's output is low while on the sensor (BiclopsDefault.cfg homeSignalPolarity:
  /// pan ActiveLow, tilt ActiveHigh; verge ours).
  std::array<bool, 3> home_active_low{true, false, true};
  /// The chip's cycle (sample) time, GetSampleTime, microseconds.
  std::uint16_t sample_time_us = 153;
  /// GetVersion words: chip (family << 12 | motor type << 8 | axes << 4 | special) and
  /// software (custom << 8 | major << 4 | minor).
  std::uint16_t version_chip = 0x2130;
  std::uint16_t version_software = 0x0015;
};

/// Biclops pan +-180 deg, tilt +-60 deg (published), verge -5..25 deg (ours, as models/), at
/// 12000 counts per turn (0.03 deg/count: 2000 counts per encoder cycle, 6:1 belt, TRACLabs
/// BiclopsDefault.cfg); motors 150, 150, 100 deg/s and 600, 600, 400 deg/s^2. Powered up at
/// home (start_counts 0): the unit tests' head.
BiclopsEmulatorConfig DefaultBiclopsEmulatorConfig();
/// As DefaultBiclopsEmulatorConfig, powered up where a real head is left: each axis somewhere
/// off home, drawn from `seed` (pan within +-60 deg, tilt +-30 deg, verge -3..15 deg), so that
/// it reads 0 counts away from its true home until homed.
BiclopsEmulatorConfig PoweredUpBiclopsEmulatorConfig(std::uint64_t seed);

/// A state-changing command the chip executed.
struct PmdExecuted {
  double t_s = 0.0;  ///< emulator time
  int axis = 0;
  std::uint8_t opcode = 0;  ///< pmd::op::kSetPosition, kUpdate, ...
  std::int64_t value = 0;   ///< pmd::CommandValue (0 for Update and Reset)

  bool operator==(const PmdExecuted& o) const {
    return axis == o.axis && opcode == o.opcode && value == o.value;  // time aside
  }
};

/// The motion chip: registers, trajectory generation and status, without bytes.
class PmdChipModel {
 public:
  /// The profile registers of one axis.
  struct Registers {
    std::int32_t position = 0;       ///< counts
    std::int32_t velocity = 0;       ///< counts/cycle * 2^16
    std::uint32_t acceleration = 0;  ///< counts/cycle^2 * 2^16
    std::uint32_t deceleration = 0;  ///< counts/cycle^2 * 2^16 (stored; profiles use acceleration)
    std::uint16_t profile_mode = pmd::kTrapezoidalProfile;
    std::uint16_t stop_mode = pmd::kNoStop;  ///< executed (and cleared) by the next Update
  };

  /// What Execute did.
  struct Outcome {
    std::optional<pmd::Reply> reply;  ///< none for Reset
    bool executed = false;            ///< a state-changing command took effect
  };

  explicit PmdChipModel(const BiclopsEmulatorConfig& config);

  /// Advances the mechanism to `t_s` (emulator time; not earlier than the last call), in steps
  /// of at most 1 ms: profile ends, limit switches, captures and breakpoints happen on the way.
  void Advance(double t_s);
  /// Executes one packet whose checksum is good, at the current time.
  Outcome Execute(const pmd::Command& command);

  static constexpr int kAxes = 3;
  /// Mechanism position (counts from the true home) and motion.
  double position_counts(int axis) const { return motor_[Index(axis)].position(); }
  double velocity_counts_s(int axis) const { return motor_[Index(axis)].velocity(); }
  bool moving(int axis) const { return motor_[Index(axis)].moving(); }
  /// What the chip's actual-position register reads now (counts from the encoder's zero).
  std::int32_t encoder_counts(int axis) const {
    return ToRegister(motor_[Index(axis)].position(), axis);
  }
  const Registers& buffered(int axis) const { return buffered_[Index(axis)]; }
  const Registers& active(int axis) const { return active_[Index(axis)]; }
  std::uint16_t ActivityStatus(int axis) const;
  std::uint16_t EventStatus(int axis) const { return axis_[Index(axis)].event_status; }
  std::uint16_t SignalStatus(int axis) const;
  int resets() const { return resets_; }
  double cycle_s() const { return config_.sample_time_us * 1e-6; }
  const BiclopsEmulatorConfig& config() const { return config_; }

 private:
  /// Per-axis chip state besides the profile registers.
  struct AxisState {
    std::uint16_t event_status = 0;
    std::uint16_t signal_sense = 0;
    std::uint16_t capture_source = pmd::kCaptureIndex;
    bool capture_armed = true;
    std::int32_t capture_value = 0;
    std::uint16_t motor_mode = pmd::kMotorOn;
    std::uint16_t limit_switch_mode = 1;  ///< enabled
    std::uint16_t auto_stop_mode = 0;     ///< disabled
    std::uint32_t position_error_limit = 0x7FFF;
    std::int64_t requested_target = 0;  ///< mechanism counts the last Update aimed at
    bool was_moving = false;
    bool at_positive = false, at_negative = false;
  };
  /// One of the chip's two breakpoints.
  struct Breakpoint {
    int axis = 0;
    std::uint16_t action = pmd::kBreakpointNoAction;
    std::uint16_t trigger = pmd::kBreakpointDisable;
    std::uint32_t value = 0;
  };

  static std::size_t Index(int axis) { return static_cast<std::size_t>(axis); }
  /// Position registers count from the encoder's zero: register = mechanism - offset.
  std::int32_t ToRegister(double mechanism_counts, int axis) const;
  void StartProfile(int axis);
  /// Index pulse and home-sensor edges crossed between two mechanism positions.
  void CheckCapture(int axis, double from, double to);
  void CheckBreakpoints();
  bool OnHome(int axis, double mechanism_counts) const;
  std::uint16_t* GenericRegister(int axis, std::uint8_t set_opcode, int words);

  BiclopsEmulatorConfig config_;
  std::vector<TrapezoidAxis> motor_;
  std::array<Registers, kAxes> buffered_{}, active_{};
  std::array<AxisState, kAxes> axis_{};
  std::array<Breakpoint, 2> breakpoint_{};
  std::array<std::int64_t, kAxes> offset_{};
  /// Registers the model only stores (filter gains, limits, modes): by axis and Set opcode.
  std::map<std::pair<int, std::uint8_t>, std::array<std::uint16_t, 3>> generic_;
  std::map<std::uint16_t, std::uint16_t> io_;  ///< WriteIO / ReadIO space
  std::uint16_t host_io_error_ = pmd::status::kOk;
  double t_s_ = 0.0;
  int resets_ = 0;
};

class BiclopsEmulator final : public DeviceEmulator {
 public:
  /// How the received packets fared.
  struct Counts {
    std::uint64_t packets = 0;
    std::uint64_t checksum_errors = 0;  ///< answered status 0x09
    /// Opcodes not in the table, Magellan-only opcodes, a bad address byte: 0x02.
    std::uint64_t invalid_instructions = 0;
    std::uint64_t other_errors = 0;  ///< invalid axis, parameter, negative value
  };

  explicit BiclopsEmulator(const BiclopsEmulatorConfig& config = DefaultBiclopsEmulatorConfig());

  void Receive(std::span<const std::uint8_t> in, double t_s,
               std::vector<std::uint8_t>* out) override;
  void Advance(double t_s, std::vector<std::uint8_t>* out) override;

  const PmdChipModel& chip() const { return chip_; }
  /// Every state-changing command executed, in order.
  const std::vector<PmdExecuted>& executed() const { return executed_; }
  const Counts& counts() const { return counts_; }

 private:
  PmdChipModel chip_;
  pmd::CommandDecoder decoder_;
  std::vector<PmdExecuted> executed_;
  Counts counts_;
  double t_s_ = 0.0;
};

/// A Biclops at power-up with PoweredUpBiclopsEmulatorConfig(seed) (`hgrasp emulate biclops`):
/// it must be homed before its angles mean anything.
std::unique_ptr<DeviceEmulator> MakeBiclopsEmulator(std::uint64_t seed = 1);

}  // namespace hgrasp::drivers
