#include "biclops/biclops_head.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <thread>

#include "common/error.h"

namespace hgrasp::drivers {

namespace {

using device::Status;
constexpr double kPi = 3.14159265358979323846;
constexpr const char* kAxisNames[3] = {"pan", "tilt", "verge"};

double Deg(double deg) { return deg * kPi / 180.0; }

double Seconds(std::chrono::steady_clock::duration d) {
  return std::chrono::duration<double>(d).count();
}

std::string Text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

void Require(bool ok, const std::string& field, double value, const std::string& expected) {
  if (!ok) throw InputError("", "biclops." + field, Text(value), expected);
}

// The Get opcode of each buffered register (libPMD PMD.cpp) and its result words.
constexpr std::uint8_t kGetOpcode[] = {pmd::op::kGetPosition, pmd::op::kGetVelocity,
                                       pmd::op::kGetAcceleration, pmd::op::kGetProfileMode};
constexpr int kGetWords[] = {2, 2, 2, 1};

}  // namespace

BiclopsOptions DefaultBiclopsOptions() {
  BiclopsOptions o;
  const double cpr = 12000.0 / (2.0 * kPi);
  o.axes[0] = {cpr, -kPi, kPi, Deg(150.0), Deg(300.0)};
  o.axes[1] = {cpr, Deg(-60.0), Deg(60.0), Deg(150.0), Deg(80.0)};
  o.axes[2] = {cpr, Deg(-5.0), Deg(25.0), Deg(100.0), Deg(200.0)};
  return o;
}

BiclopsHead::BiclopsHead(std::unique_ptr<ByteLink> link, const BiclopsOptions& options)
    : link_(std::move(link)), options_(options) {
  HGRASP_DEMAND_MSG(link_ != nullptr, "BiclopsHead needs a link");
  for (int a = 0; a < 3; ++a) {
    const BiclopsAxisOptions& x = options_.axes[Index(a)];
    const std::string axis = std::string("axes.") + kAxisNames[a] + ".";
    Require(std::isfinite(x.counts_per_rad) && x.counts_per_rad != 0.0, axis + "counts_per_rad",
            x.counts_per_rad, "a finite non-zero number of encoder counts per radian");
    Require(std::isfinite(x.min_rad), axis + "min_rad", x.min_rad, "a finite angle (rad)");
    Require(std::isfinite(x.max_rad) && x.max_rad > x.min_rad, axis + "max_rad", x.max_rad,
            "a finite angle (rad) above min_rad");
    const double reach = std::max(std::abs(x.min_rad), std::abs(x.max_rad));
    Require(reach * std::abs(x.counts_per_rad) < 2.0e9, axis + "counts_per_rad", x.counts_per_rad,
            "a range that fits the chip's 32-bit position registers");
    Require(std::isfinite(x.max_speed_rad_s) && x.max_speed_rad_s > 0.0, axis + "max_speed_rad_s",
            x.max_speed_rad_s, "a positive speed (rad/s)");
    Require(std::isfinite(x.max_accel_rad_s2) && x.max_accel_rad_s2 > 0.0,
            axis + "max_accel_rad_s2", x.max_accel_rad_s2, "a positive acceleration (rad/s^2)");
    // The longest profile: across the range, from full speed the other way.
    const double v = x.max_speed_rad_s, acc = x.max_accel_rad_s2;
    longest_move_s_ = std::max(longest_move_s_, (x.max_rad - x.min_rad) / v + 3.0 * v / acc);
  }
  Require(options_.reply_timeout_s > 0.0, "reply_timeout_s", options_.reply_timeout_s,
          "a positive time (s)");
  Require(options_.resync_byte_timeout_s > 0.0, "resync_byte_timeout_s",
          options_.resync_byte_timeout_s, "a positive time (s)");
  Require(options_.silence_timeout_s > options_.reply_timeout_s, "silence_timeout_s",
          options_.silence_timeout_s, "a time (s) longer than reply_timeout_s");
  Require(options_.max_resends >= 0, "max_resends", options_.max_resends, "0 or more");
  Require(options_.settle_margin_s >= 0.0, "settle_margin_s", options_.settle_margin_s,
          "0 s or more");
  created_ = call_start_ = last_rx_ = Clock::now();
}

BiclopsCounters BiclopsHead::counters() const {
  std::lock_guard<std::mutex> lock(mu_);
  return counters_;
}

std::array<std::int32_t, 3> BiclopsHead::ToCounts(const device::HeadJoints& target) const {
  const double q[3] = {target.pan, target.tilt, target.verge};
  std::array<std::int32_t, 3> counts{};
  for (int a = 0; a < 3; ++a) {
    const double c = q[a] * options_.axes[Index(a)].counts_per_rad;
    counts[Index(a)] = static_cast<std::int32_t>(std::llround(std::clamp(c, -2.1e9, 2.1e9)));
  }
  return counts;
}

// ---------------------------------------------------------------------------------------------
// Link level

void BiclopsHead::BeginCall() {
  call_start_ = Clock::now();
  silent_ = false;
}

double BiclopsHead::SilenceLeft() const {
  const Clock::time_point since = std::max(call_start_, last_rx_);
  return options_.silence_timeout_s - Seconds(Clock::now() - since);
}

Status BiclopsHead::ReadLink(std::span<std::uint8_t> buf, double timeout_s, std::size_t* n) {
  *n = 0;
  const double left = SilenceLeft();
  if (left <= 0.0) {
    silent_ = true;
    return Status::kTimeout;
  }
  const Status s = link_->Read(buf, std::clamp(timeout_s, 0.0, left), n);
  if (s == Status::kOk && *n > 0) {
    last_rx_ = Clock::now();
    return Status::kOk;
  }
  if (s == Status::kDisconnected) return s;
  if (SilenceLeft() <= 0.0) silent_ = true;
  return Status::kTimeout;
}

Status BiclopsHead::Drain(double quiet_s) {
  std::uint8_t buf[64];
  const Clock::time_point give_up = Clock::now() + std::chrono::milliseconds(200);
  for (;;) {
    std::size_t n = 0;
    const Status s = ReadLink(buf, quiet_s, &n);
    if (s == Status::kDisconnected) return s;
    if (s != Status::kOk || Clock::now() > give_up) break;
  }
  link_->Discard();
  return Status::kOk;
}

Status BiclopsHead::Exchange(const pmd::Command& command, int result_words, pmd::Reply* reply) {
  ++counters_.exchanges;
  link_->Discard();  // whatever came unasked belongs to no command of ours
  const std::vector<std::uint8_t> bytes = pmd::Encode(command);
  Status s = link_->Write(bytes);
  if (s != Status::kOk) return s;
  decoder_.Expect(result_words);
  const Clock::time_point sent = Clock::now();
  const Clock::time_point deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(
                         std::chrono::duration<double>(options_.reply_timeout_s));
  std::uint8_t buf[16];
  for (;;) {
    const double left = Seconds(deadline - Clock::now());
    if (left <= 0.0 || silent_) {
      ++counters_.timeouts;
      return Status::kTimeout;
    }
    std::size_t n = 0;
    s = ReadLink(buf, left, &n);
    if (s == Status::kDisconnected) return s;
    if (s != Status::kOk) continue;
    for (std::size_t i = 0; i < n; ++i) {
      const pmd::ReplyDecoder::Result r = decoder_.Push(buf[i]);
      if (r == pmd::ReplyDecoder::Result::kNeedMore) continue;
      if (r == pmd::ReplyDecoder::Result::kGarbled || i + 1 < n) {
        ++counters_.garbled;  // a bad sum, or more bytes than the reply has: misaligned
        return Status::kBadReply;
      }
      *reply = decoder_.reply();
      if (reply->status != pmd::status::kOk) ++counters_.error_replies;
      const double rtt = Seconds(Clock::now() - sent);
      rtt_s_ = rtt_s_ > 0.0 ? 0.9 * rtt_s_ + 0.1 * rtt : rtt;
      return Status::kOk;
    }
  }
}

Status BiclopsHead::Resync() {
  // TRACLabs PMDSerial::ReSync / C-Motion PMDSerial_Sync: in point-to-point mode the chip has no
  // timeout, so a packet cut short waits for its missing bytes. Single 0x00 bytes complete it
  // (a 0x00 cannot make a wrong packet's sum right: it is answered with a checksum error) or,
  // when nothing was pending, make up a NoOperation (00 00 00 00). The first answer means the
  // chip is between packets.
  //
  // The check that follows is a GetVersion, not the all-zero NoOperation libPMD sends: a zero
  // sent after an answer we missed (a late answer) stays pending in the chip, and up to three
  // such zeros would turn a NoOperation check into a NoOperation that answers "00 00", leaving
  // the next command misframed. Shifted by one, two or three zeros a GetVersion (00 71 00 8F)
  // gives a checksum error, an unknown opcode or a 2-byte answer instead of 6: always caught.
  ++counters_.resyncs;
  const std::uint8_t zero = 0x00;
  const double wait = ZeroWait();
  // Rounds without an answer go on until the line has been silent too long (a cut cable is a
  // timeout); answered rounds that do not end in sync are limited.
  for (int answered_rounds = 0; answered_rounds < 8;) {
    Status s = Drain(wait);
    if (s == Status::kDisconnected) return s;
    if (silent_) return Status::kTimeout;
    bool answered = false;
    for (int k = 0; k < 8 && !answered; ++k) {
      s = link_->Write(std::span<const std::uint8_t>(&zero, 1));
      if (s != Status::kOk) return s;
      std::uint8_t buf[16];
      std::size_t n = 0;
      s = ReadLink(buf, wait, &n);
      if (s == Status::kDisconnected) return s;
      if (s == Status::kOk) answered = true;
      if (silent_) return Status::kTimeout;
    }
    if (!answered) continue;
    ++answered_rounds;
    s = Drain(wait);
    if (s == Status::kDisconnected) return s;
    pmd::Reply reply;
    s = Exchange(pmd::Simple(0, pmd::op::kGetVersion), 2, &reply);
    if (s == Status::kDisconnected) return s;
    const bool version_ok =
        !initialized_ || (reply.words[0] == version_chip_ && reply.words[1] == version_software_);
    if (s == Status::kOk && reply.status == pmd::status::kOk && version_ok) {
      need_sync_ = false;
      return Status::kOk;
    }
    if (silent_) return Status::kTimeout;
  }
  return silent_ ? Status::kTimeout : Status::kBadReply;
}

double BiclopsHead::ZeroWait() const {
  // Four round trips of the link, at least 3 ms, at most the configured wait: a pty answers in
  // a fraction of a millisecond, a 9600-baud line behind a USB adapter in 5-20 ms.
  return std::clamp(4.0 * rtt_s_, 0.003, options_.resync_byte_timeout_s);
}

Status BiclopsHead::SyncIfNeeded() {
  if (!need_sync_) return Status::kOk;
  return Resync();
}

Status BiclopsHead::Fail(Status s) {
  if (s == Status::kOk) return s;
  need_sync_ = true;
  if (s == Status::kDisconnected) {
    // The port went away: the chip may have been power-cycled meanwhile. Everything the driver
    // knows of its registers is read again before it is relied on.
    ++counters_.disconnects;
    initialized_ = false;
    for (auto& axis : reg_) axis.fill(Known{});
    active_target_.fill(Known{});
    at_rest_.fill(false);
  }
  return s;
}

// ---------------------------------------------------------------------------------------------
// Register level

Status BiclopsHead::Query(int axis, std::uint8_t opcode, int result_words, pmd::Reply* reply) {
  // Get* commands have no side effects: they are simply asked again until a clean reply.
  Status last = Status::kTimeout;
  for (int attempt = 0; attempt <= options_.max_resends; ++attempt) {
    Status s = SyncIfNeeded();
    if (s != Status::kOk) return s;
    s = Exchange(pmd::Simple(static_cast<std::uint8_t>(axis), opcode), result_words, reply);
    if (s == Status::kDisconnected) return s;
    if (s == Status::kOk && reply->status == pmd::status::kOk) return Status::kOk;
    // A non-zero status on a Get may be a corrupted reply (a status byte that happens to match
    // the sum): resynchronise and ask again; a chip that keeps refusing is reported.
    last = s == Status::kOk ? Status::kRejected : s;
    need_sync_ = true;
    if (silent_) return Status::kTimeout;
  }
  return last;
}

Status BiclopsHead::ReadRegister(int axis, Register r, std::int64_t* value) {
  pmd::Reply reply;
  const Status s = Query(axis, kGetOpcode[r], kGetWords[r], &reply);
  if (s != Status::kOk) return s;
  if (r == kAcceleration) {
    *value = pmd::JoinLong(reply.words[0], reply.words[1]);  // unsigned
  } else {
    *value = pmd::ReplyLong(reply);
  }
  return Status::kOk;
}

Status BiclopsHead::WriteRegister(int axis, Register r, std::int64_t value) {
  Known& known = reg_[Index(axis)][r];
  if (!known.known) {
    const Status s = ReadRegister(axis, r, &known.value);
    if (s != Status::kOk) return s;
    known.known = true;
  }
  // Sent only when it changes the register: so a read-back tells whether it was executed.
  if (known.value == value) return Status::kOk;
  const std::int64_t before = known.value;
  pmd::Command command;
  const auto a = static_cast<std::uint8_t>(axis);
  switch (r) {
    case kPosition:
      command = pmd::SetPosition(a, static_cast<std::int32_t>(value));
      break;
    case kVelocity:
      command = pmd::SetVelocity(a, static_cast<std::int32_t>(value));
      break;
    case kAcceleration:
      command = pmd::SetAcceleration(a, static_cast<std::uint32_t>(value));
      break;
    default:
      command = pmd::SetProfileMode(a, static_cast<std::uint16_t>(value));
      break;
  }
  for (int attempt = 0; attempt <= options_.max_resends; ++attempt) {
    Status s = SyncIfNeeded();
    if (s != Status::kOk) return s;
    pmd::Reply reply;
    s = Exchange(command, 0, &reply);
    if (s == Status::kOk && reply.status == pmd::status::kOk) {
      known.value = value;
      return Status::kOk;
    }
    if (s == Status::kOk) {
      // The chip refused the packet: not executed. Misframed packets are sent again.
      need_sync_ = true;
      if (!pmd::StatusNeedsResync(reply.status)) return Status::kRejected;
      ++counters_.resends;
      continue;
    }
    // Lost or garbled reply: executed or not? Resynchronise and read the register back.
    known.known = false;
    need_sync_ = true;
    if (s == Status::kDisconnected) return s;
    ++counters_.readbacks;
    std::int64_t now = 0;
    s = ReadRegister(axis, r, &now);
    if (s != Status::kOk) return s;
    known = {true, now};
    if (now == value) return Status::kOk;         // executed, once
    if (now != before) return Status::kBadReply;  // changed by something else
    ++counters_.resends;                          // not executed: safe to send again
  }
  return Status::kBadReply;
}

Status BiclopsHead::ResolveActive(int axis) {
  // A trapezoidal profile ends exactly on its active target: wait for the end and read it.
  const Clock::time_point give_up =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(
                         std::chrono::duration<double>(longest_move_s_ + options_.settle_margin_s));
  for (;;) {
    pmd::Reply reply;
    Status s = Query(axis, pmd::op::kGetActivityStatus, 1, &reply);
    if (s != Status::kOk) return s;
    if ((reply.words[0] & pmd::activity::kInMotion) == 0) {
      s = Query(axis, pmd::op::kGetCommandedPosition, 2, &reply);
      if (s != Status::kOk) return s;
      active_target_[Index(axis)] = {true, pmd::ReplyLong(reply)};
      at_rest_[Index(axis)] = true;
      return Status::kOk;
    }
    if (Clock::now() > give_up) return Status::kTimeout;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

Status BiclopsHead::UpdateTo(int axis, std::int64_t target) {
  Known& active = active_target_[Index(axis)];
  if (!active.known) {
    const Status s = ResolveActive(axis);
    if (s != Status::kOk) return s;
  }
  if (active.value == target) return Status::kOk;
  const std::int64_t before = active.value;
  for (int attempt = 0; attempt <= options_.max_resends; ++attempt) {
    Status s = SyncIfNeeded();
    if (s != Status::kOk) return s;
    const bool from_rest = at_rest_[Index(axis)];
    pmd::Reply reply;
    s = Exchange(pmd::Update(static_cast<std::uint8_t>(axis)), 0, &reply);
    if (s == Status::kOk && reply.status == pmd::status::kOk) {
      active.value = target;
      at_rest_[Index(axis)] = false;
      return Status::kOk;
    }
    if (s == Status::kOk) {
      need_sync_ = true;
      if (!pmd::StatusNeedsResync(reply.status)) return Status::kRejected;
      ++counters_.resends;
      continue;
    }
    // Lost or garbled reply: did the Update happen?
    active.known = false;
    at_rest_[Index(axis)] = false;
    need_sync_ = true;
    if (s == Status::kDisconnected) return s;
    ++counters_.update_checks;
    pmd::Reply status_reply;
    s = Query(axis, pmd::op::kGetActivityStatus, 1, &status_reply);
    if (s != Status::kOk) return s;
    if (from_rest && (status_reply.words[0] & pmd::activity::kInMotion) != 0) {
      active = {true, target};  // only an Update starts a profile on an axis at rest
      return Status::kOk;
    }
    s = ResolveActive(axis);  // the profile ends on the new target or the old one
    if (s != Status::kOk) return s;
    if (active.value == target) return Status::kOk;
    if (active.value != before) return Status::kBadReply;
    ++counters_.resends;
  }
  return Status::kBadReply;
}

// ---------------------------------------------------------------------------------------------
// Device level

Status BiclopsHead::EnsureInitialized() {
  if (initialized_) return Status::kOk;
  pmd::Reply reply;
  Status s = Query(0, pmd::op::kGetVersion, 2, &reply);
  if (s != Status::kOk) return s;
  version_chip_ = reply.words[0];
  version_software_ = reply.words[1];
  // GetVersion's chip word: family << 12 | motor type << 8 | axes << 4 | special (libPMD
  // PMD::GetVersion). Pan, tilt and verge need three axes.
  if (((version_chip_ >> 4) & 0xF) < 3) return Status::kRejected;
  // The cycle time scales velocities and accelerations; libPMD reads it from the chip too
  // (PMDController::ConfigureController, GetSampleTime, microseconds).
  s = Query(0, pmd::op::kGetSampleTime, 1, &reply);
  if (s != Status::kOk) return s;
  if (reply.words[0] == 0) return Status::kBadReply;
  cycle_s_ = reply.words[0] * 1e-6;
  for (int a = 0; a < 3; ++a) {
    const BiclopsAxisOptions& x = options_.axes[Index(a)];
    const double cpr = std::abs(x.counts_per_rad);
    // libPMD PMDAxisControl::CountsVelToPMD / CountsAccToPMD.
    const double v = x.max_speed_rad_s * cpr * cycle_s_ * pmd::kVelocityScale;
    const double acc = x.max_accel_rad_s2 * cpr * cycle_s_ * cycle_s_ * pmd::kAccelerationScale;
    velocity_reg_[Index(a)] = static_cast<std::int32_t>(
        std::clamp<double>(std::llround(v), 1.0, std::numeric_limits<std::int32_t>::max()));
    accel_reg_[Index(a)] = static_cast<std::uint32_t>(
        std::clamp<double>(std::llround(acc), 1.0, std::numeric_limits<std::uint32_t>::max()));
  }
  for (int a = 0; a < 3; ++a) {
    s = WriteRegister(a, kProfileMode, pmd::kTrapezoidalProfile);
    if (s == Status::kOk) s = WriteRegister(a, kVelocity, velocity_reg_[Index(a)]);
    if (s == Status::kOk) s = WriteRegister(a, kAcceleration, accel_reg_[Index(a)]);
    if (s != Status::kOk) return s;
  }
  initialized_ = true;
  return Status::kOk;
}

Status BiclopsHead::Initialize() {
  std::lock_guard<std::mutex> lock(mu_);
  BeginCall();
  return Fail(EnsureInitialized());
}

Status BiclopsHead::Read(device::HeadState* state) {
  std::lock_guard<std::mutex> lock(mu_);
  BeginCall();
  const Clock::time_point t0 = Clock::now();
  double q[3];
  bool moving = false;
  for (int a = 0; a < 3; ++a) {
    // The status first, then the position: an axis seen at rest stays there (only this driver
    // starts profiles), so the position read after it is where the axis stopped. The other way
    // round, a profile that ends between the two replies (one 9600-baud exchange takes 10 ms)
    // reads as a head at rest short of its target.
    pmd::Reply reply;
    Status s = Query(a, pmd::op::kGetActivityStatus, 1, &reply);
    if (s != Status::kOk) return Fail(s);
    const bool in_motion = (reply.words[0] & pmd::activity::kInMotion) != 0;
    s = Query(a, pmd::op::kGetActualPosition, 2, &reply);
    if (s != Status::kOk) return Fail(s);
    q[a] = static_cast<double>(pmd::ReplyLong(reply)) / options_.axes[Index(a)].counts_per_rad;
    at_rest_[Index(a)] = !in_motion;
    moving = moving || in_motion;
  }
  const Clock::time_point t1 = Clock::now();
  state->t_s = Seconds(t0 - created_) + 0.5 * Seconds(t1 - t0);
  state->q = {q[0], q[1], q[2]};
  state->moving = moving;
  return Status::kOk;
}

Status BiclopsHead::MoveTo(const device::HeadJoints& target) {
  std::lock_guard<std::mutex> lock(mu_);
  BeginCall();
  const double q[3] = {target.pan, target.tilt, target.verge};
  for (int a = 0; a < 3; ++a) {
    const BiclopsAxisOptions& x = options_.axes[Index(a)];
    if (!std::isfinite(q[a]) || q[a] < x.min_rad - 1e-9 || q[a] > x.max_rad + 1e-9) {
      return Status::kRejected;  // nothing sent
    }
  }
  Status s = EnsureInitialized();
  if (s != Status::kOk) return Fail(s);
  const std::array<std::int32_t, 3> counts = ToCounts(target);
  bool change[3];
  for (int a = 0; a < 3; ++a) {
    if (!active_target_[Index(a)].known) {
      s = ResolveActive(a);
      if (s != Status::kOk) return Fail(s);
    }
    change[a] = active_target_[Index(a)].value != counts[Index(a)];
  }
  // All targets first, then the Updates, so that the axes start together.
  for (int a = 0; a < 3; ++a) {
    if (!change[a]) continue;
    s = WriteRegister(a, kPosition, counts[Index(a)]);
    if (s != Status::kOk) return Fail(s);
  }
  for (int a = 0; a < 3; ++a) {
    if (!change[a]) continue;
    s = UpdateTo(a, counts[Index(a)]);
    if (s != Status::kOk) return Fail(s);
  }
  return Status::kOk;
}

Status BiclopsHead::ResetChip() {
  std::lock_guard<std::mutex> lock(mu_);
  BeginCall();
  // The velocity registers hold non-zero values after initialisation; Reset clears them.
  Status s = EnsureInitialized();
  if (s != Status::kOk) return Fail(s);
  for (int attempt = 0; attempt <= options_.max_resends; ++attempt) {
    s = SyncIfNeeded();
    if (s != Status::kOk) return Fail(s);
    link_->Discard();
    s = link_->Write(pmd::Encode(pmd::Reset()));
    if (s != Status::kOk) return Fail(s);
    // libPMD sends Reset without reading a reply: the chip answers one only to refuse it.
    std::uint8_t buf[16];
    std::size_t n = 0;
    s = ReadLink(buf, 0.05, &n);
    if (s == Status::kDisconnected) return Fail(s);
    need_sync_ = true;
    if (s == Status::kOk) {
      ++counters_.resends;  // refused (a damaged packet): not executed
      continue;
    }
    ++counters_.readbacks;
    std::int64_t velocity = 0;
    s = ReadRegister(0, kVelocity, &velocity);
    if (s != Status::kOk) return Fail(s);
    if (velocity == 0) {
      // Reset: every register is at its power-up value; read them again before use.
      initialized_ = false;
      for (auto& axis : reg_) axis.fill(Known{});
      active_target_.fill(Known{});
      at_rest_.fill(false);
      return Status::kOk;
    }
    if (velocity != velocity_reg_[0]) return Fail(Status::kBadReply);
    ++counters_.resends;
  }
  return Fail(Status::kBadReply);
}

}  // namespace hgrasp::drivers
