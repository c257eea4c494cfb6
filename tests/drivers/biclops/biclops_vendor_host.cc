#include "biclops_vendor_host.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>

namespace hgrasp::drivers {

namespace {

namespace op = pmd::op;

// libPMD PMDAxisControl: AutostopEventMask and MoveEventMask.
constexpr std::uint16_t kAutostopEvents =
    pmd::event::kMotionError | pmd::event::kInPositiveLimit | pmd::event::kInNegativeLimit;
constexpr std::uint16_t kMoveEvents = kAutostopEvents | pmd::event::kMotionComplete;

std::string Hex(int v) {
  static const char* d = "0123456789ABCDEF";
  return std::string("0x") + d[(v >> 4) & 0xF] + d[v & 0xF];
}

}  // namespace

VendorHost::VendorHost(std::unique_ptr<ByteLink> link, Clock& clock)
    : link_(std::move(link)), clock_(&clock) {}

bool VendorHost::Send(const pmd::Command& c, int result_words, pmd::Reply* reply) {
  ++packets_;
  link_->Discard();
  if (link_->Write(pmd::Encode(c)) != device::Status::kOk) {
    error_ = "write failed";
    return false;
  }
  if (c.opcode == op::kReset) return true;  // libPMD reads no reply to Reset
  pmd::ReplyDecoder decoder;
  decoder.Expect(result_words);
  const auto deadline = clock_->Now() + std::chrono::milliseconds(500);
  std::uint8_t buf[16];
  for (;;) {
    std::size_t n = 0;
    const double left = Clock::ToSeconds(deadline - clock_->Now());
    if (left <= 0.0) {
      error_ = "no reply to opcode " + Hex(c.opcode);
      return false;
    }
    if (const device::Status s = link_->Read(std::span<std::uint8_t>(buf, 1), left, &n);
        s != device::Status::kOk && s != device::Status::kTimeout) {
      error_ =
          "read failed (" + std::string(device::ToString(s)) + ") awaiting opcode " + Hex(c.opcode);
      return false;
    }
    if (n == 0) continue;
    const pmd::ReplyDecoder::Result r = decoder.Push(buf[0]);
    if (r == pmd::ReplyDecoder::Result::kNeedMore) continue;
    if (r == pmd::ReplyDecoder::Result::kGarbled) {
      error_ = "bad reply checksum to opcode " + Hex(c.opcode);
      return false;
    }
    break;
  }
  if (reply != nullptr) *reply = decoder.reply();
  if (decoder.reply().status != pmd::status::kOk) {
    error_ = "status " + Hex(decoder.reply().status) + " to opcode " + Hex(c.opcode) + " axis " +
             std::to_string(c.axis);
    return false;
  }
  return true;
}

bool VendorHost::Word(int axis, std::uint8_t opcode, std::uint16_t w) {
  return Send(pmd::WithWord(static_cast<std::uint8_t>(axis), opcode, w), 0);
}

bool VendorHost::Long(int axis, std::uint8_t opcode, std::uint32_t v) {
  return Send(pmd::WithLong(static_cast<std::uint8_t>(axis), opcode, v), 0);
}

bool VendorHost::GetWord(int axis, std::uint8_t opcode, std::uint16_t* w) {
  pmd::Reply r;
  if (!Send(pmd::Simple(static_cast<std::uint8_t>(axis), opcode), 1, &r)) return false;
  *w = r.words[0];
  return true;
}

bool VendorHost::GetLong(int axis, std::uint8_t opcode, std::int32_t* v) {
  pmd::Reply r;
  if (!Send(pmd::Simple(static_cast<std::uint8_t>(axis), opcode), 2, &r)) return false;
  *v = static_cast<std::int32_t>(pmd::ReplyLong(r));
  return true;
}

bool VendorHost::SendRaw(std::span<const std::uint8_t> bytes, int reply_words,
                         std::uint8_t* status) {
  ++packets_;
  link_->Discard();
  if (link_->Write(bytes) != device::Status::kOk) return false;
  pmd::ReplyDecoder decoder;
  decoder.Expect(reply_words);
  const auto deadline = clock_->Now() + std::chrono::milliseconds(500);
  std::uint8_t b = 0;
  while (clock_->Now() < deadline) {
    std::size_t n = 0;
    if (const device::Status s = link_->Read(std::span<std::uint8_t>(&b, 1), 0.05, &n);
        s != device::Status::kOk && s != device::Status::kTimeout) {
      return false;
    }
    if (n == 0) continue;
    const pmd::ReplyDecoder::Result r = decoder.Push(b);
    if (r == pmd::ReplyDecoder::Result::kNeedMore) continue;
    if (r == pmd::ReplyDecoder::Result::kGarbled) return false;
    *status = decoder.reply().status;
    return true;
  }
  error_ = "no reply to raw bytes";
  return false;
}

// ---------------------------------------------------------------------------------------------
// Biclops::Initialize

bool VendorHost::Initialize(const std::array<VendorAxisConfig, 3>& axes) {
  for (int a = 0; a < 3; ++a)
    axis_[static_cast<std::size_t>(a)].cfg = axes[static_cast<std::size_t>(a)];
  // PMDController::ConfigureController: GetVersion (axis count, family), GetSampleTime.
  pmd::Reply r;
  if (!Send(pmd::Simple(0, op::kGetVersion), 2, &r)) return false;
  const int family = r.words[0] >> 12, axis_count = (r.words[0] >> 4) & 0xF;
  if (axis_count < 3) {
    error_ = "fewer than 3 axes";
    return false;
  }
  // PMDController::HasMemory: write a word to the buffer and read it back.
  const std::uint16_t start[] = {0, 0, 0}, length[] = {0, 0, 8}, data[] = {0, 0x8765, 0x4321};
  if (!Send(pmd::WithWords(0, op::kSetBufferStart, start), 0)) return false;
  if (!Send(pmd::WithWords(0, op::kSetBufferLength, length), 0)) return false;
  if (!Send(pmd::WithWords(0, op::kWriteBuffer, data), 0)) return false;
  if (!Send(pmd::WithWord(0, op::kReadBuffer, 0), 2, &r)) return false;
  if (pmd::ReplyLong(r) == static_cast<std::int32_t>(0x87654321)) {
    error_ = "the emulated Biclops has no memory; this host does not model one";
    return false;
  }
  std::uint16_t cycle_us = 0;
  if (!GetWord(0, op::kGetSampleTime, &cycle_us)) return false;
  cycle_s_ = cycle_us * 1e-6;
  for (int a = 0; a < 3; ++a) {
    // SetMotorTypeInHardware: the glue logic's brushless bit, then SetMotorType on a Magellan
    // only.
    std::uint16_t io = 0;
    if (!Send(pmd::WithWord(0, op::kReadIO, 0), 1, &r)) return false;
    io = r.words[0] & static_cast<std::uint16_t>(~0x0002u);
    const std::uint16_t write_io[] = {0, io};
    if (!Send(pmd::WithWords(0, op::kWriteIO, write_io), 0)) return false;
    if (family == 5 && !Word(a, op::kSetMotorType, 7)) return false;
    if (!ConfigureHardware(a)) return false;
  }
  return true;
}

bool VendorHost::ConfigureHardware(int a) {
  const VendorAxisConfig& cfg = axis_[static_cast<std::size_t>(a)].cfg;
  std::uint16_t w = 0;
  if (!Word(a, op::kResetEventStatus, static_cast<std::uint16_t>(~kMoveEvents))) return false;
  if (!Word(a, op::kSetAxisOutSource, static_cast<std::uint16_t>(a))) return false;  // none
  if (!Word(a, op::kSetMotorMode, pmd::kMotorOff)) return false;
  if (!GetWord(a, op::kGetMotorMode, &w)) return false;
  // DisableAmp: the axis-out pin through its signal sense.
  if (!GetWord(a, op::kGetSignalSense, &w)) return false;
  w = cfg.amp_active_low ? (w & ~pmd::signal::kAxisOut) : (w | pmd::signal::kAxisOut);
  if (!Word(a, op::kSetSignalSense, w)) return false;
  if (!Word(a, op::kSetLimitSwitchMode, 0)) return false;  // no limit sensors (Navigator)
  if (!GetWord(a, op::kGetSignalSense, &w)) return false;
  w &= static_cast<std::uint16_t>(~pmd::signal::kMotorDirection);
  w = cfg.home_active_low ? (w | pmd::signal::kHome) : (w & ~pmd::signal::kHome);
  w &= static_cast<std::uint16_t>(~(pmd::signal::kPositiveLimit | pmd::signal::kNegativeLimit));
  if (!Word(a, op::kSetSignalSense, w)) return false;
  if (!Word(a, op::kResetEventStatus, 0)) return false;
  if (!Word(a, op::kSetOutputMode, pmd::kOutputPwmSignMagnitude)) return false;
  if (!Word(a, op::kSetProfileMode, pmd::kTrapezoidalProfile)) return false;
  if (!Word(a, op::kSetAxisMode, 1)) return false;
  return GetWord(a, op::kGetMotorMode, &w);
}

// ---------------------------------------------------------------------------------------------
// Moves: PreMove, SendProfileToController, Update / MultiUpdate, IsMotionDone

bool VendorHost::PreMove(int a) {
  AxisState& s = axis_[static_cast<std::size_t>(a)];
  if (!s.event_status_loaded && !GetWord(a, op::kGetEventStatus, &s.event_status)) return false;
  const std::uint16_t events = s.event_status;
  if (events != 0 && !Word(a, op::kResetEventStatus, 0)) return false;
  if ((events & pmd::event::kMotionError) != 0 && !Word(a, op::kSetMotorMode, pmd::kMotorOn)) {
    return false;
  }
  if ((events & kAutostopEvents) != 0) s.loaded = false;
  s.event_status_loaded = false;
  s.event_status = 0;
  return true;
}

bool VendorHost::SendProfile(int a) {
  // Only what differs from what was loaded, then always the position.
  AxisState& s = axis_[static_cast<std::size_t>(a)];
  const auto vel =
      std::max<std::int32_t>(1, static_cast<std::int32_t>(s.vel * cycle_s_ * pmd::kVelocityScale));
  const auto acc = std::max<std::uint32_t>(
      2, static_cast<std::uint32_t>(s.acc * cycle_s_ * cycle_s_ * pmd::kAccelerationScale));
  if (!s.loaded || vel != s.loaded_vel) {
    if (!Long(a, op::kSetVelocity, static_cast<std::uint32_t>(vel))) return false;
  }
  if (!s.loaded || acc != s.loaded_acc) {
    if (!Long(a, op::kSetAcceleration, acc)) return false;
  }
  if (!Long(a, op::kSetPosition, static_cast<std::uint32_t>(s.pos))) return false;
  s.loaded_vel = vel;
  s.loaded_acc = acc;
  s.loaded = true;
  return true;
}

bool VendorHost::WaitMotionDone(int a, bool include_capture) {
  AxisState& s = axis_[static_cast<std::size_t>(a)];
  const std::uint16_t mask = kMoveEvents | (include_capture ? pmd::event::kCaptureReceived : 0);
  const auto give_up = clock_->Now() + std::chrono::seconds(30);
  for (;;) {
    if (!GetWord(a, op::kGetEventStatus, &s.event_status)) return false;
    s.event_status_loaded = true;
    if ((s.event_status & mask) != 0) return true;
    if (clock_->Now() > give_up) {
      error_ = "motion never done on axis " + std::to_string(a);
      return false;
    }
    clock_->SleepFor(std::chrono::milliseconds(5));
  }
}

bool VendorHost::Move1(int a, bool with_capture, bool* capture_seen) {
  if (!PreMove(a)) return false;
  if (with_capture) {
    // MoveWithCaptureInterrupt: breakpoint 1 smooth-stops the axis on the capture event.
    const std::uint16_t value[] = {0, pmd::event::kCaptureReceived, pmd::event::kCaptureReceived};
    if (!Send(pmd::WithWords(static_cast<std::uint8_t>(a), op::kSetBreakpointValue, value), 0)) {
      return false;
    }
    const std::uint16_t bp[] = {0, static_cast<std::uint16_t>(a | pmd::kBreakpointSmoothStop << 4 |
                                                              pmd::kBreakpointEventStatus << 8)};
    if (!Send(pmd::WithWords(static_cast<std::uint8_t>(a), op::kSetBreakpoint, bp), 0))
      return false;
  }
  if (!SendProfile(a)) return false;
  if (!Send(pmd::Update(static_cast<std::uint8_t>(a)), 0)) return false;
  if (!WaitMotionDone(a, with_capture)) return false;
  if (with_capture) {
    const std::uint16_t off[] = {0, static_cast<std::uint16_t>(a)};
    if (!Send(pmd::WithWords(static_cast<std::uint8_t>(a), op::kSetBreakpoint, off), 0))
      return false;
    // CaptureEventTriggered, on the event status the wait loaded.
    *capture_seen =
        (axis_[static_cast<std::size_t>(a)].event_status & pmd::event::kCaptureReceived) != 0;
    // The axis may still be stopping: libPMD's next move starts from wherever it is; this
    // host waits for the stop so that each step starts at rest, as libPMD's 500 ms polls do.
    std::uint16_t activity = pmd::activity::kInMotion;
    while ((activity & pmd::activity::kInMotion) != 0) {
      if (!GetWord(a, op::kGetActivityStatus, &activity)) return false;
      clock_->SleepFor(std::chrono::milliseconds(5));
    }
  }
  return true;
}

bool VendorHost::Move(int mask, const std::array<std::int32_t, 3>& target) {
  for (int a = 0; a < 3; ++a) {
    if ((mask >> a & 1) == 0) continue;
    AxisState& s = axis_[static_cast<std::size_t>(a)];
    s.pos = target[static_cast<std::size_t>(a)];
    s.vel = s.cfg.run_vel;
    s.acc = s.cfg.run_acc;
    if (!PreMove(a) || !SendProfile(a)) return false;
  }
  if (!Word(0, op::kMultiUpdate, static_cast<std::uint16_t>(mask))) return false;
  for (int a = 0; a < 3; ++a) {
    if ((mask >> a & 1) != 0 && !WaitMotionDone(a, false)) return false;
  }
  return true;
}

bool VendorHost::ReadPosition(int axis, std::int32_t* counts) {
  return GetLong(axis, op::kGetActualPosition, counts);
}

// ---------------------------------------------------------------------------------------------
// Biclops::HomeAxes: PMDAxisControl::FindHome, homingMode bestWay

bool VendorHost::HomeAxes() {
  for (int a : {1, 2, 0}) {
    if (!FindHome(a)) return false;
  }
  return true;
}

bool VendorHost::HomeAsserted(int a, bool* asserted) {
  std::uint16_t w = 0;
  if (!GetWord(a, op::kGetSignalStatus, &w)) return false;
  *asserted = (w & pmd::signal::kHome) != 0;
  return true;
}

bool VendorHost::FindHome(int a) {
  AxisState& s = axis_[static_cast<std::size_t>(a)];
  const VendorAxisConfig& cfg = s.cfg;
  // GetHomedState on a controller without memory: the capture source.
  std::uint16_t source = 0;
  if (!GetWord(a, op::kGetCaptureSource, &source)) return false;
  // SetHomedState(false).
  if (!Word(a, op::kSetCaptureSource, pmd::kCaptureIndex)) return false;
  // SetFilter(homing filter): gains, then Update.
  const std::uint8_t gain_ops[] = {op::kSetKp,   op::kSetKd,   op::kSetKi,
                                   op::kSetKvff, op::kSetKaff, op::kSetKout};
  for (std::size_t i = 0; i < 6; ++i) {
    if (!Word(a, gain_ops[i], cfg.run_filter[i])) return false;
  }
  if (!Long(a, op::kSetIntegrationLimit, 1000)) return false;
  if (!Word(a, op::kSetMotorLimit, 20000)) return false;
  if (!Word(a, op::kSetMotorBias, 0)) return false;
  if (!Long(a, op::kSetPositionErrorLimit, 333)) return false;
  if (!Send(pmd::Update(static_cast<std::uint8_t>(a)), 0)) return false;
  // The current position is defined to be zero.
  std::int32_t pos = 0;
  if (!GetLong(a, op::kGetActualPosition, &pos)) return false;
  if (pos != 0 && !Long(a, op::kSetActualPosition, 0)) return false;
  // A zero move so that closed-loop control does not move the axis.
  s.pos = 0;
  s.vel = 0.0;
  s.acc = cfg.homing_acc;
  if (!SendProfile(a)) return false;
  // EnableAmp, closed loop on.
  std::uint16_t sense = 0;
  if (!GetWord(a, op::kGetSignalSense, &sense)) return false;
  sense = cfg.amp_active_low ? (sense | pmd::signal::kAxisOut) : (sense & ~pmd::signal::kAxisOut);
  if (!Word(a, op::kSetSignalSense, sense)) return false;
  if (!Word(a, op::kSetProfileMode, pmd::kTrapezoidalProfile)) return false;
  if (!Word(a, op::kSetMotorMode, pmd::kMotorOn)) return false;

  // FindHomeBestWay with several index pulses per axis turn and a home sensor, no analog
  // sensor: start towards -, motion limited to +-rangeOfMotion.
  s.vel = cfg.homing_vel;
  s.acc = cfg.homing_acc;
  int move_dir = -1;
  const std::int32_t ll = -cfg.range_of_motion, ul = cfg.range_of_motion;
  std::int32_t home_center = 0, index_pos = 0;
  bool asserted = false;
  if (!HomeAsserted(a, &asserted)) return false;
  if (asserted) {
    if (!FindHomeCenter(a, &move_dir, &home_center, ll, ul)) return false;
    if (!FindIndex(a, move_dir, &index_pos)) return false;
  } else {
    if (!FindIndex(a, move_dir, &index_pos)) return false;
    if (!FindHomeCenter(a, &move_dir, &home_center, ll, ul)) return false;
  }
  // The index nearest the home centre is the zero.
  const double cycles = static_cast<double>(home_center - index_pos) / cfg.counts_per_encoder_cycle;
  const std::int32_t zero =
      index_pos + static_cast<std::int32_t>(std::lround(cycles)) * cfg.counts_per_encoder_cycle;
  if (!Long(a, op::kAdjustActualPosition, static_cast<std::uint32_t>(-zero))) return false;
  zero_[static_cast<std::size_t>(a)] = zero;
  // SetHomedState(true), auto-stop on, the run filter, and the move to 0 at the run profile.
  if (!Word(a, op::kSetCaptureSource, pmd::kCaptureHome)) return false;
  if (!Word(a, op::kSetAutoStopMode, 1)) return false;
  if (!Send(pmd::Update(static_cast<std::uint8_t>(a)), 0)) return false;  // SetFilter(run)
  s.pos = 0;
  s.vel = cfg.run_vel;
  s.acc = cfg.run_acc;
  bool seen = false;
  return Move1(a, false, &seen);
}

bool VendorHost::FindIndex(int a, int move_dir, std::int32_t* index_pos) {
  AxisState& s = axis_[static_cast<std::size_t>(a)];
  std::int32_t pos = 0;
  if (!GetLong(a, op::kGetActualPosition, &pos)) return false;
  const std::int32_t ll = pos - 2 * s.cfg.counts_per_encoder_cycle;
  const std::int32_t ul = pos + 2 * s.cfg.counts_per_encoder_cycle;
  if (!Word(a, op::kSetCaptureSource, pmd::kCaptureIndex)) return false;
  std::int32_t capture = 0;
  if (!GetLong(a, op::kGetCaptureValue, &capture)) return false;  // re-arm
  for (int attempt = 0; attempt < 2; ++attempt) {
    s.pos = move_dir > 0 ? ul : ll;
    bool seen = false;
    if (!Move1(a, true, &seen)) return false;
    if (seen) {
      if (!GetLong(a, op::kGetActualPosition, &pos)) return false;
      return GetLong(a, op::kGetCaptureValue, index_pos);
    }
    move_dir = -move_dir;  // the other direction
  }
  error_ = "index not found on axis " + std::to_string(a);
  return false;
}

bool VendorHost::FindHomeCenter(int a, int* move_dir, std::int32_t* center, std::int32_t motion_ll,
                                std::int32_t motion_ul) {
  AxisState& s = axis_[static_cast<std::size_t>(a)];
  const std::int32_t width = s.cfg.home_sensor_width;
  if (!Word(a, op::kSetCaptureSource, pmd::kCaptureHome)) return false;
  std::uint16_t normal_sense = 0;
  if (!GetWord(a, op::kGetSignalSense, &normal_sense)) return false;
  std::int32_t start = 0;
  if (!GetLong(a, op::kGetActualPosition, &start)) return false;
  bool asserted = false;
  if (!HomeAsserted(a, &asserted)) return false;
  std::int32_t local_ll = asserted ? start - width : motion_ll;
  std::int32_t local_ul = asserted ? start + width : motion_ul;
  std::int32_t home[2] = {0, 0};
  bool valid = false;
  for (int attempts = 0; !valid && attempts <= 2; ++attempts) {
    for (int edge = 0; edge < 2; ++edge) {
      if (!HomeAsserted(a, &asserted)) return false;
      if (asserted) {
        // Off the sensor first, the other way.
        s.pos = *move_dir > 0 ? local_ll : local_ul;
        bool seen = false;
        if (!Move1(a, false, &seen)) return false;
      }
      s.pos = *move_dir < 0 ? local_ll : local_ul;
      std::int32_t capture = 0;
      if (!GetLong(a, op::kGetCaptureValue, &capture)) return false;  // re-arm
      bool seen = false;
      if (!Move1(a, true, &seen)) return false;
      if (!seen) {
        *move_dir = -*move_dir;
        s.pos = *move_dir < 0 ? local_ll : local_ul;
        if (!Move1(a, true, &seen)) return false;
        if (!seen) {
          Word(a, op::kSetSignalSense, normal_sense);
          error_ = "home edge not found on axis " + std::to_string(a);
          return false;
        }
      }
      if (!GetLong(a, op::kGetCaptureValue, &home[edge])) return false;
      *move_dir = -*move_dir;
    }
    valid = std::abs(home[0] - home[1]) > width / 2;
    if (!valid) {
      local_ll = std::max(motion_ll, local_ll - width);
      local_ul = std::min(motion_ul, local_ul + width);
    }
  }
  if (!Word(a, op::kSetSignalSense, normal_sense)) return false;
  if (!valid) {
    error_ = "home edges too close on axis " + std::to_string(a);
    return false;
  }
  *center = (home[0] + home[1]) / 2;
  return true;
}

}  // namespace hgrasp::drivers
