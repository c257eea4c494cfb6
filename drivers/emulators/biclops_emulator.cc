#include "emulators/biclops_emulator.h"

#include <algorithm>
#include <cmath>
#include <utility>

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

BiclopsEmulatorConfig PoweredUpBiclopsEmulatorConfig(std::uint64_t seed) {
  BiclopsEmulatorConfig c = DefaultBiclopsEmulatorConfig();
  // splitmix64: a few deterministic draws, no dependence on a library's distributions.
  std::uint64_t x = seed;
  auto next = [&x]() {
    x += 0x9E3779B97F4A7C15ull;
    std::uint64_t z = x;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return static_cast<double>((z ^ (z >> 31)) >> 11) / 9007199254740992.0;  // [0, 1)
  };
  const double lo_deg[3] = {-60.0, -30.0, -3.0}, hi_deg[3] = {60.0, 30.0, 15.0};
  for (std::size_t a = 0; a < 3; ++a) {
    c.start_counts[a] = std::round((lo_deg[a] + (hi_deg[a] - lo_deg[a]) * next()) * kCountsPerDeg);
  }
  return c;
}

namespace {

// Get opcode -> (Set opcode, words) of the registers the model only stores, and their
// power-up values where they are not 0 (ours: PMD's manuals were not available).
struct GenericPair {
  std::uint8_t get, set;
  int words;
};
constexpr GenericPair kGeneric[] = {
    {0x07, pmd::op::kSetMotorLimit, 1},
    {0x2D, pmd::op::kSetMotorBias, 1},
    {0x50, pmd::op::kSetKp, 1},
    {0x51, pmd::op::kSetKi, 1},
    {0x52, pmd::op::kSetKd, 1},
    {0x54, pmd::op::kSetKvff, 1},
    {0x94, pmd::op::kSetKaff, 1},
    {0x9F, pmd::op::kSetKout, 1},
    {0x96, pmd::op::kSetIntegrationLimit, 2},
    {0x58, pmd::op::kSetJerk, 2},
    {0x59, 0x14, 2},
    {0x56, 0x2F, 1},
    {0x6B, 0x6A, 2},
    {0x6E, pmd::op::kSetOutputMode, 1},
    {0x88, pmd::op::kSetAxisMode, 1},
    {0x8A, 0x89, 1},
    {0x8E, 0x8D, 1},
    {0x9D, 0x9C, 1},
    {0xA9, 0xA8, 1},
    {0xAB, 0xAA, 1},
    {0xAF, 0xAE, 1},
    {0xB1, 0xB0, 1},
    {0xB3, 0xB2, 1},
    {0xB5, 0xB4, 1},
    {0xB9, 0xB8, 1},
    {0xBD, 0xBC, 1},
    {0xBF, 0xBE, 1},
    {0xCE, 0xCF, 1},
    {0xDB, 0xDA, 1},
    {0xDF, 0xDE, 2},
    {0xE3, 0xE2, 1},
    {0xE5, 0xE4, 1},
    {0xE7, 0xE6, 1},
    {0xE9, 0xE8, 1},
    {0xEC, 0xEB, 1},
    {0xEE, pmd::op::kSetAxisOutSource, 1},
    {0x7B, 0x76, 1},
    {0x7C, 0x72, 1},
    {0x7D, 0x75, 1},
    {0x86, 0x85, 1},
    {0x2C, 0x84, 1},
    {0x69, 0x77, 1},
    {0x8C, 0x8B, 1},
};

const GenericPair* FindGenericGet(std::uint8_t op) {
  for (const GenericPair& g : kGeneric) {
    if (g.get == op) return &g;
  }
  return nullptr;
}

// Opcodes of the Magellan only (PMDOPCodes.h): a Navigator refuses them.
bool MagellanOnly(std::uint8_t op) {
  switch (op) {
    case pmd::op::kSetMotorType:
    case pmd::op::kGetMotorType:
    case pmd::op::kRestoreOperatingMode:
    case pmd::op::kSetEventAction:
    case pmd::op::kGetEventAction:
    case pmd::op::kSetOperatingMode:
    case pmd::op::kGetOperatingMode:
      return true;
    default:
      return false;
  }
}

}  // namespace

PmdChipModel::PmdChipModel(const BiclopsEmulatorConfig& config) : config_(config) {
  for (int a = 0; a < kAxes; ++a) {
    motor_.emplace_back(config.limits[Index(a)], config.start_counts[Index(a)]);
    // Relative encoders: the registers read 0 where the mechanism powered up.
    offset_[Index(a)] = std::llround(motor_.back().position());
    axis_[Index(a)].requested_target = offset_[Index(a)];
  }
  // The axis-out pin and serial settings at power-up (ours): everything else reads 0.
  for (int a = 0; a < kAxes; ++a) {
    generic_[{a, pmd::op::kSetOutputMode}] = {pmd::kOutputPwmSignMagnitude, 0, 0};
    generic_[{a, pmd::op::kSetAxisMode}] = {1, 0, 0};
    generic_[{a, pmd::op::kSetMotorLimit}] = {0x7FFF, 0, 0};
    generic_[{a, pmd::op::kSetKout}] = {0xFFFF, 0, 0};
  }
}

std::int32_t PmdChipModel::ToRegister(double mechanism_counts, int axis) const {
  return static_cast<std::int32_t>(std::llround(mechanism_counts) - offset_[Index(axis)]);
}

bool PmdChipModel::OnHome(int axis, double x) const {
  const std::size_t a = Index(axis);
  return std::abs(x - config_.home_center_counts[a]) <= 0.5 * config_.home_width_counts[a];
}

std::uint16_t PmdChipModel::SignalStatus(int axis) const {
  const std::size_t a = Index(axis);
  const TrapezoidAxis& m = motor_[a];
  const double x = m.position();
  std::uint16_t level = 0;
  const double spacing = config_.index_spacing_counts[a];
  if (config_.has_index[a] && spacing > 0.0) {
    const double k = std::round(x / spacing);
    if (std::abs(x - k * spacing) < 0.5) level |= pmd::signal::kEncoderIndex;
  }
  if (OnHome(axis, x) != config_.home_active_low[a]) level |= pmd::signal::kHome;
  // Limit switches: active low, closed at the hard stops.
  if (x < m.limits().max) level |= pmd::signal::kPositiveLimit;
  if (x > m.limits().min) level |= pmd::signal::kNegativeLimit;
  if (axis_[a].motor_mode == pmd::kMotorOn) level |= pmd::signal::kAxisOut;
  return static_cast<std::uint16_t>((level ^ axis_[a].signal_sense) & pmd::signal::kStatusMask);
}

void PmdChipModel::CheckCapture(int axis, double from, double to) {
  const std::size_t a = Index(axis);
  AxisState& s = axis_[a];
  if (!s.capture_armed || from == to) return;
  const double lo = std::min(from, to), hi = std::max(from, to);
  std::optional<double> at;
  if (s.capture_source == pmd::kCaptureIndex) {
    const double spacing = config_.index_spacing_counts[a];
    if (config_.has_index[a] && spacing > 0.0) {
      // The first index position crossed in the direction of travel.
      const double k = to > from ? std::ceil(lo / spacing) : std::floor(hi / spacing);
      const double idx = k * spacing;
      if (idx >= lo && idx <= hi && idx != from) at = idx;
    }
  } else if (s.capture_source == pmd::kCaptureHome) {
    // The home input's status bit going from 0 to 1 (its level XOR its sense).
    const bool sense = (s.signal_sense & pmd::signal::kHome) != 0;
    const bool active_low = config_.home_active_low[a];
    auto bit = [&](double x) { return (OnHome(axis, x) != active_low) != sense; };
    if (!bit(from) && bit(to)) {
      const double half = 0.5 * config_.home_width_counts[a];
      const double c = config_.home_center_counts[a];
      // The sensor edge that was crossed: entering it, or leaving it (inverted sense).
      const double edges[2] = {c - half, c + half};
      double best = to;
      for (double e : edges) {
        if (e >= lo && e <= hi) best = e;
      }
      at = best;
    }
  }
  if (!at) return;
  s.capture_value = ToRegister(*at, axis);
  s.capture_armed = false;
  s.event_status |= pmd::event::kCaptureReceived;
}

void PmdChipModel::CheckBreakpoints() {
  for (std::size_t b = 0; b < breakpoint_.size(); ++b) {
    Breakpoint& bp = breakpoint_[b];
    if (bp.trigger != pmd::kBreakpointEventStatus) continue;  // the only trigger modelled
    const std::size_t a = Index(bp.axis);
    // Value: mask in the high word, the wanted bit states in the low word.
    const auto mask = static_cast<std::uint16_t>(bp.value >> 16);
    const auto want = static_cast<std::uint16_t>(bp.value & 0xFFFFu);
    if ((axis_[a].event_status & mask) != (want & mask)) continue;
    const double cycle = cycle_s();
    const double accel = active_[a].acceleration / pmd::kAccelerationScale / (cycle * cycle);
    switch (bp.action) {
      case pmd::kBreakpointSmoothStop:
        motor_[a].MoveAt(0.0, accel > 0.0 ? accel : motor_[a].limits().max_accel);
        break;
      case pmd::kBreakpointAbruptStop:
        motor_[a].Stop();
        break;
      case pmd::kBreakpointMotorOff:
        motor_[a].Stop();
        axis_[a].motor_mode = pmd::kMotorOff;
        break;
      default:
        break;
    }
    axis_[a].event_status |= b == 0 ? pmd::event::kBreakpoint1 : pmd::event::kBreakpoint2;
    bp.trigger = pmd::kBreakpointDisable;  // a breakpoint fires once
  }
}

void PmdChipModel::Advance(double t_s) {
  double dt = t_s - t_s_;
  if (dt <= 0.0) return;
  t_s_ = t_s;
  while (dt > 0.0) {
    const double h = std::min(dt, 1e-3);
    dt -= h;
    for (int a = 0; a < kAxes; ++a) {
      TrapezoidAxis& m = motor_[Index(a)];
      AxisState& s = axis_[Index(a)];
      const double before = m.position();
      m.Advance(h);
      CheckCapture(a, before, m.position());
      const bool at_pos = m.position() >= m.limits().max;
      const bool at_neg = m.position() <= m.limits().min;
      if (at_pos && !s.at_positive) s.event_status |= pmd::event::kInPositiveLimit;
      if (at_neg && !s.at_negative) s.event_status |= pmd::event::kInNegativeLimit;
      if ((at_pos || at_neg) && !m.moving() && s.was_moving) {
        // Held at a hard stop short of the profile's target: a following error beyond the
        // limit is a motion error; with auto-stop on, the motor goes off.
        const double error = std::abs(static_cast<double>(s.requested_target) - m.position());
        if (error > s.position_error_limit) {
          s.event_status |= pmd::event::kMotionError;
          if (s.auto_stop_mode != 0) s.motor_mode = pmd::kMotorOff;
        }
      }
      s.at_positive = at_pos;
      s.at_negative = at_neg;
      if (s.was_moving && !m.moving()) s.event_status |= pmd::event::kMotionComplete;
      s.was_moving = m.moving();
    }
    CheckBreakpoints();
  }
}

std::uint16_t PmdChipModel::ActivityStatus(int axis) const {
  const TrapezoidAxis& m = motor_[Index(axis)];
  const Registers& act = active_[Index(axis)];
  std::uint16_t s = axis_[Index(axis)].motor_mode == pmd::kMotorOn ? pmd::activity::kMotorOn : 0;
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

void PmdChipModel::StartProfile(int axis) {
  // The buffered profile becomes the active one; the trajectory starts from where the axis
  // is, at its present velocity. With the motor off the mechanism does not follow (ours).
  const std::size_t a = Index(axis);
  AxisState& s = axis_[a];
  if (buffered_[a].stop_mode != pmd::kNoStop) {
    // A stop: the axis halts where it is (abrupt) or at its acceleration (smooth); the
    // profile's other registers stay buffered.
    const double cycle = cycle_s();
    const double accel = active_[a].acceleration / pmd::kAccelerationScale / (cycle * cycle);
    if (buffered_[a].stop_mode == pmd::kSmoothStop && accel > 0.0) {
      motor_[a].MoveAt(0.0, accel);
    } else {
      motor_[a].Stop();
    }
    buffered_[a].stop_mode = pmd::kNoStop;
    s.requested_target = std::llround(motor_[a].position());
    return;
  }
  active_[a] = buffered_[a];
  if (s.motor_mode != pmd::kMotorOn) return;
  const double cycle = cycle_s();
  const Registers& buf = buffered_[a];
  const double speed = buf.velocity / pmd::kVelocityScale / cycle;
  const double accel = buf.acceleration / pmd::kAccelerationScale / (cycle * cycle);
  s.requested_target = buf.position + offset_[a];
  motor_[a].MoveTo(static_cast<double>(s.requested_target), speed, accel);
  if (!motor_[a].moving()) s.event_status |= pmd::event::kMotionComplete;  // already there
  s.was_moving = motor_[a].moving();
}

std::uint16_t* PmdChipModel::GenericRegister(int axis, std::uint8_t set_opcode, int /*words*/) {
  return generic_[{axis, set_opcode}].data();
}

PmdChipModel::Outcome PmdChipModel::Execute(const pmd::Command& c) {
  Outcome out;
  const pmd::OpcodeInfo* info = pmd::FindOpcode(c.opcode);
  if (info == nullptr) {
    // No instruction at all (the packet was framed by its checksum).
    out.reply = Status(pmd::status::kInvalidInstruction);
    host_io_error_ = pmd::status::kInvalidInstruction;
    return out;
  }
  const bool chip_wide = c.opcode == pmd::op::kNoOperation || c.opcode == pmd::op::kReset ||
                         c.opcode == pmd::op::kGetVersion || c.opcode == pmd::op::kGetSampleTime ||
                         c.opcode == pmd::op::kMultiUpdate || c.opcode == pmd::op::kWriteIO ||
                         c.opcode == pmd::op::kReadIO || c.opcode == pmd::op::kGetHostIOError ||
                         (c.opcode >= pmd::op::kSetBufferStart && c.opcode <= 0xCB);
  if (c.axis >= kAxes || (c.opcode == pmd::op::kReset && c.axis != 0)) {
    out.reply = Status(pmd::status::kInvalidAxis);
    host_io_error_ = pmd::status::kInvalidAxis;
    return out;
  }
  if (MagellanOnly(c.opcode)) {
    // A Magellan instruction, which a Navigator does not have (framed by its table length).
    out.reply = Status(pmd::status::kInvalidInstruction);
    host_io_error_ = pmd::status::kInvalidInstruction;
    return out;
  }
  const int axis = chip_wide ? 0 : c.axis;
  const std::size_t a = Index(axis);
  Registers& buf = buffered_[a];
  AxisState& st = axis_[a];
  const double cycle = cycle_s();
  const auto value32 = static_cast<std::uint32_t>(pmd::JoinLong(c.words[0], c.words[1]));
  out.reply = Status(pmd::status::kOk);
  out.executed = info->changes_state;
  switch (c.opcode) {
    case pmd::op::kNoOperation:
      break;
    case pmd::op::kSetPosition:
      buf.position = static_cast<std::int32_t>(value32);
      break;
    case pmd::op::kSetVelocity: {
      const auto v = static_cast<std::int32_t>(value32);
      if (v < 0 && buf.profile_mode == pmd::kTrapezoidalProfile) {
        out.reply = Status(pmd::status::kInvalidNegativeValue);
        out.executed = false;
        break;
      }
      buf.velocity = v;
      break;
    }
    case pmd::op::kSetAcceleration:
      buf.acceleration = value32;
      break;
    case pmd::op::kSetDeceleration:
      buf.deceleration = value32;
      break;
    case pmd::op::kSetProfileMode:
      // This model generates trapezoidal profiles only.
      if (c.words[0] != pmd::kTrapezoidalProfile) {
        out.reply = Status(pmd::status::kInvalidParameter);
        out.executed = false;
        break;
      }
      buf.profile_mode = c.words[0];
      break;
    case pmd::op::kUpdate:
      StartProfile(axis);
      break;
    case pmd::op::kMultiUpdate:
      for (int i = 0; i < kAxes; ++i) {
        if ((c.words[0] >> i) & 1u) StartProfile(i);
      }
      break;
    case pmd::op::kReset:
      // Every register to its power-up value; the position counters restart at 0 where the
      // mechanism is; the motors stop. No reply.
      for (int i = 0; i < kAxes; ++i) {
        motor_[Index(i)].Stop();
        offset_[Index(i)] = std::llround(motor_[Index(i)].position());
        buffered_[Index(i)] = Registers{};
        active_[Index(i)] = Registers{};
        axis_[Index(i)] = AxisState{};
        axis_[Index(i)].requested_target = offset_[Index(i)];
      }
      breakpoint_ = {};
      ++resets_;
      host_io_error_ = pmd::status::kChipsetReset;
      out.reply.reset();
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
    case 0x92:  // GetDeceleration
      out.reply = Long(buf.deceleration);
      break;
    case pmd::op::kGetProfileMode:
      out.reply = Word(buf.profile_mode);
      break;
    case pmd::op::kSetStopMode:
      if (c.words[0] > pmd::kSmoothStop) {
        out.reply = Status(pmd::status::kInvalidParameter);
        out.executed = false;
        break;
      }
      buf.stop_mode = c.words[0];
      break;
    case pmd::op::kGetStopMode:
      out.reply = Word(buf.stop_mode);
      break;
    case pmd::op::kGetActualPosition:
    case pmd::op::kGetCommandedPosition:
      // A stiff servo: the encoder reads the profile position.
      out.reply = Long(static_cast<std::uint32_t>(ToRegister(motor_[a].position(), axis)));
      break;
    case pmd::op::kGetCommandedVelocity:
    case 0xAD: {  // GetActualVelocity
      const double v = motor_[a].velocity() * cycle * pmd::kVelocityScale;
      out.reply = Long(static_cast<std::uint32_t>(static_cast<std::int32_t>(std::llround(v))));
      break;
    }
    case 0x99:  // GetPositionError: a stiff servo
      out.reply = Long(0);
      break;
    case pmd::op::kSetActualPosition:
      // The encoder counter is loaded: the mechanism stands still, the registers move.
      offset_[a] = std::llround(motor_[a].position()) - static_cast<std::int32_t>(value32);
      break;
    case pmd::op::kAdjustActualPosition:
      offset_[a] -= static_cast<std::int32_t>(value32);
      break;
    case pmd::op::kGetActivityStatus:
      out.reply = Word(ActivityStatus(axis));
      break;
    case pmd::op::kGetEventStatus:
      out.reply = Word(st.event_status);
      break;
    case pmd::op::kResetEventStatus:
      st.event_status &= c.words[0];  // bits that are 0 in the mask are cleared
      break;
    case pmd::op::kGetSignalStatus:
      out.reply = Word(SignalStatus(axis));
      break;
    case pmd::op::kSetSignalSense:
      st.signal_sense = c.words[0];
      break;
    case pmd::op::kGetSignalSense:
      out.reply = Word(st.signal_sense);
      break;
    case pmd::op::kSetCaptureSource:
      st.capture_source = c.words[0];
      break;
    case pmd::op::kGetCaptureSource:
      out.reply = Word(st.capture_source);
      break;
    case pmd::op::kGetCaptureValue:
      // Reading the capture register re-arms the capture.
      out.reply = Long(static_cast<std::uint32_t>(st.capture_value));
      st.capture_armed = true;
      break;
    case pmd::op::kSetMotorMode:
      st.motor_mode = c.words[0] != 0 ? pmd::kMotorOn : pmd::kMotorOff;
      if (st.motor_mode == pmd::kMotorOff) motor_[a].Stop();
      break;
    case pmd::op::kGetMotorMode:
      out.reply = Word(st.motor_mode);
      break;
    case pmd::op::kSetLimitSwitchMode:
      st.limit_switch_mode = c.words[0];
      break;
    case 0x81:  // GetLimitSwitchMode
      out.reply = Word(st.limit_switch_mode);
      break;
    case pmd::op::kSetAutoStopMode:
      st.auto_stop_mode = c.words[0];
      break;
    case 0xD3:  // GetAutoStopMode
      out.reply = Word(st.auto_stop_mode);
      break;
    case pmd::op::kSetPositionErrorLimit:
      st.position_error_limit = value32;
      break;
    case pmd::op::kGetPositionErrorLimit:
      out.reply = Long(st.position_error_limit);
      break;
    case pmd::op::kClearPositionError:
      break;
    case pmd::op::kSetBreakpoint:
    case pmd::op::kSetBreakpointValue: {
      if (c.words[0] > 1) {
        out.reply = Status(pmd::status::kInvalidParameter);
        out.executed = false;
        break;
      }
      Breakpoint& bp = breakpoint_[c.words[0]];
      if (c.opcode == pmd::op::kSetBreakpoint) {
        // Second word: axis | action << 4 | trigger << 8 (libPMD PMD::SetBreakpoint).
        bp.axis = c.words[1] & 0x0F;
        bp.action = (c.words[1] >> 4) & 0x0F;
        bp.trigger = (c.words[1] >> 8) & 0xFF;
        if (bp.axis >= kAxes) {
          bp.trigger = pmd::kBreakpointDisable;
          out.reply = Status(pmd::status::kInvalidAxis);
          out.executed = false;
        }
      } else {
        bp.value = pmd::JoinLong(c.words[1], c.words[2]);
      }
      break;
    }
    case pmd::op::kGetBreakpoint:
    case pmd::op::kGetBreakpointValue: {
      if (c.words[0] > 1) {
        out.reply = Status(pmd::status::kInvalidParameter);
        break;
      }
      const Breakpoint& bp = breakpoint_[c.words[0]];
      out.reply = c.opcode == pmd::op::kGetBreakpoint
                      ? Word(static_cast<std::uint16_t>(bp.axis | bp.action << 4 | bp.trigger << 8))
                      : Long(bp.value);
      break;
    }
    case pmd::op::kWriteIO:
      io_[c.words[0]] = c.words[1];
      break;
    case pmd::op::kReadIO:
      out.reply = Word(io_.count(c.words[0]) != 0 ? io_[c.words[0]] : 0);
      break;
    case pmd::op::kGetHostIOError:
      out.reply = Word(host_io_error_);
      host_io_error_ = pmd::status::kOk;
      break;
    case pmd::op::kReadBuffer:
    case 0xC1:
    case 0xC3:
    case 0xC5:
    case 0xC7:
      // No external memory on the Biclops' chip: buffers read 0 (libPMD's HasMemory test
      // writes a word and reads it back).
      out.reply = Long(0);
      break;
    case 0xCB:  // GetBufferFunction
      out.reply = Word(0);
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
    case 0x3E: {  // GetTime: chip cycles since power-up
      out.reply = Long(static_cast<std::uint32_t>(t_s_ / cycle));
      break;
    }
    default:
      if (const GenericPair* g = FindGenericGet(c.opcode)) {
        const std::uint16_t* w = GenericRegister(axis, g->set, g->words);
        if (g->words == 2) {
          out.reply = Long(pmd::JoinLong(w[0], w[1]));
        } else {
          out.reply = Word(w[0]);
        }
      } else if (info->result_words == 0 && info->argument_words > 0) {
        // A Set* the model only stores (filter gains, limits, modes, buffer pointers).
        std::uint16_t* w = GenericRegister(axis, c.opcode, info->argument_words);
        for (int i = 0; i < info->argument_words; ++i) w[i] = c.words[static_cast<std::size_t>(i)];
      } else if (info->result_words == 0) {
        // A command without data the model has no use for (InitializePhase, ClearInterrupt).
      } else {
        // A Get* of a quantity the model does not have: 0.
        out.reply = info->result_words == 2 ? Long(0) : Word(0);
      }
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
      if (reply.status == pmd::status::kInvalidInstruction) {
        ++counts_.invalid_instructions;  // a Magellan-only instruction
      } else if (reply.status != pmd::status::kOk) {
        ++counts_.other_errors;
      }
    }
    const std::vector<std::uint8_t> bytes = pmd::Encode(reply);
    out->insert(out->end(), bytes.begin(), bytes.end());
  }
}

std::unique_ptr<DeviceEmulator> MakeBiclopsEmulator(std::uint64_t seed) {
  return std::make_unique<BiclopsEmulator>(PoweredUpBiclopsEmulatorConfig(seed));
}

}  // namespace hgrasp::drivers
