#include "emulators/biclops_emulator.h"

#include <algorithm>
#include <cmath>

namespace hgrasp::drivers {

namespace {

constexpr double kCountsPerDeg = 12000.0 / 360.0;

AxisLimits Limits(double min_deg, double max_deg, double speed_deg_s, double accel_deg_s2) {
  // The range rounds outwards to whole counts so that a target at a joint limit, rounded to
  // counts by the driver, is inside it.
  return AxisLimits{std::floor(min_deg * kCountsPerDeg + 1e-6),
                    std::ceil(max_deg * kCountsPerDeg - 1e-6), speed_deg_s * kCountsPerDeg,
                    accel_deg_s2 * kCountsPerDeg};
}

pmd::Reply Status(std::uint8_t status) {
  pmd::Reply r;
  r.status = status;
  return r;
}

pmd::Reply Word(std::uint16_t w) {
  pmd::Reply r;
  r.words[0] = w;
  r.word_count = 1;
  return r;
}

pmd::Reply Long(std::uint32_t v) {
  pmd::Reply r;
  r.words = pmd::SplitLong(v);
  r.word_count = 2;
  return r;
}

}  // namespace

BiclopsEmulatorConfig DefaultBiclopsEmulatorConfig() {
  BiclopsEmulatorConfig c;
  c.limits[0] = Limits(-180.0, 180.0, 150.0, 600.0);
  c.limits[1] = Limits(-60.0, 60.0, 150.0, 600.0);
  c.limits[2] = Limits(-5.0, 25.0, 100.0, 400.0);
  return c;
}

PmdChipModel::PmdChipModel(const BiclopsEmulatorConfig& config) : config_(config) {
  for (int a = 0; a < kAxes; ++a) {
    motor_.emplace_back(config.limits[Index(a)], config.start_counts[Index(a)]);
    // Power-up: the registers read where the mechanism is (the Biclops is homed at 0).
    const std::int32_t here = ToRegister(motor_.back().position(), a);
    buffered_[Index(a)].position = here;
    active_[Index(a)].position = here;
  }
}

std::int32_t PmdChipModel::ToRegister(double mechanism_counts, int axis) const {
  return static_cast<std::int32_t>(std::llround(mechanism_counts) - offset_[Index(axis)]);
}

void PmdChipModel::Advance(double t_s) {
  const double dt = t_s - t_s_;
  if (dt <= 0.0) return;
  t_s_ = t_s;
  for (TrapezoidAxis& m : motor_) m.Advance(dt);
}

std::uint16_t PmdChipModel::ActivityStatus(int axis) const {
  const TrapezoidAxis& m = motor_[Index(axis)];
  const Registers& act = active_[Index(axis)];
  std::uint16_t s = pmd::activity::kMotorOn;
  s |= static_cast<std::uint16_t>((act.profile_mode & 0x7u) << 3);
  if (m.moving()) {
    s |= pmd::activity::kInMotion;
    const double speed = act.velocity / pmd::kVelocityScale / cycle_s();
    if (std::abs(m.velocity()) >= std::min(speed, m.limits().max_speed) * (1.0 - 1e-9)) {
      s |= pmd::activity::kAtMaximumVelocity;
    }
  } else {
    s |= pmd::activity::kAxisSettled;
  }
  // The hard stops at the ends of travel read as the limit inputs (our model's choice).
  if (m.position() >= m.limits().max) s |= pmd::activity::kInPositiveLimit;
  if (m.position() <= m.limits().min) s |= pmd::activity::kInNegativeLimit;
  return s;
}

PmdChipModel::Outcome PmdChipModel::Execute(const pmd::Command& c) {
  Outcome out;
  const pmd::OpcodeInfo* info = pmd::FindOpcode(c.opcode);
  if (info == nullptr) {
    out.reply = Status(pmd::status::kInvalidInstruction);
    return out;
  }
  const bool chip_wide = c.opcode == pmd::op::kNoOperation || c.opcode == pmd::op::kReset ||
                         c.opcode == pmd::op::kGetVersion || c.opcode == pmd::op::kGetSampleTime;
  if (c.axis >= kAxes || (c.opcode == pmd::op::kReset && c.axis != 0)) {
    out.reply = Status(pmd::status::kInvalidAxis);
    return out;
  }
  const std::size_t a = Index(chip_wide ? 0 : c.axis);
  Registers& buf = buffered_[a];
  const double cycle = cycle_s();
  out.reply = Status(pmd::status::kOk);
  switch (c.opcode) {
    case pmd::op::kNoOperation:
      break;
    case pmd::op::kSetPosition:
      buf.position = static_cast<std::int32_t>(pmd::CommandValue(c));
      out.executed = true;
      break;
    case pmd::op::kSetVelocity: {
      const auto v = static_cast<std::int32_t>(pmd::CommandValue(c));
      if (v < 0 && buf.profile_mode == pmd::kTrapezoidalProfile) {
        out.reply = Status(pmd::status::kInvalidNegativeValue);
        break;
      }
      buf.velocity = v;
      out.executed = true;
      break;
    }
    case pmd::op::kSetAcceleration:
      buf.acceleration = static_cast<std::uint32_t>(pmd::CommandValue(c));
      out.executed = true;
      break;
    case pmd::op::kSetProfileMode:
      // This model generates trapezoidal profiles only.
      if (c.words[0] != pmd::kTrapezoidalProfile) {
        out.reply = Status(pmd::status::kInvalidParameter);
        break;
      }
      buf.profile_mode = c.words[0];
      out.executed = true;
      break;
    case pmd::op::kUpdate: {
      // The buffered profile becomes the active one; the trajectory starts from where the axis
      // is, at its present velocity.
      active_[a] = buf;
      const double speed = buf.velocity / pmd::kVelocityScale / cycle;
      const double accel = buf.acceleration / pmd::kAccelerationScale / (cycle * cycle);
      motor_[a].MoveTo(static_cast<double>(buf.position + offset_[a]), speed, accel);
      out.executed = true;
      break;
    }
    case pmd::op::kReset:
      // Every register to its power-up value; the position counters restart at 0 where the
      // mechanism is; the motors stop. No reply.
      for (int i = 0; i < kAxes; ++i) {
        motor_[Index(i)].Stop();
        offset_[Index(i)] = std::llround(motor_[Index(i)].position());
        buffered_[Index(i)] = Registers{};
        active_[Index(i)] = Registers{};
      }
      ++resets_;
      out.reply.reset();
      out.executed = true;
      break;
    case pmd::op::kGetPosition:
      out.reply = Long(static_cast<std::uint32_t>(buf.position));
      break;
    case pmd::op::kGetVelocity:
      out.reply = Long(static_cast<std::uint32_t>(buf.velocity));
      break;
    case pmd::op::kGetAcceleration:
      out.reply = Long(buf.acceleration);
      break;
    case pmd::op::kGetProfileMode:
      out.reply = Word(buf.profile_mode);
      break;
    case pmd::op::kGetActualPosition:
    case pmd::op::kGetCommandedPosition:
      // A stiff servo: the encoder reads the profile position.
      out.reply = Long(static_cast<std::uint32_t>(ToRegister(motor_[a].position(), c.axis)));
      break;
    case pmd::op::kGetActivityStatus:
      out.reply = Word(ActivityStatus(c.axis));
      break;
    case pmd::op::kGetVersion: {
      pmd::Reply r;
      r.words = {config_.version_chip, config_.version_software};
      r.word_count = 2;
      out.reply = r;
      break;
    }
    case pmd::op::kGetSampleTime:
      out.reply = Word(config_.sample_time_us);
      break;
    default:
      out.reply = Status(pmd::status::kInvalidInstruction);
      break;
  }
  return out;
}

BiclopsEmulator::BiclopsEmulator(const BiclopsEmulatorConfig& config) : chip_(config) {}

void BiclopsEmulator::Advance(double t_s, std::vector<std::uint8_t>* /*out*/) {
  t_s_ = std::max(t_s_, t_s);
  chip_.Advance(t_s_);
}

void BiclopsEmulator::Receive(std::span<const std::uint8_t> in, double t_s,
                              std::vector<std::uint8_t>* out) {
  Advance(t_s, out);
  pmd::CommandDecoder::Packet p;
  for (std::uint8_t byte : in) {
    if (!decoder_.Push(byte, &p)) continue;
    ++counts_.packets;
    pmd::Reply reply;
    if (!p.checksum_ok) {
      ++counts_.checksum_errors;
      reply.status = pmd::status::kBadSerialChecksum;
    } else if (p.command.address != pmd::kPointToPointAddress || !p.known_opcode) {
      ++counts_.invalid_instructions;
      reply.status = pmd::status::kInvalidInstruction;
    } else {
      const PmdChipModel::Outcome o = chip_.Execute(p.command);
      if (o.executed) {
        executed_.push_back(
            PmdExecuted{t_s_, p.command.axis, p.command.opcode, pmd::CommandValue(p.command)});
      }
      if (!o.reply) continue;  // Reset answers nothing
      reply = *o.reply;
      if (reply.status != pmd::status::kOk) ++counts_.other_errors;
    }
    const std::vector<std::uint8_t> bytes = pmd::Encode(reply);
    out->insert(out->end(), bytes.begin(), bytes.end());
  }
}

std::unique_ptr<DeviceEmulator> MakeBiclopsEmulator() {
  return std::make_unique<BiclopsEmulator>(DefaultBiclopsEmulatorConfig());
}

}  // namespace hgrasp::drivers
