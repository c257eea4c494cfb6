#pragma once
/// @file The Biclops head's PMD motion chip, emulated byte for byte (drivers/biclops/PROTOCOL.md):
/// PmdChipModel is the chip (per-axis registers, trapezoidal profiles, status words) over a
/// mechanism of TrapezoidAxis motors; BiclopsEmulator puts the serial protocol in front of it
/// (packet framing, checksum check, replies) and logs every state-changing command it executed.

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "biclops/pmd_codec.h"
#include "emulators/emulator.h"
#include "emulators/motion.h"

namespace hgrasp::drivers {

/// The emulated head. Positions are encoder counts, speeds counts/s (the chip's units).
struct BiclopsEmulatorConfig {
  /// Per chip axis (0 pan, 1 tilt, 2 verge): the mechanism's hard range (counts) and motor
  /// limits (counts/s, counts/s^2).
  std::array<AxisLimits, 3> limits;
  std::array<double, 3> start_counts{};  ///< mechanism position at power-up
  /// The chip's cycle (sample) time, GetSampleTime, microseconds.
  std::uint16_t sample_time_us = 153;
  /// GetVersion words: chip (family << 12 | motor type << 8 | axes << 4 | special) and
  /// software (custom << 8 | major << 4 | minor).
  std::uint16_t version_chip = 0x2130;
  std::uint16_t version_software = 0x0015;
};

/// Biclops pan +-180 deg, tilt +-60 deg (published), verge -5..25 deg (ours, as models/), at
/// 12000 counts per turn (0.03 deg/count: 2000 counts per encoder cycle, 6:1 belt, TRACLabs
/// BiclopsDefault.cfg); motors 150, 150, 100 deg/s and 600, 600, 400 deg/s^2.
BiclopsEmulatorConfig DefaultBiclopsEmulatorConfig();

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
    std::uint16_t profile_mode = pmd::kTrapezoidalProfile;
  };

  /// What Execute did.
  struct Outcome {
    std::optional<pmd::Reply> reply;  ///< none for Reset
    bool executed = false;            ///< a state-changing command took effect
  };

  explicit PmdChipModel(const BiclopsEmulatorConfig& config);

  /// Advances the mechanism to `t_s` (emulator time; not earlier than the last call).
  void Advance(double t_s);
  /// Executes one packet whose checksum is good, at the current time.
  Outcome Execute(const pmd::Command& command);

  static constexpr int kAxes = 3;
  /// Mechanism position (counts, power-up reference) and motion.
  double position_counts(int axis) const { return motor_[Index(axis)].position(); }
  double velocity_counts_s(int axis) const { return motor_[Index(axis)].velocity(); }
  bool moving(int axis) const { return motor_[Index(axis)].moving(); }
  const Registers& buffered(int axis) const { return buffered_[Index(axis)]; }
  const Registers& active(int axis) const { return active_[Index(axis)]; }
  std::uint16_t ActivityStatus(int axis) const;
  int resets() const { return resets_; }
  double cycle_s() const { return config_.sample_time_us * 1e-6; }

 private:
  static std::size_t Index(int axis) { return static_cast<std::size_t>(axis); }
  /// Position registers count from the last Reset: register = mechanism - offset.
  std::int32_t ToRegister(double mechanism_counts, int axis) const;

  BiclopsEmulatorConfig config_;
  std::vector<TrapezoidAxis> motor_;
  std::array<Registers, kAxes> buffered_{}, active_{};
  std::array<std::int64_t, kAxes> offset_{};
  double t_s_ = 0.0;
  int resets_ = 0;
};

class BiclopsEmulator final : public DeviceEmulator {
 public:
  /// How the received packets fared.
  struct Counts {
    std::uint64_t packets = 0;
    std::uint64_t checksum_errors = 0;       ///< answered status 0x09
    std::uint64_t invalid_instructions = 0;  ///< unknown opcode or address byte: 0x02
    std::uint64_t other_errors = 0;          ///< invalid axis, parameter, negative value
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

/// A Biclops at power-up with DefaultBiclopsEmulatorConfig (`hgrasp emulate biclops`).
std::unique_ptr<DeviceEmulator> MakeBiclopsEmulator();

}  // namespace hgrasp::drivers
