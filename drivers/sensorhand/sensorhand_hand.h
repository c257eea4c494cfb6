#pragma once
/// @file The Otto Bock SensorHand Speed driver behind device::Hand
/// (drivers/sensorhand/PROTOCOL.md), for a stock hand: its data stream gives grip force, state
/// and current every 12 ms but no finger position, and it echoes each command. The hand only
/// takes speeds (command 0x75), so Open and Close are closed loops in the driver: an I/O
/// loop estimates the opening by dead reckoning (OpeningEstimator: the speeds the hand took and
/// when, the fingers' acceleration, the motor's stall against an object, set to the limit at the
/// end stops) and sends the next speed setting (0 when the estimate reaches the target, at the
/// force limit, when the fingers stall). That loop alone owns the link; the seam calls hand it
/// goals and wait for its answer under a mutex. The loop runs on the driver's clock
/// (common/clock.h): a thread of its own on the wall clock, events of a SimClock in simulated
/// time (tests, the twin in lockstep).
///
/// Never executed twice: a speed command sets a state. One command is in flight at a time; it
/// counts as executed when the hand's echo of it arrives, or, the echo lost, when two samples
/// show the new setting by their state byte (moving its way, blocked, idle) in a way the old
/// one cannot (at once, when the samples before showed the old setting settled; else samples
/// the hand made after the command must have reached it); as lost only when two samples made
/// after the command must have reached it show the old setting and none the new. Only then may
/// a command be sent again; while neither is known (a dropout, a cut cable), nothing is sent.
/// The driver never changes a speed within a direction without a stop between, so that the
/// state byte can always tell the two settings apart.
///
/// The opening is a dead-reckoned estimate: exact at the end stops, off by tenths of a
/// millimetre after a few grips (PROTOCOL.md, "How accurate the estimate is"); estimate() gives
/// it with a worst-case bound. Home() (or Open(max_opening_m)) before a grasp makes it exact.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "common/clock.h"
#include "device/hand.h"
#include "sensorhand/opening_estimator.h"
#include "sensorhand/sensorhand_codec.h"
#include "serial/byte_link.h"
#include "serial/command_log.h"
#include "serial/serial_port.h"

namespace hgrasp::drivers {

/// Driver options, all SI. Defaults: the robot's hand (models/humanoid.xml, DESIGN.md), our
/// speed scale (PROTOCOL.md) and the emulator's timing; a real hand needs its own
/// full_speed_m_s, full_force_n, accel_m_s2 and latency_s (measured once), and transit_s for its
/// line.
struct SensorHandOptions {
  /// Widest pad distance (m), the open end stop: models/humanoid.xml, thumb slide range
  /// 0..0.05 m, opening = 2 q.
  double max_opening_m = 0.10;
  /// Strongest grip (N): DESIGN.md, grip force 10-100 N.
  double max_force_n = 100.0;
  /// Opening rate at speed byte 0x85 (m/s): the figure Otto Bock quotes for the SensorHand
  /// Speed, 300 mm/s (ours: PROTOCOL.md). Slower bytes scale linearly (SpeedFraction). The
  /// opening estimate integrates it: its error is the estimate's error per metre travelled.
  double full_speed_m_s = 0.30;
  /// Grip force the motor stalls at with close speed 0x85 (N); slower bytes scale linearly.
  double full_force_n = 100.0;
  /// Finger acceleration and deceleration (m/s^2): the estimate's speed ramps, and the run-on
  /// after a stop.
  double accel_m_s2 = 10.0;
  /// Speed of the last millimetres before a target opening (m/s).
  double slow_speed_m_s = 0.04;
  /// From the driver writing a speed command to the hand acting on it (s): the bytes on the
  /// line (5 at 19200 baud: 2.6 ms on a real one) and the hand's reaction. Stops are sent this
  /// much ahead of where the estimate should stop; a command whose echo was lost is taken to
  /// have acted this long after its write (with an echo: in the middle of write and echo).
  double latency_s = 0.001;
  /// Open() is done within this distance of its target, as estimated (m).
  double opening_tolerance_m = 0.001;
  /// The opening assumed when the driver starts (m), until an end stop fixes it: the robot's
  /// start pose (models/humanoid.xml, 0.08 m). Open(max_opening_m) or Home() finds it.
  double initial_opening_m = 0.08;
  /// How far initial_opening_m may be off (m): the estimate's uncertainty at the start.
  double initial_uncertainty_m = 0.0;
  /// Relative error of full_speed_m_s (a share: 0.02 = 2%): the reported uncertainty grows by
  /// this share of the travel since the last end stop.
  double speed_error = 0.02;
  /// How long a seam call may wait for the hand (s): a cut link is reported after it.
  double call_timeout_s = 0.4;
  /// No stream sample for this long: the stream is restarted (0x73) (s).
  double stream_timeout_s = 0.06;
  /// A Read() needs a sample at most this old (s).
  double fresh_s = 0.1;
  /// Worst one-way delay (s): from the hand starting to send a frame until the host has all of
  /// it, and from the host's write until the hand has the command; the line, the adapter and a
  /// stream frame's time on the wire (12 bytes at 19200 baud: 6 ms). Sizes the wait before the
  /// stream's state byte may judge a command whose echo was lost.
  double transit_s = 0.03;
  /// A command neither echoed nor judged by the stream for this long while samples arrive (s):
  /// the driver gives up knowing and stops the fingers (a hand whose state byte it cannot read).
  double unresolved_s = 1.0;
};

/// The driver's opening estimate (OpeningEstimator) at the newest sample.
struct SensorHandEstimate {
  double t_s = 0.0;                ///< the driver's clock (s), as HandState::t_s
  double opening_m = 0.0;          ///< estimated pad distance (m)
  double velocity_m_s = 0.0;       ///< estimated rate (m/s)
  double uncertainty_m = 0.0;      ///< bound on the estimate's error (m), 0 right at an end stop
  bool referenced = false;         ///< an end stop has fixed the estimate since the start
  bool lost = false;               ///< closed onto an object unseen (a dropout): Open homes first
  int fixes = 0;                   ///< end-stop fixes so far
  double last_correction_m = 0.0;  ///< the last fix's correction (m, true - estimate)
  double max_abs_correction_m = 0.0;  ///< the largest |correction| so far (m)
};

/// Counters of the link's behaviour since the driver was made.
struct SensorHandStats {
  std::uint64_t samples = 0;            ///< stream frames received
  std::uint64_t echoes = 0;             ///< command echoes received
  std::uint64_t stray_echoes = 0;       ///< of which matched no command in flight
  std::uint64_t discarded_bytes = 0;    ///< bytes thrown away while resynchronising
  std::uint64_t commands = 0;           ///< speed commands written (first sends and re-sends)
  std::uint64_t executed = 0;           ///< of which seen executed (by echo or by the stream)
  std::uint64_t executed_unechoed = 0;  ///< of which executed, echo lost: told by the stream
  std::uint64_t lost = 0;               ///< of which seen not executed (dropped, damaged)
  std::uint64_t unresolved = 0;         ///< of which never told either way (unresolved_s)
  std::uint64_t resends = 0;            ///< a lost command sent again
  std::uint64_t stops_inserted = 0;     ///< a stop sent between two speeds of one direction
  std::uint64_t stream_starts = 0;      ///< 0x73 written to restart a silent stream
  std::uint64_t anomalies = 0;          ///< the stream contradicted the setting (a reset, ...)
  std::uint64_t failures = 0;           ///< seam calls that returned a failure status
  double echo_delay_mean_s = 0.0;       ///< from writing a command to reading its echo (s)
  double echo_delay_max_s = 0.0;
};

class SensorHandHand final : public device::Hand {
 public:
  /// Takes the link (a SerialPort at 19200 8N1, possibly wrapped in a FaultyLink) and starts
  /// the I/O loop, which starts the data stream. Throws InputError on bad options.
  /// `clock`: what the driver reads the time from and waits on, its I/O loop included (a
  /// thread of its own on the wall clock; events on a SimClock).
  explicit SensorHandHand(std::unique_ptr<ByteLink> link, SensorHandOptions options = {},
                          Clock& clock = Clock::Wall());
  /// Stops the fingers (speed 0, which holds a grip: the gear does not back-drive) and the
  /// stream, as far as the link allows within about 0.3 s.
  ~SensorHandHand() override;
  SensorHandHand(const SensorHandHand&) = delete;
  SensorHandHand& operator=(const SensorHandHand&) = delete;

  /// The latest stream sample: the estimated opening (estimate() says how good it is), the grip
  /// force (bracket force), moving (the fingers move or a goal is under way). t_s: the driver's
  /// clock (s) when the sample arrived. Waits up to call_timeout_s for a sample when the stream is
  /// silent.
  device::Status Read(device::HandState* state) override;
  /// Starts moving the fingers to `opening_m` (clamped to 0..max_opening_m) and returns when
  /// the hand has taken the first speed command (or needed none); the I/O loop stops the
  /// fingers there, as estimated. A target within opening_tolerance_m of an end (0 or
  /// max_opening_m) drives the fingers into that end until the stream shows them blocked, which
  /// fixes the estimate there. An object in the way (a grip force while closing) stops them at
  /// it, touching lightly. If the estimate is lost (estimate().lost) the fingers first open to
  /// the end stop. Read().moving goes false when done. kRejected for a non-finite opening.
  device::Status Open(double opening_m) override;
  /// Starts closing at the speed whose stall force is at most `max_force_n` (clamped to
  /// max_force_n; raised to the smallest step, about 1.2 N) and returns when the hand has
  /// taken the command; the I/O loop stops the fingers (speed 0) when the force reaches the
  /// limit, the fingers stall on an object, or they meet. kRejected unless max_force_n > 0.
  device::Status Close(double max_force_n) override;
  /// Open(max_opening_m): the fingers run to the open end stop, which fixes the estimate.
  device::Status Home() { return Open(options_.max_opening_m); }

  /// Waits until no goal is under way and no command is in flight (s); false on timeout.
  bool WaitIdle(double timeout_s);
  /// Every speed setting the driver saw the hand execute, in order: each command once.
  std::vector<sensorhand::SpeedSetting> executed() const;
  /// Commands whose outcome the driver never learnt (unresolved_s), in order.
  std::vector<sensorhand::SpeedSetting> unresolved() const;
  /// The commands the driver sent the hand, in the order sent, as sensorhand::Encode frames
  /// them (the encoding of SensorHandEmulator::log). A speed setting is confirmed once the
  /// driver sees it executed (executed(): by its echo or the stream), removed when the stream
  /// shows it lost, unconfirmed while neither (or never: unresolved()). The stream's start
  /// (0x73, sent again every kStreamRetryS while the stream is silent: a start of a running
  /// stream changes nothing) and stop (0x7A, at destruction) are unconfirmed: their echoes are
  /// not awaited.
  const CommandLog<sensorhand::Command>& command_log() const { return command_log_; }
  SensorHandEstimate estimate() const;
  SensorHandStats stats() const;

  /// The serial framing the hand needs: 19200 8N1.
  static SerialConfig SerialConfigFor(std::string port);

 private:
  enum class GoalKind { kHold, kOpen, kClose };
  struct Goal {
    GoalKind kind = GoalKind::kHold;
    double opening_m = 0.0;  ///< kOpen: target
    bool to_end = false;     ///< kOpen: drive into the end stop at the target
    double force_n = 0.0;    ///< kClose: limit
    std::uint64_t id = 0;
    std::uint64_t sample_mark = 0;  ///< samples_ when it was set: act on later samples only
    std::uint8_t close_byte = 0;    ///< kClose: the speed byte whose stall force fits the limit
    bool done = false;
    bool backing_off = false;  ///< kClose: easing a stronger grip down to the limit
    bool contact = false;      ///< kOpen: stopped at an object, easing a hard press off
    bool at_object = false;    ///< kOpen: the pads met an object during this goal
    bool homing = false;       ///< kOpen: the estimate was lost, finding the open end stop
    int last_dir = 0;          ///< kOpen: +1 opening, -1 closing, 0 not moved yet
    bool moved = false;        ///< kOpen: the hand took a move of this goal (not just sent)
    int reversals = 0;
  };
  /// What a sample's state byte says about the speed setting in force.
  enum class Evidence { kNone, kStopped, kRunning, kOpenWay, kCloseWay };
  struct Observation {
    double t_s = 0.0;  ///< estimator time of its arrival
    double force_n = 0.0;
    std::uint8_t state = 0;
  };
  struct Pending {
    sensorhand::SpeedSetting cmd, before;
    Clock::TimePoint t_write_begin{};  ///< before the write began
    Clock::TimePoint t_written{};      ///< after the write returned
    std::size_t write_bytes = 0;       ///< bytes of that write (the command last)
    bool written = false;
    sensorhand::OpeningEstimator at_write;  ///< the estimate as the command was written
    std::vector<Observation> since_write;   ///< samples since, to replay once it is resolved
    int votes_new = 0, votes_old = 0;       ///< samples that show either setting
    bool before_settled = false;            ///< the newest sample before it already showed `before`
    /// The pads pressed an object (a grip force) since kContactMemoryS before the write.
    bool contact = false;
    std::uint64_t goal_id = 0;
    CommandLog<sensorhand::Command>::Id logged = 0;  ///< its entry in command_log_
  };
  struct Sample {
    sensorhand::DumpSample d;
    Clock::TimePoint t{};  ///< when it was read
  };

  /// One turn of the I/O loop: reads (waiting up to wait_s), decides, writes. False once
  /// stopped.
  bool IoTurn(double wait_s);
  /// Reads once (waiting up to timeout_s) and handles what arrived; false when nothing came.
  bool ReadOnce(double timeout_s);
  void HandleReply(const sensorhand::Reply& r, Clock::TimePoint now);
  void HandleSample(const sensorhand::DumpSample& d, Clock::TimePoint now);
  /// A sample while a written command is unresolved: a vote for the new setting or the old
  /// one, judged against `prior` (the estimate under the old).
  void JudgePending(const sensorhand::OpeningEstimator& prior, const Observation& o, Evidence ev);
  /// Counts a sample's vote; enough of them resolve the pending command executed or lost.
  void CountVote(bool shows_new, bool shows_old, bool late, Evidence ev);
  /// No command pending: a stream that keeps contradicting the known setting is an anomaly.
  void CheckKnown(Evidence ev, double t, Clock::TimePoint now);
  /// The estimate at t_s (estimator time) had the pending command taken effect latency_s after
  /// its write, from the samples' forces since.
  sensorhand::OpeningEstimator Hypothesis(const Pending& p, double t_s) const;
  /// The pending command took effect at t_exec_s (estimator time), known to +-uncertainty_s.
  void ResolveExecuted(double t_exec_s, double uncertainty_s);
  /// Decides what to write now (under mu_): stream restart, the next speed command.
  void Step(Clock::TimePoint now, std::vector<std::uint8_t>* out);
  /// The speed setting the current goal wants now; may mark it done.
  sensorhand::SpeedSetting Control(Clock::TimePoint now);
  sensorhand::SpeedSetting ControlClose(double force);
  sensorhand::SpeedSetting ControlOpen(Clock::TimePoint now, double force);
  /// The estimate lost: into the open end stop, which fixes it.
  sensorhand::SpeedSetting Homing();
  /// kOpen with the fingers stopped: e is the target less the opening when a command takes
  /// effect.
  sensorhand::SpeedSetting OpenFromRest(double e, double force);
  /// kOpen with a speed set: go on, or stop where the fingers would come to rest on the target.
  sensorhand::SpeedSetting OpenOnTheWay(const sensorhand::OpeningEstimator& ahead, double force);
  /// Full speed towards dir (+1 open, -1 close), slow within stopping reach of the target.
  sensorhand::SpeedSetting Toward(int dir, double distance) const;
  /// The lightest touch the hand keeps on an object it met: the slow speed's stall force.
  double LightTouchN() const;
  /// Whether the newest sample shows the fingers blocked under the current setting.
  bool Blocked() const;
  /// Whether the grip force has stopped rising under the current close setting.
  bool ForceSettled() const;
  bool Moving() const;
  bool Fresh(Clock::TimePoint now) const;
  /// Sets a goal and waits for the hand to take its first command.
  device::Status StartGoal(Goal goal);
  /// The status a call that could not reach the hand returns.
  device::Status LinkFailure() const;
  double SpeedOf(std::uint8_t b) const;  ///< m/s of a speed byte
  double StopLead(double speed) const;   ///< m the fingers run on after a stop decision
  double ToS(Clock::TimePoint t) const;  ///< estimator time (s since construction)
  static Evidence Classify(std::uint8_t state);
  static bool Consistent(const sensorhand::SpeedSetting& s, Evidence e);
  /// Whether a sample read after the link was last empty at `last_empty` was made late enough
  /// after the command in force since `since` to judge it by the state byte.
  bool LateEnough(Clock::TimePoint since) const;

  const std::unique_ptr<ByteLink> link_;
  const SensorHandOptions options_;
  const std::uint8_t slow_byte_;
  Clock& clock_;
  const Clock::TimePoint t0_;

  mutable std::mutex mu_;
  std::condition_variable cv_;
  sensorhand::ReplyDecoder decoder_;  // I/O loop only
  bool stop_ = false;
  bool shutting_down_ = false;
  bool send_dump_stop_ = false;
  bool dump_stopped_ = false;
  device::Status link_status_ = device::Status::kOk;
  std::deque<Sample> history_;  ///< the latest samples, newest last
  std::uint64_t samples_ = 0;
  Clock::TimePoint last_empty_t_{};  ///< the last read that found nothing began then
  Clock::TimePoint last_sample_t_{};
  Clock::TimePoint last_stream_start_{};
  sensorhand::SpeedSetting known_;        ///< the hand's setting, as last known
  Clock::TimePoint known_since_{};        ///< when it was written (it took effect after)
  Clock::TimePoint known_resolved_t_{};   ///< the newest sample when the driver learnt it
  std::uint64_t known_since_sample_ = 0;  ///< samples_ then
  bool setting_known_ = false;            ///< the first sample has told whether the hand is still
  bool known_shown_ = false;    ///< a settled sample has shown known_ since it took effect
  bool resend_anyway_ = false;  ///< send the next setting even if it equals known_
  int contradictions_ = 0;      ///< late samples in a row that contradict known_
  sensorhand::OpeningEstimator estimator_;
  std::optional<Pending> pending_;
  std::optional<sensorhand::SpeedSetting> last_lost_;  ///< the last command seen lost
  Goal goal_;
  std::uint64_t next_goal_id_ = 1;
  std::uint64_t acked_goal_id_ = 0;  ///< the newest goal whose first command the hand took
  std::vector<sensorhand::SpeedSetting> executed_, unresolved_;
  CommandLog<sensorhand::Command> command_log_;
  SensorHandStats stats_;
  std::unique_ptr<Clock::Worker> io_;  ///< the I/O loop; last, so that it stops first
};

}  // namespace hgrasp::drivers
