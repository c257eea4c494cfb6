#include "sensorhand/sensorhand_hand.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "common/error.h"

namespace hgrasp::drivers {
namespace {

using device::Status;
using sensorhand::DumpSample;
using sensorhand::Reply;
using sensorhand::SpeedSetting;

constexpr double kPollS = 0.003;             // the I/O thread's read wait
constexpr double kStreamRetryS = 0.1;        // 0x73 at most this often while the stream is silent
constexpr double kDisconnectedFailS = 0.05;  // a vanished port fails a call after this
constexpr std::size_t kHistory = 16;         // samples kept
constexpr int kStallSamples = 5;             // window of the stall test (60 ms)
constexpr double kStallFraction = 0.05;      // moved less than this share of the setting's
constexpr double kStallMinM = 0.00005;       // travel in it (clamped to 0.05..0.2 mm): stalled
constexpr double kStallMaxM = 0.0002;
constexpr std::uint16_t kMovingRaw = 5;  // > 0.05 mm over 2 samples: moving
constexpr std::uint16_t kMeetRaw = 30;   // opening < 0.3 mm: the fingers meet
constexpr int kLostAfter = 2;     // late samples with the old counter before a command is lost
constexpr int kMaxReversals = 3;  // Open() gives up hunting after this many turns

bool SeqAfter(std::uint16_t a, std::uint16_t b) { return static_cast<std::int16_t>(a - b) > 0; }

double Seconds(std::chrono::steady_clock::duration d) {
  return std::chrono::duration<double>(d).count();
}

void Check(bool ok, const char* field, double value, const char* expected) {
  if (!ok)
    throw InputError("", std::string("sensorhand.") + field, std::to_string(value), expected);
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

SensorHandHand::SensorHandHand(std::unique_ptr<ByteLink> link, SensorHandOptions options)
    : link_(std::move(link)),
      options_(options),
      slow_byte_(sensorhand::SpeedByteAtMost(options.slow_speed_m_s / options.full_speed_m_s)) {
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
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
  Check(positive(options_.latency_s), "latency_s", options_.latency_s, "> 0 s");
  Check(positive(options_.call_timeout_s), "call_timeout_s", options_.call_timeout_s, "> 0 s");
  Check(options_.stream_timeout_s >= 2 * sensorhand::kDumpPeriodS, "stream_timeout_s",
        options_.stream_timeout_s, "at least two stream periods (0.024 s)");
  Check(options_.fresh_s >= options_.stream_timeout_s, "fresh_s", options_.fresh_s,
        "at least stream_timeout_s");
  Check(std::isfinite(options_.transit_s) && options_.transit_s >= 0.0, "transit_s",
        options_.transit_s, ">= 0 s");
  const Clock::time_point now = Clock::now();
  last_empty_t_ = now;
  last_sample_t_ = now - std::chrono::hours(1);
  last_stream_start_ = last_sample_t_;
  goal_.id = next_goal_id_++;  // hold: stop the fingers if they move when we connect
  thread_ = std::thread([this] { IoLoop(); });
}

SensorHandHand::~SensorHandHand() {
  {
    std::unique_lock<std::mutex> lock(mu_);
    shutting_down_ = true;
    Goal hold;
    hold.id = next_goal_id_++;
    hold.sample_mark = samples_;
    goal_ = hold;
    const Clock::time_point deadline = Clock::now() + std::chrono::milliseconds(300);
    cv_.wait_until(lock, deadline, [&] { return !pending_ && known_.stopped(); });
    send_dump_stop_ = true;
    cv_.wait_until(lock, Clock::now() + std::chrono::milliseconds(50),
                   [&] { return !send_dump_stop_; });
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

// --- The I/O thread ---------------------------------------------------------------------------

void SensorHandHand::IoLoop() {
  std::vector<std::uint8_t> out;
  for (;;) {
    ReadOnce(kPollS);
    // Drain: what is decided next rests on everything that has arrived, and a command's
    // reference sample is the newest one (see Pending).
    while (ReadOnce(0.0)) {
    }
    out.clear();
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (stop_) return;
      Step(Clock::now(), &out);
    }
    if (!out.empty()) {
      const Status w = link_->Write(out);
      const Clock::time_point t_w = Clock::now();
      std::lock_guard<std::mutex> lock(mu_);
      if (w != Status::kOk) link_status_ = w;
      if (pending_ && !pending_->written) {
        // Samples the hand may have sent before the command reached it: those made since the
        // reference sample could have been made (it arrived after t_floor, so it was made after
        // t_floor - transit) until the command arrives (t_w + transit), one per period, plus one.
        const double span = Seconds(t_w - pending_->t_floor) + 2.0 * options_.transit_s;
        const int n = static_cast<int>(std::ceil(span / sensorhand::kDumpPeriodS)) + 1;
        pending_->seq_after = static_cast<std::uint16_t>(pending_->seq_ref + std::min(n, 30000));
        pending_->t_written = t_w;
        pending_->written = true;
      }
    }
    cv_.notify_all();
  }
}

bool SensorHandHand::ReadOnce(double timeout_s) {
  std::uint8_t buf[256];
  std::size_t n = 0;
  // Taken before the read: if it finds nothing, the link was empty at some moment after this,
  // whatever the scheduler did to this thread meanwhile.
  const Clock::time_point before = Clock::now();
  const Status s = link_->Read(buf, timeout_s, &n);
  const Clock::time_point now = Clock::now();
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

void SensorHandHand::HandleReply(const Reply& r, Clock::time_point now) {
  switch (r.kind) {
    case Reply::Kind::kDump:
      HandleSample(r.dump, now);
      break;
    case Reply::Kind::kSpeedEcho:
      // Counted only: an echo is 4 bytes under an 8-bit sum, which a resynchronisation inside
      // a damaged stream frame can fake; the stream's counter decides (PROTOCOL.md).
      ++stats_.echoes;
      break;
    case Reply::Kind::kDumpStartEcho:
    case Reply::Kind::kDumpStopEcho:
      break;
  }
}

void SensorHandHand::HandleSample(const DumpSample& d, Clock::time_point now) {
  const bool first = samples_ == 0;
  if (!history_.empty()) {
    const std::uint16_t gap = static_cast<std::uint16_t>(d.seq - history_.back().d.seq);
    if (gap == 0 || gap >= 1000) {
      history_.clear();  // the hand restarted its numbering (power cycle): start afresh
    } else {
      stats_.missed_samples += gap - 1u;
    }
  }
  ++samples_;
  ++stats_.samples;
  last_sample_t_ = now;
  history_.push_back({d, now, last_empty_t_});
  if (history_.size() > kHistory) history_.pop_front();

  bool resolved = false;
  if (pending_ && pending_->written) {
    const std::uint8_t advanced = static_cast<std::uint8_t>(d.counter - pending_->counter0);
    if (advanced == 1 && d.speed == pending_->cmd) {
      // Executed: the hand counted it and runs with it.
      executed_.push_back(pending_->cmd);
      ++stats_.executed;
      acked_goal_id_ = std::max(acked_goal_id_, pending_->goal_id);
      pending_.reset();
      resolved = true;
    } else if (advanced == 0 && d.speed == pending_->before) {
      // Made after the command must have reached the hand: numbered beyond the bound, or
      // arrived after a moment when the link was empty 2 transits after the write (so made
      // after t_w + transit).
      const bool late = SeqAfter(d.seq, pending_->seq_after) ||
                        Seconds(last_empty_t_ - pending_->t_written) >= 2.0 * options_.transit_s;
      if (late && ++pending_->stale >= kLostAfter) {
        // Two samples made after the command must have reached the hand still show the old
        // counter: it never arrived whole. Safe to send again.
        ++stats_.lost;
        last_lost_ = pending_->cmd;
        pending_.reset();
        resolved = true;
      }
    } else {
      // Something else changed the hand (a power cycle, another host): believe the stream.
      ++stats_.anomalies;
      pending_.reset();
      resolved = true;
    }
  }
  if (pending_) return;  // the setting stays as it was until the command is resolved
  if (!first && !resolved && d.counter != known_counter_) ++stats_.anomalies;
  if (first || d.speed != known_) setting_since_seq_ = d.seq;
  known_ = d.speed;
  known_counter_ = d.counter;
}

void SensorHandHand::Step(Clock::time_point now, std::vector<std::uint8_t>* out) {
  if (send_dump_stop_) {
    const auto stop = sensorhand::EncodeDumpStop();
    out->insert(out->end(), stop.begin(), stop.end());
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
    last_stream_start_ = now;
    ++stats_.stream_starts;
  }
  // One command in flight; decisions on fresh samples only, one per sample.
  if (pending_ || silent || samples_ == decided_samples_) return;
  decided_samples_ = samples_;
  if (samples_ <= goal_.sample_mark) return;
  const SpeedSetting want = Control();
  if (want == known_) {
    acked_goal_id_ = std::max(acked_goal_id_, goal_.id);
    return;
  }
  Pending p;
  p.cmd = want;
  p.before = known_;
  p.counter0 = known_counter_;
  p.seq_ref = history_.back().d.seq;
  p.t_floor = history_.back().arrived_after;
  p.goal_id = goal_.id;
  pending_ = p;
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

SpeedSetting SensorHandHand::Control() {
  if (goal_.done) return sensorhand::kStop;
  const DumpSample& s = history_.back().d;
  const double y = sensorhand::OpeningM(s.opening);
  const double force = sensorhand::ForceN(s.f_bracket);
  switch (goal_.kind) {
    case GoalKind::kHold:
      goal_.done = true;
      return sensorhand::kStop;

    case GoalKind::kClose: {
      const double step =
          options_.full_force_n / (sensorhand::kSpeedMax - sensorhand::kSpeedMin + 1);
      if (goal_.backing_off || force > goal_.force_n + step) {
        // Pressing harder than asked (a stronger grip before): ease off slowly down to it.
        goal_.backing_off = true;
        if (force > goal_.force_n) return {slow_byte_, 0};
        goal_.done = true;
        return sensorhand::kStop;
      }
      if (force >= goal_.force_n || s.opening <= kMeetRaw || (known_.close != 0 && Stalled())) {
        // At the force limit, stalled on the object, or the fingers meet: speed 0 holds the
        // grip (the gear does not back-drive).
        goal_.done = true;
        return sensorhand::kStop;
      }
      return {0, goal_.close_byte};
    }

    case GoalKind::kOpen: {
      const double e = goal_.opening_m - y;
      const double tol = options_.opening_tolerance_m;
      const double slow_zone = StopLead(options_.full_speed_m_s) + 0.004;
      auto start = [&](int dir) -> SpeedSetting {
        if (goal_.last_dir != 0 && dir != goal_.last_dir && ++goal_.reversals > kMaxReversals) {
          goal_.done = true;
          return sensorhand::kStop;
        }
        goal_.last_dir = dir;
        const std::uint8_t b = std::abs(e) > slow_zone ? sensorhand::kSpeedMax : slow_byte_;
        return dir > 0 ? SpeedSetting{b, 0} : SpeedSetting{0, b};
      };
      if (known_.stopped()) {
        if (Moving()) return sensorhand::kStop;  // let the fingers settle, then judge
        if (std::abs(e) <= tol) {
          goal_.done = true;
          return sensorhand::kStop;
        }
        return start(e > 0.0 ? 1 : -1);
      }
      const int dir = known_.open != 0 ? 1 : -1;
      const double v = SpeedOf(dir > 0 ? known_.open : known_.close);
      if (Stalled()) {
        // Blocked: an object between the fingers, or an end stop.
        goal_.done = true;
        return sensorhand::kStop;
      }
      if (dir * e < -tol) return start(-dir);  // running the wrong way (a new goal)
      if (dir * e <= StopLead(v)) return sensorhand::kStop;
      if (v > SpeedOf(slow_byte_) && dir * e <= slow_zone) {
        return dir > 0 ? SpeedSetting{slow_byte_, 0} : SpeedSetting{0, slow_byte_};
      }
      return known_;
    }
  }
  return sensorhand::kStop;
}

bool SensorHandHand::Stalled() const {
  if (known_.stopped() || history_.empty()) return false;
  const DumpSample& newest = history_.back().d;
  // Enough samples under the current setting to judge.
  if (!SeqAfter(newest.seq, static_cast<std::uint16_t>(setting_since_seq_ + kStallSamples - 1))) {
    return false;
  }
  std::uint16_t lo = newest.opening, hi = newest.opening;
  const std::uint16_t from = static_cast<std::uint16_t>(newest.seq - kStallSamples);
  int seen = 0;
  for (const Sample& h : history_) {
    if (SeqAfter(from, h.d.seq)) continue;
    lo = std::min(lo, h.d.opening);
    hi = std::max(hi, h.d.opening);
    ++seen;
  }
  // Judge only a window with most of its samples: after a dropout the first sample stands
  // alone and shows no motion.
  if (seen < kStallSamples - 1) return false;
  // Stalled: the fingers covered less than 5% of what the setting asks for in the window
  // (between 0.05 and 0.2 mm): against an object that is above 95% of the stall force.
  const double expected_m =
      SpeedOf(std::max(known_.open, known_.close)) * kStallSamples * sensorhand::kDumpPeriodS;
  const double limit_m = std::clamp(kStallFraction * expected_m, kStallMinM, kStallMaxM);
  return sensorhand::OpeningM(hi) - sensorhand::OpeningM(lo) < limit_m;
}

bool SensorHandHand::Moving() const {
  if (history_.size() < 3) return false;
  const std::uint16_t a = history_.back().d.opening;
  const std::uint16_t b = history_[history_.size() - 3].d.opening;
  return (a > b ? a - b : b - a) > kMovingRaw;
}

bool SensorHandHand::Fresh(Clock::time_point now) const {
  return samples_ > 0 && Seconds(now - last_sample_t_) <= options_.fresh_s;
}

Status SensorHandHand::LinkFailure() const {
  return link_status_ == Status::kDisconnected ? Status::kDisconnected : Status::kTimeout;
}

// --- Seam calls -------------------------------------------------------------------------------

Status SensorHandHand::StartGoal(Goal goal) {
  std::unique_lock<std::mutex> lock(mu_);
  const Clock::time_point t0 = Clock::now();
  const Clock::time_point deadline =
      t0 + std::chrono::duration_cast<Clock::duration>(
               std::chrono::duration<double>(options_.call_timeout_s));
  goal.id = next_goal_id_++;
  goal.sample_mark = samples_;
  goal_ = goal;
  const std::uint64_t id = goal.id;
  while (acked_goal_id_ < id) {
    const Clock::time_point now = Clock::now();
    if (now >= deadline) break;
    if (link_status_ == Status::kDisconnected && !Fresh(now) &&
        Seconds(now - t0) >= kDisconnectedFailS) {
      break;
    }
    cv_.wait_until(lock, std::min(deadline, now + std::chrono::milliseconds(10)));
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
  const Clock::time_point t0 = Clock::now();
  const Clock::time_point deadline =
      t0 + std::chrono::duration_cast<Clock::duration>(
               std::chrono::duration<double>(options_.call_timeout_s));
  for (;;) {
    const Clock::time_point now = Clock::now();
    if (Fresh(now)) break;
    if (now >= deadline ||
        (link_status_ == Status::kDisconnected && Seconds(now - t0) >= kDisconnectedFailS)) {
      ++stats_.failures;
      return LinkFailure();
    }
    cv_.wait_until(lock, std::min(deadline, now + std::chrono::milliseconds(10)));
  }
  const Sample& s = history_.back();
  state->t_s = Seconds(s.t.time_since_epoch());
  state->opening_m = sensorhand::OpeningM(s.d.opening);
  state->grip_force_n = sensorhand::ForceN(s.d.f_bracket);
  state->moving = (!goal_.done && goal_.kind != GoalKind::kHold) || Moving() || !!pending_;
  return Status::kOk;
}

bool SensorHandHand::WaitIdle(double timeout_s) {
  std::unique_lock<std::mutex> lock(mu_);
  return cv_.wait_for(lock, std::chrono::duration<double>(timeout_s),
                      [&] { return goal_.done && !pending_ && known_.stopped() && !Moving(); });
}

std::vector<SpeedSetting> SensorHandHand::executed() const {
  std::lock_guard<std::mutex> lock(mu_);
  return executed_;
}

SensorHandStats SensorHandHand::stats() const {
  std::lock_guard<std::mutex> lock(mu_);
  return stats_;
}

}  // namespace hgrasp::drivers
