#include "biclops/biclops_head.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <thread>
#include <utility>

#include "common/error.h"

namespace hgrasp::drivers {

namespace {

using device::Status;
constexpr double kPi = 3.14159265358979323846;
constexpr const char* kAxisNames[3] = {"pan", "tilt", "verge"};

double Deg(double deg) { return deg * kPi / 180.0; }

double Seconds(Clock::Duration d) { return Clock::ToSeconds(d); }

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
  // Homing (BiclopsDefault.cfg: pan [homing profile] 50 deg/s, 10 deg/s^2, homeSensorWidth 50
  // counts, ActiveLow; tilt 15 deg/s, 20 deg/s^2, 860 counts, ActiveHigh; verge: ours).
  o.axes[0].homing_speed_rad_s = Deg(50.0);
  o.axes[0].homing_accel_rad_s2 = Deg(10.0);
  o.axes[0].home_sensor_width_rad = 50.0 / cpr;
  o.axes[0].home_active_low = true;
  o.axes[1].homing_speed_rad_s = Deg(15.0);
  o.axes[1].homing_accel_rad_s2 = Deg(20.0);
  o.axes[1].home_sensor_width_rad = 860.0 / cpr;
  o.axes[1].home_active_low = false;
  o.axes[2].homing_speed_rad_s = Deg(15.0);
  o.axes[2].homing_accel_rad_s2 = Deg(20.0);
  o.axes[2].home_sensor_width_rad = 300.0 / cpr;
  o.axes[2].home_active_low = true;
  // Run servo filters (BiclopsDefault.cfg [run servo filter]); verge as tilt (ours).
  o.axes[1].filter_kp = o.axes[2].filter_kp = 200;
  o.axes[1].filter_kd = o.axes[2].filter_kd = 50;
  o.axes[1].filter_ki = o.axes[2].filter_ki = 250;
  return o;
}

BiclopsHead::BiclopsHead(std::unique_ptr<ByteLink> link, const BiclopsOptions& options,
                         Clock& clock)
    : link_(std::move(link)), options_(options), clock_(&clock) {
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
    Require(std::isfinite(x.homing_speed_rad_s) && x.homing_speed_rad_s > 0.0,
            axis + "homing_speed_rad_s", x.homing_speed_rad_s, "a positive speed (rad/s)");
    Require(std::isfinite(x.homing_accel_rad_s2) && x.homing_accel_rad_s2 > 0.0,
            axis + "homing_accel_rad_s2", x.homing_accel_rad_s2,
            "a positive acceleration (rad/s^2)");
    Require(
        std::isfinite(x.index_spacing_rad) && std::abs(x.index_spacing_rad * x.counts_per_rad) >= 4,
        axis + "index_spacing_rad", x.index_spacing_rad,
        "a positive angle (rad) of at least 4 encoder counts");
    Require(std::isfinite(x.home_sensor_width_rad) && x.home_sensor_width_rad > 0.0 &&
                x.home_sensor_width_rad < x.index_spacing_rad,
            axis + "home_sensor_width_rad", x.home_sensor_width_rad,
            "a positive angle (rad) below index_spacing_rad");
    Require(std::isfinite(x.home_offset_rad) && std::abs(x.home_offset_rad) < x.index_spacing_rad,
            axis + "home_offset_rad", x.home_offset_rad,
            "a finite angle (rad) within one index spacing");
    const std::pair<const char*, std::pair<int, std::pair<long, long>>> gains[] = {
        {"filter_kp", {x.filter_kp, {0, 32767}}},
        {"filter_kd", {x.filter_kd, {0, 32767}}},
        {"filter_ki", {x.filter_ki, {0, 32767}}},
        {"filter_kvff", {x.filter_kvff, {0, 32767}}},
        {"filter_kaff", {x.filter_kaff, {0, 32767}}},
        {"filter_kout", {x.filter_kout, {0, 65535}}},
        {"filter_integration_limit", {x.filter_integration_limit, {0, 2147483647L}}},
        {"filter_motor_limit", {x.filter_motor_limit, {0, 32767}}},
        {"filter_motor_bias", {x.filter_motor_bias, {-32768, 32767}}},
        {"output_mode", {x.output_mode, {0, 2}}},
    };
    for (const auto& [name, v] : gains) {
      Require(v.first >= v.second.first && v.first <= v.second.second, axis + name, v.first,
              "an integer in " + std::to_string(v.second.first) + ".." +
                  std::to_string(v.second.second) + " (PMD chip units)");
    }
    Require(std::isfinite(x.position_error_limit_rad) && x.position_error_limit_rad >= 0.0 &&
                x.position_error_limit_rad * std::abs(x.counts_per_rad) < 2.0e9,
            axis + "position_error_limit_rad", x.position_error_limit_rad,
            "an angle (rad) of 0 or more that fits the chip's 32-bit register");
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
  Require(options_.stop_settle_s > 0.0, "stop_settle_s", options_.stop_settle_s,
          "a positive time (s)");
  created_ = call_start_ = last_rx_ = clock_->Now();
  silence_limit_s_ = options_.silence_timeout_s;
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
  call_start_ = clock_->Now();
  silent_ = false;
  probing_ = false;
  silence_limit_s_ = options_.silence_timeout_s;
}

double BiclopsHead::SilenceLeft() const {
  const Clock::TimePoint since = std::max(call_start_, last_rx_);
  // In whole clock ticks: a remainder below one tick would be a wait that never ends.
  return Seconds(Clock::FromSeconds(silence_limit_s_) - (clock_->Now() - since));
}

void BiclopsHead::SilenceReached() {
  if (probing_ || line_probes_left_ <= 0) {
    silent_ = true;  // the probe went unanswered too, or none is granted: the line is lost
    return;
  }
  // During homing, a silence as long as the limit is a dropout that has ended or a cut cable:
  // one resynchronisation round (a drain and up to a packet's length of zeros, each awaited)
  // tells which. The exchange in flight ends as a lost reply (Exchange watches line_probes_),
  // which every step already resolves without executing anything twice.
  --line_probes_left_;
  ++line_probes_;
  ++counters_.line_probes;
  probing_ = true;
  need_sync_ = true;
  call_start_ = clock_->Now();
  silence_limit_s_ = static_cast<double>(pmd::kMaxCommandBytes + 2) * ZeroWait();
}

Status BiclopsHead::ReadLink(std::span<std::uint8_t> buf, double timeout_s, std::size_t* n) {
  *n = 0;
  const double left = SilenceLeft();
  if (left <= 0.0) {
    SilenceReached();
    return Status::kTimeout;
  }
  const Status s = link_->Read(buf, std::clamp(timeout_s, 0.0, left), n);
  if (s == Status::kOk && *n > 0) {
    last_rx_ = clock_->Now();
    if (probing_) {  // the chip answered the probe: the full limit again from this byte
      probing_ = false;
      silence_limit_s_ = options_.silence_timeout_s;
    }
    return Status::kOk;
  }
  if (s == Status::kDisconnected) return s;
  if (SilenceLeft() <= 0.0) SilenceReached();
  return Status::kTimeout;
}

Status BiclopsHead::Drain(double quiet_s) {
  std::uint8_t buf[64];
  const Clock::TimePoint give_up = clock_->Now() + std::chrono::milliseconds(200);
  for (;;) {
    std::size_t n = 0;
    const Status s = ReadLink(buf, quiet_s, &n);
    if (s == Status::kDisconnected) return s;
    if (s != Status::kOk || clock_->Now() > give_up) break;
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
  const Clock::TimePoint sent = clock_->Now();
  const Clock::TimePoint deadline = clock_->Now() + Clock::FromSeconds(options_.reply_timeout_s);
  const std::uint64_t probes = line_probes_;
  std::uint8_t buf[16];
  for (;;) {
    const double left = Seconds(deadline - clock_->Now());
    // A line probe begun meanwhile (SilenceReached) needs its time for the resynchronisation.
    if (left <= 0.0 || silent_ || line_probes_ != probes) {
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
      if (reply->status != pmd::status::kOk) {
        ++counters_.error_replies;
      } else {
        Record(command, true);  // status 0: the chip executed it
      }
      const double rtt = Seconds(clock_->Now() - sent);
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
  // Rounds without an answer go on until the line has been silent too long (a cut cable is a
  // timeout); answered rounds that do not end in sync are limited.
  for (int answered_rounds = 0; answered_rounds < 8;) {
    // The wait after each zero, from the round trips measured so far (the check's exchange
    // measures one each round). Taken once for the whole resync, a driver's first one waited
    // 3 ms throughout (no round trip measured yet): on a 9600-baud line a zero and the first
    // byte of its answer take 2.1 ms on the wire, so with a millisecond of latency the answer
    // to the fourth zero came after a fifth had gone, which stayed pending in the chip and
    // misframed every check (a checksum error) until the resync gave up.
    const double wait = ZeroWait();
    Status s = Drain(wait);
    if (s == Status::kDisconnected) return s;
    if (silent_) return Status::kTimeout;
    bool answered = false;
    // At most one packet's length of zeros completes whatever the chip holds.
    for (std::size_t k = 0; k < pmd::kMaxCommandBytes && !answered; ++k) {
      s = link_->Write(std::span<const std::uint8_t>(&zero, 1));
      if (s != Status::kOk) return s;
      const Clock::TimePoint sent = clock_->Now();
      std::uint8_t buf[16];
      std::size_t n = 0;
      s = ReadLink(buf, wait, &n);
      if (s == Status::kDisconnected) return s;
      if (s == Status::kOk) {
        answered = true;
        const double rtt = Seconds(clock_->Now() - sent);
        zero_rtt_s_ = zero_rtt_s_ > 0.0 ? 0.9 * zero_rtt_s_ + 0.1 * rtt : rtt;
      }
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
  // a fraction of a millisecond, a 9600-baud line behind a USB adapter in 5-20 ms. Once a zero's
  // own answer has been timed, three of those: a packet's round trip carries its bytes (10 ms
  // of a GetVersion at 9600 baud), a zero's only two, and four packet round trips (clamped to
  // 20 ms) made a round of ten zeros last 0.21 s. A 200 ms dropout that ended late in a round
  // then left the chip silent for 0.37 s (reply wait, drain, a round unanswered, drain, one
  // zero), within a few ms of the 0.4 s silence that reports a cut cable. Never less than one
  // packet's round trip, which is longer than a zero's: a late answer to an earlier zero, timed
  // as this one's, must not make the wait too short (a zero sent before the answer came stays
  // pending and misframes the check).
  const double per_zero = zero_rtt_s_ > 0.0 ? std::max(3.0 * zero_rtt_s_, rtt_s_) : 4.0 * rtt_s_;
  return std::clamp(per_zero, 0.003, options_.resync_byte_timeout_s);
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
    rest_known_.fill(false);
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
    const pmd::Command get = pmd::Simple(static_cast<std::uint8_t>(axis), opcode);
    s = Exchange(get, result_words, reply);
    if (s == Status::kOk && reply->status == pmd::status::kOk) return Status::kOk;
    // A Get with a side effect (GetCaptureValue) may have run: it is asked again all the same.
    Record(get, false);
    if (s == Status::kDisconnected) return s;
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
    std::int64_t now = 0;
    if (s != Status::kDisconnected) {
      ++counters_.readbacks;
      s = ReadRegister(axis, r, &now);
    }
    if (s != Status::kOk) {
      Record(command, false);  // its outcome unknown
      return s;
    }
    known = {true, now};
    if (now == value) {
      Record(command, true);  // executed, once
      return Status::kOk;
    }
    if (now != before) {
      Record(command, false);
      return Status::kBadReply;  // changed by something else
    }
    ++counters_.resends;  // not executed: safe to send again
  }
  return Status::kBadReply;
}

Status BiclopsHead::ResolveActive(int axis) {
  // A trapezoidal profile ends exactly on its active target: wait for the end and read it.
  const Clock::TimePoint give_up =
      clock_->Now() + Clock::FromSeconds(longest_move_s_ + options_.settle_margin_s);
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
    if (clock_->Now() > give_up) return Status::kTimeout;
    clock_->SleepFor(std::chrono::milliseconds(5));
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
      rest_known_[Index(axis)] = false;
      return Status::kOk;
    }
    if (s == Status::kOk) {
      need_sync_ = true;
      if (!pmd::StatusNeedsResync(reply.status)) return Status::kRejected;
      ++counters_.resends;
      continue;
    }
    // Lost or garbled reply: did the Update happen?
    const pmd::Command update = pmd::Update(static_cast<std::uint8_t>(axis));
    active.known = false;
    at_rest_[Index(axis)] = false;
    rest_known_[Index(axis)] = false;
    need_sync_ = true;
    if (s == Status::kDisconnected) {
      Record(update, false);
      return s;
    }
    ++counters_.update_checks;
    pmd::Reply status_reply;
    s = Query(axis, pmd::op::kGetActivityStatus, 1, &status_reply);
    if (s == Status::kOk && from_rest && (status_reply.words[0] & pmd::activity::kInMotion) != 0) {
      active = {true, target};  // only an Update starts a profile on an axis at rest
      Record(update, true);
      return Status::kOk;
    }
    if (s == Status::kOk) s = ResolveActive(axis);  // it ends on the new target or the old one
    if (s != Status::kOk) {
      Record(update, false);
      return s;
    }
    if (active.value == target) {
      Record(update, true);
      return Status::kOk;
    }
    if (active.value != before) {
      Record(update, false);
      return Status::kBadReply;
    }
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
  const Clock::TimePoint t0 = clock_->Now();
  double q[3];
  bool moving = false;
  for (int a = 0; a < 3; ++a) {
    // An axis seen at rest with no profile started since stays where it was read (only this
    // driver starts profiles, and the chip's servo holds the position): nothing to ask. A head
    // at rest reads at no cost, which keeps a 9600-baud line (six exchanges, 56 ms, for a full
    // reading) from limiting the cameras' frame rate to half of 25 frames/s.
    if (at_rest_[Index(a)] && rest_known_[Index(a)]) {
      q[a] = rest_q_[Index(a)];
      continue;
    }
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
    rest_known_[Index(a)] = !in_motion;
    rest_q_[Index(a)] = q[a];
    moving = moving || in_motion;
  }
  const Clock::TimePoint t1 = clock_->Now();
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

// ---------------------------------------------------------------------------------------------
// Configuration and homing (PROTOCOL.md, "Homing")

bool BiclopsHead::homed() const {
  std::lock_guard<std::mutex> lock(mu_);
  return homed_;
}

std::string BiclopsHead::last_error() const {
  std::lock_guard<std::mutex> lock(mu_);
  return last_error_;
}

Status BiclopsHead::Failed(int axis, const std::string& step, Status s) {
  if (s == Status::kOk) return s;
  last_error_ = std::string("biclops ") + kAxisNames[axis] + ": " + step + ": " +
                std::string(device::ToString(s));
  return s;
}

void BiclopsHead::Record(const pmd::Command& command, bool executed) {
  const pmd::OpcodeInfo* info = pmd::FindOpcode(command.opcode);
  if (info == nullptr || !info->changes_state) return;
  if (executed) {
    command_log_.Executed(command);
  } else {
    command_log_.Unconfirmed(command);
  }
}

Status BiclopsHead::Command(const pmd::Command& command) {
  // Configuration Set*s write the same value however often they arrive: a lost or garbled
  // reply is answered by sending the command again.
  Status last = Status::kBadReply;
  for (int attempt = 0; attempt <= options_.max_resends; ++attempt) {
    Status s = SyncIfNeeded();
    if (s != Status::kOk) return s;
    pmd::Reply reply;
    s = Exchange(command, 0, &reply);
    // Lost or garbled: the chip may have executed it; it is sent again without asking.
    if (s != Status::kOk) Record(command, false);
    if (s == Status::kDisconnected) return s;
    if (s == Status::kOk && reply.status == pmd::status::kOk) return Status::kOk;
    need_sync_ = true;
    if (s == Status::kOk && !pmd::StatusNeedsResync(reply.status)) return Status::kRejected;
    last = s == Status::kOk ? Status::kRejected : s;
    if (silent_) return Status::kTimeout;
    ++counters_.resends;
  }
  return last;
}

Status BiclopsHead::ConfigureAxis(int axis) {
  // libPMD PMDAxisControl::ConfigureHardware, for a brushed axis without limit sensors, then
  // SetFilter (the run filter) and the homing profile. Every command here is idempotent.
  const BiclopsAxisOptions& x = options_.axes[Index(axis)];
  const auto a = static_cast<std::uint8_t>(axis);
  const double cpr = std::abs(x.counts_per_rad);
  // The axis' current position, so that the filter's Update (which also makes the buffered
  // profile active) does not move it.
  pmd::Reply reply;
  Status s = Query(axis, pmd::op::kGetActualPosition, 2, &reply);
  if (s != Status::kOk) return Failed(axis, "GetActualPosition", s);
  const auto here = static_cast<std::int32_t>(pmd::ReplyLong(reply));
  // The amplifier enable (axis-out pin, driven through its signal sense: libPMD EnableAmp),
  // the home input's sense (so that its status bit reads 1 on the sensor), limit inputs as
  // they come (active low), the motor's direction as the encoder's.
  std::uint16_t sense = 0;
  if (x.home_active_low) sense |= pmd::signal::kHome;
  if (x.amp_active_low) sense |= pmd::signal::kAxisOut;
  const auto error_limit =
      static_cast<std::uint32_t>(std::llround(x.position_error_limit_rad * cpr));
  const std::pair<const char*, pmd::Command> steps[] = {
      {"SetMotorMode off", pmd::WithWord(a, pmd::op::kSetMotorMode, pmd::kMotorOff)},
      {"SetAxisOutSource", pmd::WithWord(a, pmd::op::kSetAxisOutSource, a)},
      {"SetLimitSwitchMode", pmd::WithWord(a, pmd::op::kSetLimitSwitchMode, 0)},
      {"SetSignalSense", pmd::WithWord(a, pmd::op::kSetSignalSense, sense)},
      {"ResetEventStatus", pmd::WithWord(a, pmd::op::kResetEventStatus, 0)},
      {"SetOutputMode",
       pmd::WithWord(a, pmd::op::kSetOutputMode, static_cast<std::uint16_t>(x.output_mode))},
      {"SetProfileMode", pmd::SetProfileMode(a, pmd::kTrapezoidalProfile)},
      {"SetAxisMode", pmd::WithWord(a, pmd::op::kSetAxisMode, 1)},
      {"SetKp", pmd::WithWord(a, pmd::op::kSetKp, static_cast<std::uint16_t>(x.filter_kp))},
      {"SetKd", pmd::WithWord(a, pmd::op::kSetKd, static_cast<std::uint16_t>(x.filter_kd))},
      {"SetKi", pmd::WithWord(a, pmd::op::kSetKi, static_cast<std::uint16_t>(x.filter_ki))},
      {"SetKvff", pmd::WithWord(a, pmd::op::kSetKvff, static_cast<std::uint16_t>(x.filter_kvff))},
      {"SetKaff", pmd::WithWord(a, pmd::op::kSetKaff, static_cast<std::uint16_t>(x.filter_kaff))},
      {"SetKout", pmd::WithWord(a, pmd::op::kSetKout, static_cast<std::uint16_t>(x.filter_kout))},
      {"SetIntegrationLimit",
       pmd::WithLong(a, pmd::op::kSetIntegrationLimit,
                     static_cast<std::uint32_t>(x.filter_integration_limit))},
      {"SetMotorLimit",
       pmd::WithWord(a, pmd::op::kSetMotorLimit, static_cast<std::uint16_t>(x.filter_motor_limit))},
      {"SetMotorBias",
       pmd::WithWord(a, pmd::op::kSetMotorBias, static_cast<std::uint16_t>(x.filter_motor_bias))},
      {"SetPositionErrorLimit", pmd::WithLong(a, pmd::op::kSetPositionErrorLimit, error_limit)},
      {"SetAutoStopMode", pmd::WithWord(a, pmd::op::kSetAutoStopMode, 0)},
      {"SetPosition", pmd::SetPosition(a, here)},
  };
  for (const auto& [name, command] : steps) {
    s = Command(command);
    if (s != Status::kOk) return Failed(axis, name, s);
  }
  // The filter takes effect at an Update (libPMD SetFilter); the motor then goes on.
  s = HomingUpdate(axis, here, /*at_target=*/true);
  if (s != Status::kOk) return Failed(axis, "Update (filter)", s);
  s = Command(pmd::WithWord(a, pmd::op::kSetMotorMode, pmd::kMotorOn));
  if (s != Status::kOk) return Failed(axis, "SetMotorMode on", s);
  return Status::kOk;
}

Status BiclopsHead::UpdateOnce(int axis, const std::function<Status(bool*, bool*)>& took) {
  const auto a = static_cast<std::uint8_t>(axis);
  for (int attempt = 0; attempt <= options_.max_resends; ++attempt) {
    Status s = SyncIfNeeded();
    if (s != Status::kOk) return s;
    pmd::Reply reply;
    s = Exchange(pmd::Update(a), 0, &reply);
    if (s == Status::kDisconnected) {
      Record(pmd::Update(a), false);
      return s;
    }
    if (s == Status::kOk && reply.status == pmd::status::kOk) return Status::kOk;
    need_sync_ = true;
    if (s == Status::kOk && !pmd::StatusNeedsResync(reply.status)) return Status::kRejected;
    if (silent_) {
      if (s != Status::kOk) Record(pmd::Update(a), false);
      return Status::kTimeout;
    }
    if (s != Status::kOk) {
      ++counters_.update_checks;
      bool executed = false, sure = true;
      s = took(&executed, &sure);
      if (s != Status::kOk) {
        Record(pmd::Update(a), false);
        return s;
      }
      if (executed) {
        Record(pmd::Update(a), sure);
        return Status::kOk;
      }
    }
    ++counters_.resends;
  }
  return Status::kBadReply;
}

Status BiclopsHead::HomingUpdate(int axis, std::int32_t target, bool at_target) {
  // Re-sending an Update of the same buffered profile aims the axis at the same target again;
  // still, it is re-sent only when the chip shows it did not take the first: not moving, no
  // motion event since the events were reset before it (a sweep that a capture breakpoint
  // stopped short of its target ends with one: without this check such an Update was taken
  // as lost and sent again, and the axis swept on to the target), and its commanded position
  // not at the target. (An axis that stood at the target already, its motor off, shows the
  // same either way: the Update is then taken as done, its execution unconfirmed.)
  const auto took = [this, axis, target, at_target](bool* executed, bool* sure) {
    pmd::Reply reply;
    Status s = Query(axis, pmd::op::kGetActivityStatus, 1, &reply);
    if (s != Status::kOk) return s;
    if ((reply.words[0] & pmd::activity::kInMotion) != 0) {
      *executed = true;
      return Status::kOk;
    }
    s = Query(axis, pmd::op::kGetEventStatus, 1, &reply);
    if (s != Status::kOk) return s;
    constexpr std::uint16_t kMotionEvents =
        pmd::event::kMotionComplete | pmd::event::kCaptureReceived | pmd::event::kBreakpoint1;
    if ((reply.words[0] & kMotionEvents) != 0) {
      *executed = true;
      return Status::kOk;
    }
    s = Query(axis, pmd::op::kGetCommandedPosition, 2, &reply);
    if (s != Status::kOk) return s;
    *executed = pmd::ReplyLong(reply) == target;
    *sure = !at_target;
    return Status::kOk;
  };
  return UpdateOnce(axis, took);
}

Status BiclopsHead::HomingMove(int axis, std::int32_t target, int capture, bool* captured,
                               std::int32_t* capture_counts) {
  // libPMD PMDAxisControl::MoveWithCaptureInterrupt: a breakpoint on the capture-received event
  // bit stops the axis smoothly at the first capture.
  const BiclopsAxisOptions& x = options_.axes[Index(axis)];
  const auto a = static_cast<std::uint8_t>(axis);
  const double cpr = std::abs(x.counts_per_rad);
  Status s;
  pmd::Reply reply;
  s = Query(axis, pmd::op::kGetActualPosition, 2, &reply);
  if (s != Status::kOk) return s;
  const double distance = std::abs(static_cast<double>(target - pmd::ReplyLong(reply)));
  if (capture >= 0) {
    s = Command(pmd::WithWord(a, pmd::op::kSetCaptureSource, static_cast<std::uint16_t>(capture)));
    if (s != Status::kOk) return s;
  }
  s = Command(pmd::WithWord(a, pmd::op::kResetEventStatus, 0));
  if (s != Status::kOk) return s;
  if (capture >= 0) {
    s = Query(axis, pmd::op::kGetCaptureValue, 2, &reply);  // re-arms the capture
    if (s != Status::kOk) return s;
    const std::uint16_t bit = pmd::event::kCaptureReceived;
    const std::uint16_t value_words[] = {0, bit, bit};  // breakpoint 1: mask, wanted state
    s = Command(pmd::WithWords(a, pmd::op::kSetBreakpointValue, value_words));
    if (s != Status::kOk) return s;
    const std::uint16_t bp_words[] = {
        0, static_cast<std::uint16_t>(a | pmd::kBreakpointSmoothStop << 4 |
                                      pmd::kBreakpointEventStatus << 8)};
    s = Command(pmd::WithWords(a, pmd::op::kSetBreakpoint, bp_words));
    if (s != Status::kOk) return s;
  }
  const double v = x.homing_speed_rad_s * cpr, acc = x.homing_accel_rad_s2 * cpr;
  const double vel_reg = std::max(1.0, std::round(v * cycle_s_ * pmd::kVelocityScale));
  // At least 2: libPMD ("V2.3 of navigator won't allow acc < 2").
  const double acc_reg =
      std::max(2.0, std::round(acc * cycle_s_ * cycle_s_ * pmd::kAccelerationScale));
  s = Command(pmd::SetVelocity(a, static_cast<std::int32_t>(vel_reg)));
  if (s == Status::kOk) s = Command(pmd::SetAcceleration(a, static_cast<std::uint32_t>(acc_reg)));
  if (s == Status::kOk) s = Command(pmd::SetPosition(a, target));
  if (s == Status::kOk) s = HomingUpdate(axis, target, /*at_target=*/distance == 0.0);
  if (s != Status::kOk) return s;
  // The sweep's duration at the registers' speed and acceleration, and a margin.
  const double v_real = vel_reg / pmd::kVelocityScale / cycle_s_;
  const double a_real = acc_reg / pmd::kAccelerationScale / (cycle_s_ * cycle_s_);
  const double expected = distance / v_real + 2.0 * v_real / a_real;
  const Clock::TimePoint give_up =
      clock_->Now() + Clock::FromSeconds(expected + options_.settle_margin_s);
  for (;;) {
    s = Query(axis, pmd::op::kGetActivityStatus, 1, &reply);
    if (s != Status::kOk) return s;
    if ((reply.words[0] & pmd::activity::kInMotion) == 0) break;
    if (StopRequested(stop_)) return Status::kInterrupted;
    if (clock_->Now() > give_up) return Status::kTimeout;
    clock_->SleepFor(std::chrono::milliseconds(10));
    BeginCall();  // a long sweep is not silence: the chip answers every poll
  }
  *captured = false;
  if (capture >= 0) {
    const std::uint16_t off[] = {0, static_cast<std::uint16_t>(a)};  // no action, disabled
    s = Command(pmd::WithWords(a, pmd::op::kSetBreakpoint, off));
    if (s != Status::kOk) return s;
    s = Query(axis, pmd::op::kGetEventStatus, 1, &reply);
    if (s != Status::kOk) return s;
    if ((reply.words[0] & pmd::event::kCaptureReceived) != 0) {
      s = Query(axis, pmd::op::kGetCaptureValue, 2, &reply);
      if (s != Status::kOk) return s;
      *captured = true;
      *capture_counts = static_cast<std::int32_t>(pmd::ReplyLong(reply));
    }
  }
  return Status::kOk;
}

Status BiclopsHead::AdjustPosition(int axis, std::int32_t delta) {
  // AdjustActualPosition shifts the counter: twice would shift it twice. The axis is at rest,
  // so a lost reply is resolved by reading the position: shifted or not.
  const auto a = static_cast<std::uint8_t>(axis);
  pmd::Reply reply;
  Status s = Query(axis, pmd::op::kGetActualPosition, 2, &reply);
  if (s != Status::kOk) return s;
  const std::int64_t before = pmd::ReplyLong(reply);
  const pmd::Command adjust =
      pmd::WithLong(a, pmd::op::kAdjustActualPosition, static_cast<std::uint32_t>(delta));
  for (int attempt = 0; attempt <= options_.max_resends; ++attempt) {
    s = SyncIfNeeded();
    if (s != Status::kOk) return s;
    s = Exchange(adjust, 0, &reply);
    if (s == Status::kDisconnected) {
      Record(adjust, false);  // its outcome unknown
      return s;
    }
    if (s == Status::kOk && reply.status == pmd::status::kOk) return Status::kOk;
    need_sync_ = true;
    if (s == Status::kOk && !pmd::StatusNeedsResync(reply.status)) return Status::kRejected;
    if (silent_) {
      if (s != Status::kOk) Record(adjust, false);
      return Status::kTimeout;
    }
    if (s != Status::kOk) {
      ++counters_.readbacks;
      s = Query(axis, pmd::op::kGetActualPosition, 2, &reply);
      if (s != Status::kOk) {
        Record(adjust, false);
        return s;
      }
      const std::int64_t now = pmd::ReplyLong(reply);
      if (std::abs(now - (before + delta)) <= 2) {
        // Executed, once; a shift of less than the read-back's tolerance cannot be told from
        // none.
        Record(adjust, std::abs(delta) > 2);
        return Status::kOk;
      }
      if (std::abs(now - before) > 2) {
        Record(adjust, false);
        return Status::kBadReply;  // moved: unclear
      }
    }
    ++counters_.resends;
  }
  return Status::kBadReply;
}

Status BiclopsHead::HomeAxis(int axis) {
  // libPMD FindHome with homingMode bestWay for an axis with several index pulses per turn and
  // a home sensor (FindHomeBestWay, FindHomeCenter, FindIndex; the index sweep of
  // FindHomeWithHomeSensor): the sensor's centre from both of its edges, then the index pulse
  // within half an encoder cycle of it is the zero.
  const BiclopsAxisOptions& x = options_.axes[Index(axis)];
  const double cpr = std::abs(x.counts_per_rad);
  const auto width =
      static_cast<std::int32_t>(std::max(2.0, std::round(x.home_sensor_width_rad * cpr)));
  const auto cycle = static_cast<std::int32_t>(std::round(std::abs(x.index_spacing_rad) * cpr));
  const auto range = static_cast<std::int32_t>(std::ceil((x.max_rad - x.min_rad) * cpr));
  pmd::Reply reply;
  bool got = false;
  std::int32_t value = 0;
  Status s = Query(axis, pmd::op::kGetActualPosition, 2, &reply);
  if (s != Status::kOk) return Failed(axis, "GetActualPosition", s);
  std::int32_t here = static_cast<std::int32_t>(pmd::ReplyLong(reply));
  s = Query(axis, pmd::op::kGetSignalStatus, 1, &reply);
  if (s != Status::kOk) return Failed(axis, "GetSignalStatus", s);
  if ((reply.words[0] & pmd::signal::kHome) != 0) {
    // On the sensor: off it first, so that its edge can be captured (FindHomeCenter).
    s = HomingMove(axis, here - 2 * width, -1, &got, &value);
    if (s != Status::kOk) return Failed(axis, "moving off the home sensor", s);
    here -= 2 * width;
  }
  // First edge: towards the negative end (libPMD starts homing in - without an absolute
  // sensor), then the other way over the whole range.
  int dir = -1;
  std::int32_t edge[2] = {0, 0};
  s = HomingMove(axis, here - range, pmd::kCaptureHome, &got, &edge[0]);
  if (s != Status::kOk) return Failed(axis, "searching the home sensor (-)", s);
  if (!got) {
    dir = 1;
    s = HomingMove(axis, here + range, pmd::kCaptureHome, &got, &edge[0]);
    if (s != Status::kOk) return Failed(axis, "searching the home sensor (+)", s);
    if (!got) {
      last_error_ = std::string("biclops ") + kAxisNames[axis] +
                    ": no home sensor edge over the whole range (sensor or axis broken?)";
      return Status::kRejected;
    }
  }
  // Second edge: past the sensor, then back onto it from the other side.
  s = HomingMove(axis, edge[0] + dir * 3 * width, -1, &got, &value);
  if (s != Status::kOk) return Failed(axis, "moving past the home sensor", s);
  s = HomingMove(axis, edge[0] - dir * 2 * width, pmd::kCaptureHome, &got, &edge[1]);
  if (s != Status::kOk) return Failed(axis, "searching the home sensor's other edge", s);
  if (!got || std::abs(edge[0] - edge[1]) <= width / 2) {
    last_error_ = std::string("biclops ") + kAxisNames[axis] +
                  ": the home sensor's other edge was not found within " +
                  std::to_string(3 * width) + " counts";
    return Status::kRejected;
  }
  const std::int32_t center = (edge[0] + edge[1]) / 2;
  // The index: from half an encoder cycle below the centre, one cycle up with index capture.
  s = HomingMove(axis, center - cycle / 2, -1, &got, &value);
  if (s != Status::kOk) return Failed(axis, "moving below the home sensor", s);
  std::int32_t index = 0;
  s = HomingMove(axis, center + cycle / 2 + cycle / 20, pmd::kCaptureIndex, &got, &index);
  if (s != Status::kOk) return Failed(axis, "searching the index pulse", s);
  if (!got) {
    last_error_ = std::string("biclops ") + kAxisNames[axis] +
                  ": no index pulse within half an encoder cycle of the home sensor";
    return Status::kRejected;
  }
  // The zero: the index plus the calibrated offset, in encoder counts.
  const auto zero =
      static_cast<std::int32_t>(index + std::llround(x.home_offset_rad * x.counts_per_rad));
  s = AdjustPosition(axis, -zero);
  if (s != Status::kOk) return Failed(axis, "AdjustActualPosition", s);
  // Homed: the capture source set to home marks it in the chip (libPMD SetHomedState on a
  // controller without memory), motion errors stop the axis from now on, and it goes to 0.
  s = Command(pmd::WithWord(static_cast<std::uint8_t>(axis), pmd::op::kSetCaptureSource,
                            pmd::kCaptureHome));
  if (s != Status::kOk) return Failed(axis, "SetCaptureSource (homed)", s);
  s = HomingMove(axis, 0, -1, &got, &value);
  if (s != Status::kOk) return Failed(axis, "moving to 0", s);
  s = Command(pmd::WithWord(static_cast<std::uint8_t>(axis), pmd::op::kSetAutoStopMode, 1));
  if (s != Status::kOk) return Failed(axis, "SetAutoStopMode", s);
  return Status::kOk;
}

Status BiclopsHead::StopUpdate(int axis) {
  // The Update consumes the stop: a stop mode of 0 means it was executed.
  return UpdateOnce(axis, [this, axis](bool* executed, bool* /*sure*/) {
    pmd::Reply reply;
    const Status s = Query(axis, pmd::op::kGetStopMode, 1, &reply);
    if (s == Status::kOk) *executed = reply.words[0] == pmd::kNoStop;
    return s;
  });
}

Status BiclopsHead::Stop() {
  std::lock_guard<std::mutex> lock(mu_);
  BeginCall();
  for (int a = 0; a < 3; ++a) {
    Status s = Command(
        pmd::WithWord(static_cast<std::uint8_t>(a), pmd::op::kSetStopMode, pmd::kAbruptStop));
    if (s == Status::kOk) s = StopUpdate(a);
    // The axis ends wherever it stopped: its active target is read again before the next move.
    active_target_[Index(a)] = Known{};
    at_rest_[Index(a)] = false;
    rest_known_[Index(a)] = false;
    if (s != Status::kOk) return Fail(s);
  }
  // Stopped means at rest: the stop is executed at once, but the servo brakes each axis from
  // its speed (a homing sweep, a move). The safe stop's report must not say "ok" for a head
  // still turning.
  const Clock::TimePoint give_up = clock_->Now() + Clock::FromSeconds(options_.stop_settle_s);
  for (int a = 0; a < 3; ++a) {
    for (;;) {
      pmd::Reply reply;
      const Status s = Query(a, pmd::op::kGetActivityStatus, 1, &reply);
      if (s != Status::kOk) return Fail(s);
      if ((reply.words[0] & pmd::activity::kInMotion) == 0) break;
      if (clock_->Now() > give_up) {
        last_error_ = std::string("biclops ") + kAxisNames[a] + ": still moving " +
                      std::to_string(options_.stop_settle_s) + " s after the stop";
        return Status::kTimeout;
      }
      clock_->SleepFor(std::chrono::milliseconds(5));
      BeginCall();  // braking is not silence: the chip answers every poll
    }
  }
  return Status::kOk;
}

Status BiclopsHead::ConfigureAndHome(const StopRequest* stop) {
  std::lock_guard<std::mutex> lock(mu_);
  stop_ = stop;
  struct Forget {
    const StopRequest** stop;
    ~Forget() { *stop = nullptr; }
  } forget_stop{&stop_};
  BeginCall();
  // A silence that reaches the limit during homing gets a line probe (SilenceReached) instead
  // of ending the homing at once: a 200 ms dropout on top of a packet the line damaged can
  // silence the chip for 0.4 s (PROTOCOL.md, "Homing through a noisy line").
  line_probes_left_ = options_.max_resends;
  struct NoProbes {
    int* left;
    ~NoProbes() { *left = 0; }
  } no_probes{&line_probes_left_};
  last_error_.clear();
  homed_ = false;
  Status s = EnsureInitialized();
  if (s != Status::kOk) {
    last_error_ = "biclops: initialisation (GetVersion, GetSampleTime, profile): " +
                  std::string(device::ToString(s));
    return Fail(s);
  }
  // Homing changes the profile registers and the counters: the mirrors are read again after.
  auto forget = [this]() {
    initialized_ = false;
    for (auto& axis : reg_) axis.fill(Known{});
    active_target_.fill(Known{});
    at_rest_.fill(false);
    rest_known_.fill(false);
  };
  forget();
  for (int a = 0; a < 3; ++a) {
    s = ConfigureAxis(a);
    if (s != Status::kOk) return Fail(s);
  }
  // Biclops::HomeAxes: tilt, (roll,) verge, then pan.
  for (int a : {1, 2, 0}) {
    s = HomeAxis(a);
    if (s != Status::kOk) return Fail(s);
  }
  s = EnsureInitialized();  // the run profile again
  if (s != Status::kOk) {
    last_error_ = "biclops: run profile after homing: " + std::string(device::ToString(s));
    return Fail(s);
  }
  homed_ = true;
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
    if (s != Status::kOk) {
      Record(pmd::Reset(), false);
      return Fail(s);
    }
    if (velocity == 0) {
      Record(pmd::Reset(), true);
      // Reset: every register is at its power-up value; read them again before use.
      initialized_ = false;
      homed_ = false;
      for (auto& axis : reg_) axis.fill(Known{});
      active_target_.fill(Known{});
      at_rest_.fill(false);
      rest_known_.fill(false);
      return Status::kOk;
    }
    if (velocity != velocity_reg_[0]) {
      Record(pmd::Reset(), false);
      return Fail(Status::kBadReply);
    }
    ++counters_.resends;
  }
  return Fail(Status::kBadReply);
}

}  // namespace hgrasp::drivers
