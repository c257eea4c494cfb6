#include "sensorhand/sensorhand_hand.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "common/error.h"

namespace hgrasp::drivers {
namespace {

using device::Status;
using sensorhand::DumpSample;
using sensorhand::MotionState;
using sensorhand::Reply;
using sensorhand::SpeedSetting;

constexpr double kPollS = 0.003;             // the I/O loop's read wait (its period on a SimClock)
constexpr double kStreamRetryS = 0.1;        // 0x73 at most this often while the stream is silent
constexpr double kDisconnectedFailS = 0.05;  // a vanished port fails a call after this
constexpr std::size_t kHistory = 16;         // samples kept
constexpr int kForceSettledSamples = 5;      // the grip force has not risen over 5 samples (60 ms)
constexpr int kVotes = 2;            // late samples that must show a setting before it is believed
constexpr int kContradictions = 3;   // late samples in a row against known_: an anomaly
constexpr double kStillM_s = 0.001;  // estimated slower than this: the fingers are still
constexpr double kContactN = 0.5;    // a grip force above this: the pads touch an object
constexpr double kEndMarginM = 0.005;    // "at an end stop": this near it, beyond the uncertainty
constexpr double kContactMemoryS = 0.2;  // an object the pads touched this recently is still there
constexpr int kMaxReversals = 3;         // Open() gives up hunting after this many turns
// One byte on the hand's line (8N1 at 19200 baud: 10 bits, 0.52 ms). A stream frame describes
// the hand when its first byte left; its last arrives kDumpFrameBytes bytes later (6.25 ms).
constexpr double kByteS = 10.0 / sensorhand::kBaud;
constexpr double kDumpWireS = sensorhand::kDumpFrameBytes * kByteS;
const double kEchoWireS =
    static_cast<double>(sensorhand::EncodeSpeedEcho(SpeedSetting{}).size()) * kByteS;

double Seconds(Clock::Duration d) { return Clock::ToSeconds(d); }

void Check(bool ok, const char* field, double value, const char* expected) {
  if (!ok)
    throw InputError("", std::string("sensorhand.") + field, std::to_string(value), expected);
}

sensorhand::HandMotionModel ModelOf(const SensorHandOptions& o) {
  sensorhand::HandMotionModel m;
  m.max_opening_m = o.max_opening_m;
  m.full_speed_m_s = o.full_speed_m_s;
  m.full_force_n = o.full_force_n;
  m.accel_m_s2 = o.accel_m_s2;
  m.speed_error = o.speed_error;
  return m;
}

}  // namespace

SerialConfig SensorHandHand::SerialConfigFor(std::string port) {
  SerialConfig c;
  c.port = std::move(port);
  c.baud = sensorhand::kBaud;
  c.data_bits = 8;
  c.parity = Parity::kNone;
  c.stop_bits = 1;
  return c;
}

SensorHandHand::SensorHandHand(std::unique_ptr<ByteLink> link, SensorHandOptions options,
                               Clock& clock)
    : link_(std::move(link)),
      options_(options),
      slow_byte_(sensorhand::SpeedByteAtMost(options.slow_speed_m_s / options.full_speed_m_s)),
      clock_(clock),
      t0_(clock.Now()) {
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  auto non_negative = [](double v) { return std::isfinite(v) && v >= 0.0; };
  Check(link_ != nullptr, "link", 0, "a serial link");
  Check(positive(options_.max_opening_m), "max_opening_m", options_.max_opening_m, "> 0 m");
  Check(positive(options_.max_force_n), "max_force_n", options_.max_force_n, "> 0 N");
  Check(positive(options_.full_speed_m_s), "full_speed_m_s", options_.full_speed_m_s, "> 0 m/s");
  Check(positive(options_.full_force_n), "full_force_n", options_.full_force_n, "> 0 N");
  Check(positive(options_.accel_m_s2), "accel_m_s2", options_.accel_m_s2, "> 0 m/s^2");
  Check(positive(options_.slow_speed_m_s) && options_.slow_speed_m_s <= options_.full_speed_m_s,
        "slow_speed_m_s", options_.slow_speed_m_s, "> 0 m/s and at most full_speed_m_s");
  Check(positive(options_.opening_tolerance_m), "opening_tolerance_m", options_.opening_tolerance_m,
        "> 0 m");
  Check(non_negative(options_.latency_s), "latency_s", options_.latency_s, ">= 0 s");
  Check(non_negative(options_.initial_opening_m) &&
            options_.initial_opening_m <= options_.max_opening_m,
        "initial_opening_m", options_.initial_opening_m, "0..max_opening_m");
  Check(non_negative(options_.initial_uncertainty_m), "initial_uncertainty_m",
        options_.initial_uncertainty_m, ">= 0 m");
  Check(non_negative(options_.speed_error) && options_.speed_error < 1.0, "speed_error",
        options_.speed_error, "0 to 1 (a share)");
  Check(positive(options_.call_timeout_s), "call_timeout_s", options_.call_timeout_s, "> 0 s");
  Check(options_.stream_timeout_s >= 2 * sensorhand::kDumpPeriodS, "stream_timeout_s",
        options_.stream_timeout_s, "at least two stream periods (0.024 s)");
  Check(options_.fresh_s >= options_.stream_timeout_s, "fresh_s", options_.fresh_s,
        "at least stream_timeout_s");
  Check(non_negative(options_.transit_s), "transit_s", options_.transit_s, ">= 0 s");
  Check(positive(options_.unresolved_s), "unresolved_s", options_.unresolved_s, "> 0 s");
  estimator_ = sensorhand::OpeningEstimator(ModelOf(options_), 0.0, options_.initial_opening_m,
                                            options_.initial_uncertainty_m);
  const Clock::TimePoint now = clock_.Now();
  last_empty_t_ = now;
  last_sample_t_ = now - std::chrono::hours(1);
  last_stream_start_ = last_sample_t_;
  known_since_ = now;
  goal_.id = next_goal_id_++;  // hold: stop the fingers if they move when we connect
  io_ = clock_.Start(Clock::FromSeconds(kPollS),
                     [this](Clock::Duration wait) { return IoTurn(Clock::ToSeconds(wait)); });
}

SensorHandHand::~SensorHandHand() {
  {
    std::unique_lock<std::mutex> lock(mu_);
    shutting_down_ = true;
    Goal hold;
    hold.id = next_goal_id_++;
    hold.sample_mark = samples_;
    goal_ = hold;
    clock_.WaitUntil(lock, cv_, clock_.Now() + std::chrono::milliseconds(300),
                     [&] { return !pending_ && known_.stopped(); });
    send_dump_stop_ = true;
    clock_.WaitUntil(lock, cv_, clock_.Now() + std::chrono::milliseconds(50),
                     [&] { return !send_dump_stop_; });
    stop_ = true;
  }
  cv_.notify_all();
  io_.reset();
}

double SensorHandHand::ToS(Clock::TimePoint t) const { return Seconds(t - t0_); }

// --- The I/O loop -----------------------------------------------------------------------------

bool SensorHandHand::IoTurn(double wait_s) {
  ReadOnce(wait_s);
  // Drain: what is decided next rests on everything that has arrived (echoes above all).
  while (ReadOnce(0.0)) {
  }
  std::vector<std::uint8_t> out;
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (stop_) return false;
    Step(clock_.Now(), &out);
  }
  if (!out.empty()) {
    const Clock::TimePoint t_begin = clock_.Now();
    const Status w = link_->Write(out);
    const Clock::TimePoint t_w = clock_.Now();
    std::lock_guard<std::mutex> lock(mu_);
    if (w != Status::kOk) link_status_ = w;
    if (pending_ && !pending_->written) {
      pending_->t_write_begin = t_begin;
      pending_->t_written = t_w;
      pending_->write_bytes = out.size();
      pending_->written = true;
    }
  }
  cv_.notify_all();
  return true;
}

bool SensorHandHand::ReadOnce(double timeout_s) {
  std::uint8_t buf[256];
  std::size_t n = 0;
  // Taken before the read: if it finds nothing, the link was empty at some moment after this,
  // whatever the scheduler did to this thread meanwhile.
  const Clock::TimePoint before = clock_.Now();
  const Status s = link_->Read(buf, timeout_s, &n);
  const Clock::TimePoint now = clock_.Now();
  std::vector<Reply> replies;
  if (s == Status::kOk && n > 0) decoder_.Push(std::span<const std::uint8_t>(buf, n), &replies);
  std::lock_guard<std::mutex> lock(mu_);
  link_status_ = s == Status::kDisconnected ? Status::kDisconnected : Status::kOk;
  stats_.discarded_bytes = decoder_.discarded();
  if (s != Status::kOk || n == 0) {
    // Whatever is read later arrived after `before`.
    last_empty_t_ = before;
    return false;
  }
  for (const Reply& r : replies) HandleReply(r, now);
  return true;
}

void SensorHandHand::HandleReply(const Reply& r, Clock::TimePoint now) {
  switch (r.kind) {
    case Reply::Kind::kDump:
      HandleSample(r.dump, now);
      break;
    case Reply::Kind::kSpeedEcho:
      ++stats_.echoes;
      if (pending_ && pending_->written && r.speed == pending_->cmd) {
        // The hand answers a 0x75 it executed with its two speed bytes: it took the command
        // between the write and now.
        double t_begin = ToS(pending_->t_write_begin);
        double t_echo = ToS(now);
        // On a line at the hand's baud rate the command's last byte reached the hand no sooner
        // than its write took on the wire, and the echo left it at least its own length before
        // it was read. A link faster than that (a pty) leaves the plain window.
        const double reached = t_begin + static_cast<double>(pending_->write_bytes) * kByteS;
        const double answered = t_echo - kEchoWireS;
        if (answered >= reached) {
          t_begin = reached;
          t_echo = answered;
        }
        const double delay = Seconds(now - pending_->t_written);
        stats_.echo_delay_max_s = std::max(stats_.echo_delay_max_s, delay);
        const double echoed = static_cast<double>(stats_.executed - stats_.executed_unechoed + 1);
        stats_.echo_delay_mean_s += (delay - stats_.echo_delay_mean_s) / echoed;
        // Taken between the write and the echo's arrival: the middle of that window is off by
        // at most half of it, however the delays split between line, hand and scheduler.
        ResolveExecuted(0.5 * (t_begin + t_echo), 0.5 * (t_echo - t_begin));
      } else {
        ++stats_.stray_echoes;  // a late echo of a command already judged, or a false frame
      }
      break;
    case Reply::Kind::kDumpStartEcho:
    case Reply::Kind::kDumpStopEcho:
      break;
  }
}

SensorHandHand::Evidence SensorHandHand::Classify(std::uint8_t state) {
  switch (static_cast<MotionState>(state)) {
    case MotionState::kIdle:
      return Evidence::kStopped;
    case MotionState::kBlocked:
      return Evidence::kRunning;
    case MotionState::kOpening:
      return Evidence::kOpenWay;
    case MotionState::kClosing:
      return Evidence::kCloseWay;
  }
  return Evidence::kNone;
}

bool SensorHandHand::Consistent(const SpeedSetting& s, Evidence e) {
  if (e == Evidence::kNone) return false;
  if (s.stopped()) return e == Evidence::kStopped;
  if (s.open != 0) return e == Evidence::kOpenWay || e == Evidence::kRunning;
  return e == Evidence::kCloseWay || e == Evidence::kRunning;
}

bool SensorHandHand::LateEnough(Clock::TimePoint since) const {
  // The sample arrived after last_empty_t_, so the hand made it after last_empty_t_ - transit;
  // the setting reached the hand by since + transit; then the fingers need up to a full-speed
  // stop (v / a) and a period to show it in the state byte.
  const double settle = options_.full_speed_m_s / options_.accel_m_s2 + sensorhand::kDumpPeriodS;
  return Seconds(last_empty_t_ - since) >= 2.0 * options_.transit_s + settle;
}

void SensorHandHand::HandleSample(const DumpSample& d, Clock::TimePoint now) {
  ++samples_;
  ++stats_.samples;
  last_sample_t_ = now;
  history_.push_back({d, now});
  if (history_.size() > kHistory) history_.pop_front();
  // Made when its first byte left the hand: its whole frame on the wire before `now`.
  const double t = ToS(now) - kDumpWireS;
  const double force = sensorhand::ForceN(d.f_bracket);
  // The estimate under the setting the driver knows, before this sample can fix it.
  sensorhand::OpeningEstimator prior = estimator_;
  prior.AdvanceTo(t);
  estimator_.Observe(t, force, d.state);
  const Evidence ev = Classify(d.state);
  if (!setting_known_) {
    // Connecting: a hand that reports idle runs at speed 0; anything else gets a stop, sent
    // even though the driver assumes speed 0 (a stop twice changes nothing).
    setting_known_ = true;
    if (ev != Evidence::kStopped) resend_anyway_ = true;
    known_shown_ = ev == Evidence::kStopped;
  }

  if (pending_ && pending_->written) {
    JudgePending(prior, {t, force, d.state}, ev);
    return;
  }
  if (pending_ || ev == Evidence::kNone) return;
  CheckKnown(ev, t, now);
}

void SensorHandHand::JudgePending(const sensorhand::OpeningEstimator& prior, const Observation& o,
                                  Evidence ev) {
  const double t = o.t_s;
  const double force = o.force_n;
  pending_->since_write.push_back(o);
  // The echo lost (or late), the state byte tells which setting is in force. The two always
  // differ in what it shows (Step never changes a speed within a direction without a stop).
  // A sample that shows only the new one proves it at once if the samples already showed
  // the old one settled (under it the state stays in its set: idle stays idle, opening or
  // blocked stays so); else, and to call the command lost, only samples made after the
  // command must have reached the hand and the fingers settled count.
  if (force > kContactN) pending_->contact = true;
  bool shows_new = Consistent(pending_->cmd, ev);
  bool shows_old = Consistent(pending_->before, ev);
  const bool late = LateEnough(pending_->t_written);
  if (shows_new && shows_old && ev == Evidence::kRunning && force > kContactN) {
    // Blocked pressing an object: only a close speed keeps the pads on it (an open one moves
    // them off it, and they are blocked only at the open end stop, where nothing presses).
    // Before the samples are late, the old setting's grip may still show.
    shows_old = late && pending_->before.close != 0;
    shows_new = late && pending_->cmd.close != 0;
  } else if (shows_new && shows_old && ev == Evidence::kRunning) {
    // Blocked without a force: at an end stop, which a reversal's two settings put at
    // opposite ends. Where each would have the fingers tells them apart (an open speed lost
    // at the end stop stays blocked there; the close would have left it long since). A
    // close speed meets an object the pads touched since shortly before the write: it
    // would press it again rather than reach 0 (were the object gone meanwhile, neither
    // setting shows and the command stays unresolved: safe).
    const double margin = kEndMarginM + prior.uncertainty_m();
    auto at_its_end = [&](const SpeedSetting& s, double y) {
      if (s.open != 0) return y >= options_.max_opening_m - margin;
      return !pending_->contact && y <= margin;
    };
    shows_old = at_its_end(pending_->before, prior.opening_m());
    shows_new = at_its_end(pending_->cmd, Hypothesis(*pending_, t).opening_m());
  }
  CountVote(shows_new, shows_old, late, ev);
}

void SensorHandHand::CountVote(bool shows_new, bool shows_old, bool late, Evidence ev) {
  // Idle (speeds 0) and blocked (a speed set) need no settling: each is impossible under the
  // other kind of setting.
  const bool definite = ev == Evidence::kStopped || ev == Evidence::kRunning;
  if (shows_new && !shows_old && (late || definite || pending_->before_settled)) {
    ++pending_->votes_new;
  }
  if (shows_old && !shows_new && late) ++pending_->votes_old;
  if (pending_->votes_new >= kVotes && pending_->votes_new >= pending_->votes_old + kVotes) {
    ++stats_.executed_unechoed;
    const double t_exec = ToS(pending_->t_write_begin) + options_.latency_s;
    ResolveExecuted(t_exec, options_.transit_s);
    known_shown_ = true;  // these very samples showed it
  } else if (pending_->votes_old >= kVotes && pending_->votes_new == 0) {
    // Two settled samples still show the old setting and none the new: the command never
    // arrived whole. Safe to send again.
    ++stats_.lost;
    last_lost_ = pending_->cmd;
    command_log_.Resolve(pending_->logged, false);
    pending_.reset();
  }
}

void SensorHandHand::CheckKnown(Evidence ev, double t, Clock::TimePoint now) {
  if (Consistent(known_, ev)) {
    // Samples read after the command was resolved were made after it took effect (the hand
    // finishes a frame before it answers a command): from now on the state stays in this set.
    contradictions_ = 0;
    known_shown_ = true;
    return;
  }
  if (!LateEnough(known_since_) || ++contradictions_ != kContradictions) return;
  // The stream disagrees with the setting the driver knows: a hand reset (power cycle),
  // another host, or a false echo. Counted; idle is believed, since its bytes are known.
  ++stats_.anomalies;
  if (ev == Evidence::kStopped) {
    known_ = sensorhand::kStop;
    known_shown_ = true;
    known_since_ = now;
    known_since_sample_ = samples_;
    estimator_.Execute(t, sensorhand::kStop, options_.transit_s);
  }
}

sensorhand::OpeningEstimator SensorHandHand::Hypothesis(const Pending& p, double t_s) const {
  // The samples' forces only: their states were made under a setting not yet known.
  constexpr std::uint8_t kNoState = 0xFF;
  const double t_exec = ToS(p.t_write_begin) + options_.latency_s;
  sensorhand::OpeningEstimator e = p.at_write;
  bool executed = false;
  for (const Observation& o : p.since_write) {
    if (o.t_s >= t_s) break;
    if (!executed && o.t_s >= t_exec) {
      e.Execute(t_exec, p.cmd, 0.0);
      executed = true;
    }
    e.Observe(o.t_s, o.force_n, kNoState);
  }
  if (!executed) e.Execute(std::min(t_exec, t_s), p.cmd, 0.0);
  e.AdvanceTo(t_s);
  return e;
}

void SensorHandHand::ResolveExecuted(double t_exec_s, double uncertainty_s) {
  Pending p = std::move(*pending_);
  pending_.reset();
  // Replay the samples since the write on the estimate from before it, with the command taking
  // effect at t_exec_s: the running estimate assumed the old setting meanwhile.
  sensorhand::OpeningEstimator e = p.at_write;
  std::size_t i = 0;
  for (; i < p.since_write.size() && p.since_write[i].t_s < t_exec_s; ++i) {
    e.Observe(p.since_write[i].t_s, p.since_write[i].force_n, p.since_write[i].state);
  }
  e.Execute(t_exec_s, p.cmd, uncertainty_s);
  for (; i < p.since_write.size(); ++i) {
    e.Observe(p.since_write[i].t_s, p.since_write[i].force_n, p.since_write[i].state);
  }
  estimator_ = e;
  executed_.push_back(p.cmd);
  command_log_.Resolve(p.logged, true);
  ++stats_.executed;
  acked_goal_id_ = std::max(acked_goal_id_, p.goal_id);
  known_ = p.cmd;
  known_since_ = p.t_written;
  known_resolved_t_ = last_sample_t_;
  known_since_sample_ = samples_ - std::min<std::uint64_t>(samples_, p.since_write.size());
  known_shown_ = false;
  contradictions_ = 0;
}

void SensorHandHand::Step(Clock::TimePoint now, std::vector<std::uint8_t>* out) {
  if (send_dump_stop_) {
    const auto stop = sensorhand::EncodeDumpStop();
    out->insert(out->end(), stop.begin(), stop.end());
    command_log_.Unconfirmed({sensorhand::Command::Kind::kDumpStop, {}});  // no echo awaited
    send_dump_stop_ = false;
    dump_stopped_ = true;
    return;
  }
  const bool silent = samples_ == 0 || Seconds(now - last_sample_t_) > options_.stream_timeout_s;
  if (silent && !dump_stopped_ && Seconds(now - last_stream_start_) >= kStreamRetryS) {
    // The stream is off (hand reset, port back after vanishing) or the line is down: (re)start
    // it. 0x73 only switches the stream on; sent again it changes nothing.
    const auto start = sensorhand::EncodeDumpStart();
    out->insert(out->end(), start.begin(), start.end());
    command_log_.Unconfirmed({sensorhand::Command::Kind::kDumpStart, {}});  // no echo awaited
    last_stream_start_ = now;
    ++stats_.stream_starts;
  }
  if (pending_) {
    if (pending_->written && !silent &&
        Seconds(now - pending_->t_written) > options_.unresolved_s &&
        pending_->since_write.size() >= 2 * kVotes) {
      // Samples keep coming but neither an echo nor the state byte tells: give up knowing, and
      // stop the fingers (a stop is safe whichever setting is in force).
      ++stats_.unresolved;
      unresolved_.push_back(pending_->cmd);
      pending_.reset();
      // The setting since is one of two: the estimate may be off by anything. It runs on as
      // stopped (a stop goes out next; no end-stop fix under a setting it cannot know), lost.
      estimator_.Execute(ToS(now), sensorhand::kStop, 0.0);
      estimator_.MarkLost(options_.max_opening_m);
      resend_anyway_ = true;
      Goal hold;
      hold.id = next_goal_id_++;
      hold.sample_mark = samples_;
      goal_ = hold;
    }
    return;  // one command in flight
  }
  if (silent || samples_ <= goal_.sample_mark) return;
  const Goal before_control = goal_;
  SpeedSetting want = Control(now);
  if (!want.stopped() && !known_.stopped() && (want.open != 0) == (known_.open != 0) &&
      want != known_) {
    // Another speed the same way: stop first, so that the state byte tells the settings apart
    // should the echo be lost.
    want = sensorhand::kStop;
    ++stats_.stops_inserted;
  }
  if (want == known_ && !resend_anyway_) {
    acked_goal_id_ = std::max(acked_goal_id_, goal_.id);
    return;
  }
  // A speed waits until a sample has shown the setting in force: then the state byte proves at
  // once which of the two is in force should the echo be lost (a stop never waits: idle proves
  // it whatever came before).
  if (!want.stopped() && !known_shown_) {
    goal_ = before_control;  // decide again then, as if not asked now
    return;
  }
  resend_anyway_ = false;
  Pending p;
  p.cmd = want;
  p.before = known_;
  p.at_write = estimator_;
  p.before_settled = known_shown_ && Consistent(known_, Classify(history_.back().d.state));
  for (const Sample& h : history_) {
    if (Seconds(now - h.t) <= kContactMemoryS && sensorhand::ForceN(h.d.f_bracket) > kContactN)
      p.contact = true;
  }
  p.goal_id = goal_.id;
  p.logged = command_log_.Sent({sensorhand::Command::Kind::kSpeed, want});
  pending_ = std::move(p);
  if (last_lost_ && *last_lost_ == want) ++stats_.resends;
  last_lost_.reset();
  ++stats_.commands;
  const auto frame = sensorhand::EncodeSpeed(want);
  out->insert(out->end(), frame.begin(), frame.end());
}

double SensorHandHand::SpeedOf(std::uint8_t b) const {
  return options_.full_speed_m_s * sensorhand::SpeedFraction(b);
}

double SensorHandHand::StopLead(double speed) const {
  return speed * options_.latency_s + speed * speed / (2.0 * options_.accel_m_s2);
}

SpeedSetting SensorHandHand::Control(Clock::TimePoint now) {
  if (goal_.done) return sensorhand::kStop;
  const double force = sensorhand::ForceN(history_.back().d.f_bracket);
  switch (goal_.kind) {
    case GoalKind::kHold:
      goal_.done = true;
      return sensorhand::kStop;
    case GoalKind::kClose:
      return ControlClose(force);
    case GoalKind::kOpen:
      return ControlOpen(now, force);
  }
  return sensorhand::kStop;
}

SpeedSetting SensorHandHand::ControlClose(double force) {
  const double step = options_.full_force_n / (sensorhand::kSpeedMax - sensorhand::kSpeedMin + 1);
  if (goal_.backing_off || force > goal_.force_n + step) {
    // Pressing harder than asked (a stronger grip before): ease off slowly down to it.
    goal_.backing_off = true;
    if (force > goal_.force_n) return {slow_byte_, 0};
    goal_.done = true;
    return sensorhand::kStop;
  }
  if (force >= goal_.force_n || (known_.close != 0 && (Blocked() || ForceSettled()))) {
    // At the force limit, stalled on the object, or the fingers meet (blocked without a
    // force): speed 0 holds the grip (the gear does not back-drive).
    goal_.done = true;
    return sensorhand::kStop;
  }
  return {0, goal_.close_byte};
}

SpeedSetting SensorHandHand::ControlOpen(Clock::TimePoint now, double force) {
  if (estimator_.lost() && !goal_.homing) goal_.homing = true;
  if (goal_.homing) return Homing();
  // The estimate when a command decided now takes effect (half a poll early on average).
  sensorhand::OpeningEstimator ahead = estimator_;
  ahead.AdvanceTo(ToS(now) + options_.latency_s + 0.5 * kPollS);
  if (known_.stopped()) return OpenFromRest(goal_.opening_m - ahead.opening_m(), force);
  return OpenOnTheWay(ahead, force);
}

SpeedSetting SensorHandHand::Homing() {
  if (!estimator_.lost()) {
    // Fixed at the end stop: stop there, then on to the target from a known opening.
    goal_.homing = false;
    goal_.last_dir = 0;
    goal_.reversals = 0;
    goal_.at_object = false;
    return sensorhand::kStop;
  }
  if (known_.open != 0) return known_;  // until the stream shows it blocked
  if (!known_.stopped() || Moving()) return sensorhand::kStop;
  return {sensorhand::kSpeedMax, 0};
}

double SensorHandHand::LightTouchN() const {
  return options_.full_force_n * sensorhand::SpeedFraction(slow_byte_);
}

SpeedSetting SensorHandHand::Toward(int dir, double distance) const {
  const double slow_zone = StopLead(options_.full_speed_m_s) + 0.004;
  const std::uint8_t b = distance > slow_zone ? sensorhand::kSpeedMax : slow_byte_;
  return dir > 0 ? SpeedSetting{b, 0} : SpeedSetting{0, b};
}

SpeedSetting SensorHandHand::OpenFromRest(double e, double force) {
  if (Moving()) return sensorhand::kStop;  // let the fingers settle, then judge
  if (goal_.contact) {
    // Stopped on the object: ease a harder press off to a light touch first.
    if (force > LightTouchN()) return {slow_byte_, 0};
    goal_.contact = false;
  }
  if (goal_.to_end) {
    // Into the end stop, whatever the estimate says, until the stream shows it blocked
    // (or an object stops the fingers on the way to 0). Stopped again after a move the
    // hand took: there. Stopped because the move was lost on the line: send it again.
    if (goal_.moved) {
      goal_.done = true;
      return sensorhand::kStop;
    }
    const int dir = goal_.opening_m > 0.0 ? 1 : -1;
    goal_.last_dir = dir;
    return Toward(dir, std::abs(e));
  }
  if (std::abs(e) <= options_.opening_tolerance_m || (e < 0.0 && goal_.at_object)) {
    // There, or the target lies behind the object the pads met.
    goal_.done = true;
    return sensorhand::kStop;
  }
  const int dir = e > 0.0 ? 1 : -1;
  if (goal_.last_dir != 0 && dir != goal_.last_dir && ++goal_.reversals > kMaxReversals) {
    goal_.done = true;  // hunting: give up
    return sensorhand::kStop;
  }
  goal_.last_dir = dir;
  return Toward(dir, std::abs(e));
}

SpeedSetting SensorHandHand::OpenOnTheWay(const sensorhand::OpeningEstimator& ahead, double force) {
  const int dir = known_.open != 0 ? 1 : -1;
  if (goal_.contact) {
    // Easing off the object: stop at a light touch.
    if (dir > 0 && force > LightTouchN()) return known_;
    goal_.contact = false;
    return sensorhand::kStop;
  }
  goal_.moved = true;
  if (dir < 0 && force > kContactN) {
    // Closing onto an object: stop at the contact (then ease off, and go on only if the
    // target lies the other way).
    goal_.contact = true;
    goal_.at_object = true;
    return sensorhand::kStop;
  }
  if (Blocked()) {
    // Blocked: at an end stop (the estimate is fixed there). A move into it is done. A move
    // to a target short of it had its stop lost on the line (in a dropout, say) and ran on:
    // it goes on from the known opening once the fingers are stopped (the turn back counts
    // against hunting). Taken as done, the move ended with the hand shut where the plan
    // wanted it 81 mm open (fault seed 28 of the whole run through the twin's noisy lines).
    if (goal_.to_end) goal_.done = true;
    return sensorhand::kStop;
  }
  if (goal_.to_end) return known_;
  // Stop when the fingers, stopped now, would come to rest at the target or beyond.
  if (dir * (goal_.opening_m - ahead.RestOpening()) <= 0.0) return sensorhand::kStop;
  return known_;
}

bool SensorHandHand::Blocked() const {
  // Only a sample read after the setting was resolved: one read between the write and the
  // echo may have been made under the setting before (blocked at an end stop, say).
  return !known_.stopped() && !history_.empty() &&
         history_.back().d.state == static_cast<std::uint8_t>(MotionState::kBlocked) &&
         history_.back().t > known_resolved_t_;
}

bool SensorHandHand::ForceSettled() const {
  if (known_.close == 0 || history_.size() < static_cast<std::size_t>(kForceSettledSamples) ||
      samples_ < known_since_sample_ + kForceSettledSamples) {
    return false;
  }
  const std::uint8_t now = history_.back().d.f_bracket;
  const std::uint8_t then = history_[history_.size() - kForceSettledSamples].d.f_bracket;
  // Pressing, and the force has not risen by a count over 4 periods: the motor is at (within
  // a few per cent of) its stall force.
  return sensorhand::ForceN(now) > kContactN && now <= then;
}

bool SensorHandHand::Moving() const {
  if (std::abs(estimator_.velocity_m_s()) > kStillM_s) return true;
  if (history_.empty()) return false;
  const Evidence ev = Classify(history_.back().d.state);
  return ev == Evidence::kOpenWay || ev == Evidence::kCloseWay;
}

bool SensorHandHand::Fresh(Clock::TimePoint now) const {
  return samples_ > 0 && Seconds(now - last_sample_t_) <= options_.fresh_s;
}

Status SensorHandHand::LinkFailure() const {
  return link_status_ == Status::kDisconnected ? Status::kDisconnected : Status::kTimeout;
}

// --- Seam calls -------------------------------------------------------------------------------

Status SensorHandHand::StartGoal(Goal goal) {
  std::unique_lock<std::mutex> lock(mu_);
  const Clock::TimePoint t0 = clock_.Now();
  const Clock::TimePoint deadline = t0 + Clock::FromSeconds(options_.call_timeout_s);
  goal.id = next_goal_id_++;
  goal.sample_mark = samples_;
  goal_ = goal;
  const std::uint64_t id = goal.id;
  while (acked_goal_id_ < id) {
    const Clock::TimePoint now = clock_.Now();
    if (now >= deadline) break;
    if (link_status_ == Status::kDisconnected && !Fresh(now) &&
        Seconds(now - t0) >= kDisconnectedFailS) {
      break;
    }
    clock_.WaitUntil(lock, cv_, std::min(deadline, now + std::chrono::milliseconds(10)),
                     [&] { return acked_goal_id_ >= id; });
  }
  if (acked_goal_id_ >= id) return Status::kOk;
  // Not taken: the goal is dropped (the hand will be stopped once it is reachable again), so a
  // failed call has no effect later beyond a command already under way.
  if (goal_.id == id) {
    Goal hold;
    hold.id = next_goal_id_++;
    hold.sample_mark = samples_;
    goal_ = hold;
  }
  ++stats_.failures;
  return LinkFailure();
}

Status SensorHandHand::Open(double opening_m) {
  if (!std::isfinite(opening_m)) return Status::kRejected;
  Goal g;
  g.kind = GoalKind::kOpen;
  g.opening_m = std::clamp(opening_m, 0.0, options_.max_opening_m);
  if (g.opening_m <= options_.opening_tolerance_m) {
    g.opening_m = 0.0;
    g.to_end = true;
  } else if (g.opening_m >= options_.max_opening_m - options_.opening_tolerance_m) {
    g.opening_m = options_.max_opening_m;
    g.to_end = true;
  }
  return StartGoal(g);
}

Status SensorHandHand::Close(double max_force_n) {
  if (!(max_force_n > 0.0)) return Status::kRejected;  // also NaN
  Goal g;
  g.kind = GoalKind::kClose;
  g.force_n = std::min(max_force_n, options_.max_force_n);
  g.close_byte = sensorhand::SpeedByteAtMost(g.force_n / options_.full_force_n);
  return StartGoal(g);
}

Status SensorHandHand::Read(device::HandState* state) {
  std::unique_lock<std::mutex> lock(mu_);
  const Clock::TimePoint t0 = clock_.Now();
  const Clock::TimePoint deadline = t0 + Clock::FromSeconds(options_.call_timeout_s);
  for (;;) {
    const Clock::TimePoint now = clock_.Now();
    if (Fresh(now)) break;
    if (now >= deadline ||
        (link_status_ == Status::kDisconnected && Seconds(now - t0) >= kDisconnectedFailS)) {
      ++stats_.failures;
      return LinkFailure();
    }
    clock_.WaitUntil(lock, cv_, std::min(deadline, now + std::chrono::milliseconds(10)),
                     [&] { return Fresh(clock_.Now()); });
  }
  const Sample& s = history_.back();
  state->t_s = Seconds(s.t);
  state->opening_m = estimator_.opening_m();
  state->grip_force_n = sensorhand::ForceN(s.d.f_bracket);
  state->moving = (!goal_.done && goal_.kind != GoalKind::kHold) || Moving() || !!pending_;
  return Status::kOk;
}

bool SensorHandHand::WaitIdle(double timeout_s) {
  std::unique_lock<std::mutex> lock(mu_);
  return clock_.WaitUntil(lock, cv_, clock_.Now() + Clock::FromSeconds(timeout_s),
                          [&] { return goal_.done && !pending_ && known_.stopped() && !Moving(); });
}

std::vector<SpeedSetting> SensorHandHand::executed() const {
  std::lock_guard<std::mutex> lock(mu_);
  return executed_;
}

std::vector<SpeedSetting> SensorHandHand::unresolved() const {
  std::lock_guard<std::mutex> lock(mu_);
  return unresolved_;
}

SensorHandEstimate SensorHandHand::estimate() const {
  std::lock_guard<std::mutex> lock(mu_);
  SensorHandEstimate e;
  e.t_s = Seconds(t0_ + Clock::FromSeconds(estimator_.time_s()));
  e.opening_m = estimator_.opening_m();
  e.velocity_m_s = estimator_.velocity_m_s();
  e.uncertainty_m = estimator_.uncertainty_m();
  e.referenced = estimator_.referenced();
  e.lost = estimator_.lost();
  e.fixes = estimator_.fixes();
  e.last_correction_m = estimator_.last_correction_m();
  e.max_abs_correction_m = estimator_.max_abs_correction_m();
  return e;
}

SensorHandStats SensorHandHand::stats() const {
  std::lock_guard<std::mutex> lock(mu_);
  return stats_;
}

}  // namespace hgrasp::drivers
