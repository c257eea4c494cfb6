#pragma once
/// @file The Otto Bock SensorHand Speed driver behind device::Hand
/// (drivers/sensorhand/PROTOCOL.md). The hand only takes speeds (command 0x75), so Open and Close
/// are closed loops in the driver: a background thread reads the hand's data stream (opening,
/// grip force, speed setting, command counter; one sample every 12 ms) and sends the next speed
/// setting (slower near the target, 0 at the target opening, 0 at the force limit or when the
/// fingers stall). That thread alone owns the link; the seam calls hand it goals and wait for
/// its answer under a mutex.
///
/// Never executed twice: a speed command sets a state and the stream reports, in every sample,
/// the setting in force and how many 0x75 commands the hand has executed. One command is in
/// flight at a time; it counts as executed when a sample shows the counter one further on and
/// the new setting, and as lost only when two samples that the hand made after the command
/// must have reached it (told by their sample numbers, or by when they arrived) still show the
/// old counter. Only then may a command be sent again; while neither is known (a dropout, a cut
/// cable), nothing is sent.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "device/hand.h"
#include "sensorhand/sensorhand_codec.h"
#include "serial/byte_link.h"
#include "serial/serial_port.h"

namespace hgrasp::drivers {

/// Driver options. Defaults: the robot's hand (models/humanoid.xml, DESIGN.md) and our speed
/// scale (PROTOCOL.md); a real hand would need its own full_speed_m_s and full_force_n.
struct SensorHandOptions {
  /// Widest pad distance (m): models/humanoid.xml, thumb slide range 0..0.05 m, opening = 2 q.
  double max_opening_m = 0.10;
  /// Strongest grip (N): DESIGN.md, grip force 10-100 N.
  double max_force_n = 100.0;
  /// Opening rate at speed byte 0x85 (m/s): the figure Otto Bock quotes for the SensorHand
  /// Speed, 300 mm/s (ours: PROTOCOL.md). Slower bytes scale linearly (SpeedFraction).
  double full_speed_m_s = 0.30;
  /// Grip force the motor stalls at with close speed 0x85 (N); slower bytes scale linearly.
  double full_force_n = 100.0;
  /// Finger acceleration (m/s^2), to predict how far the fingers run on after a stop.
  double accel_m_s2 = 10.0;
  /// Speed of the last millimetres before a target opening (m/s): overshoot at it stays
  /// within opening_tolerance_m.
  double slow_speed_m_s = 0.04;
  /// From a stream sample to the hand acting on the command it prompts (s): the line both ways
  /// plus half a stream period, for the run-on after a stop (speed x latency + v^2 / 2a).
  double latency_s = 0.012;
  /// Open() is done within this distance of its target (m).
  double opening_tolerance_m = 0.001;
  /// How long a seam call may wait for the hand (s): a cut link is reported after it.
  double call_timeout_s = 0.4;
  /// No stream sample for this long: the stream is restarted (0x73) (s).
  double stream_timeout_s = 0.06;
  /// A Read() needs a sample at most this old (s).
  double fresh_s = 0.1;
  /// Worst one-way delay (s): from the hand starting to send a frame until the host has all of
  /// it, and from the host's write until the hand has the command; the line, the adapter and a
  /// stream frame's time on the wire (19 bytes at 19200 baud: 10 ms). Sizes the wait before a
  /// command counts as lost.
  double transit_s = 0.03;
};

/// Counters of the link's behaviour since the driver was made.
struct SensorHandStats {
  std::uint64_t samples = 0;          ///< stream frames received
  std::uint64_t missed_samples = 0;   ///< stream frames lost on the way (gaps in their numbers)
  std::uint64_t echoes = 0;           ///< command echoes received
  std::uint64_t discarded_bytes = 0;  ///< bytes thrown away while resynchronising
  std::uint64_t commands = 0;         ///< speed commands written (first sends and re-sends)
  std::uint64_t executed = 0;         ///< of which seen executed
  std::uint64_t lost = 0;             ///< of which seen not executed (dropped, damaged)
  std::uint64_t resends = 0;          ///< a lost command sent again
  std::uint64_t stream_starts = 0;    ///< 0x73 written to restart a silent stream
  std::uint64_t anomalies = 0;        ///< counter or setting changed by something else
  std::uint64_t failures = 0;         ///< seam calls that returned a failure status
};

class SensorHandHand final : public device::Hand {
 public:
  /// Takes the link (a SerialPort at 19200 8N1, possibly wrapped in a FaultyLink) and starts
  /// the I/O thread, which starts the data stream. Throws InputError on bad options.
  explicit SensorHandHand(std::unique_ptr<ByteLink> link, SensorHandOptions options = {});
  /// Stops the fingers (speed 0, which holds a grip: the gear does not back-drive) and the
  /// stream, as far as the link allows within about 0.3 s.
  ~SensorHandHand() override;
  SensorHandHand(const SensorHandHand&) = delete;
  SensorHandHand& operator=(const SensorHandHand&) = delete;

  /// The latest stream sample: opening, grip force (bracket force), moving (the fingers move
  /// or a goal is under way). t_s: steady clock (s) when the sample arrived. Waits up to
  /// call_timeout_s for a sample when the stream is silent.
  device::Status Read(device::HandState* state) override;
  /// Starts moving the fingers to `opening_m` (clamped to 0..max_opening_m) and returns when
  /// the hand has taken the first speed command (or needed none); the I/O thread stops the
  /// fingers there. Read().moving goes false when done. kRejected for a non-finite opening.
  device::Status Open(double opening_m) override;
  /// Starts closing at the speed whose stall force is at most `max_force_n` (clamped to
  /// max_force_n; raised to the smallest step, about 1.2 N) and returns when the hand has
  /// taken the command; the I/O thread stops the fingers (speed 0) when the force reaches the
  /// limit, the fingers stall on an object, or they meet. kRejected unless max_force_n > 0.
  device::Status Close(double max_force_n) override;

  /// Waits until no goal is under way and no command is in flight (s); false on timeout.
  bool WaitIdle(double timeout_s);
  /// Every speed setting the driver saw the hand execute, in order: each command once.
  std::vector<sensorhand::SpeedSetting> executed() const;
  SensorHandStats stats() const;

  /// The serial framing the hand needs: 19200 8N1.
  static SerialConfig SerialConfigFor(std::string port);

 private:
  using Clock = std::chrono::steady_clock;
  enum class GoalKind { kHold, kOpen, kClose };
  struct Goal {
    GoalKind kind = GoalKind::kHold;
    double opening_m = 0.0;  ///< kOpen: target
    double force_n = 0.0;    ///< kClose: limit
    std::uint64_t id = 0;
    std::uint64_t sample_mark = 0;  ///< samples_ when it was set: act on later samples only
    std::uint8_t close_byte = 0;    ///< kClose: the speed byte whose stall force fits the limit
    bool done = false;
    bool backing_off = false;  ///< kClose: easing a stronger grip down to the limit
    int last_dir = 0;          ///< kOpen: +1 opening, -1 closing, 0 not moved yet
    int reversals = 0;
  };
  struct Pending {
    sensorhand::SpeedSetting cmd, before;
    std::uint8_t counter0 = 0;    ///< the hand's counter before the command
    std::uint16_t seq_ref = 0;    ///< the newest sample seen before writing it
    Clock::time_point t_floor;    ///< that sample arrived after this (the link was empty then)
    Clock::time_point t_written;  ///< after the write returned
    bool written = false;
    std::uint16_t seq_after = 0;  ///< samples numbered beyond this were sent after it arrived
    int stale = 0;                ///< such samples still showing the old counter
    std::uint64_t goal_id = 0;
  };
  struct Sample {
    sensorhand::DumpSample d;
    Clock::time_point t;              ///< when it was read
    Clock::time_point arrived_after;  ///< the link was last seen empty then
  };

  void IoLoop();
  /// Reads once (waiting up to timeout_s) and handles what arrived; false when nothing came.
  bool ReadOnce(double timeout_s);
  void HandleReply(const sensorhand::Reply& r, Clock::time_point now);
  void HandleSample(const sensorhand::DumpSample& d, Clock::time_point now);
  /// Decides what to write now (under mu_): stream restart, the next speed command.
  void Step(Clock::time_point now, std::vector<std::uint8_t>* out);
  /// The speed setting the current goal wants, given the latest sample; may mark it done.
  sensorhand::SpeedSetting Control();
  /// Whether the fingers have not moved over the last ~5 samples under the current setting.
  bool Stalled() const;
  bool Moving() const;
  bool Fresh(Clock::time_point now) const;
  /// Sets a goal and waits for the hand to take its first command.
  device::Status StartGoal(Goal goal);
  /// The status a call that could not reach the hand returns.
  device::Status LinkFailure() const;
  double SpeedOf(std::uint8_t b) const;  ///< m/s of a speed byte
  double StopLead(double speed) const;   ///< m the fingers run on after a stop decision

  const std::unique_ptr<ByteLink> link_;  // used by the I/O thread only
  const SensorHandOptions options_;
  const std::uint8_t slow_byte_;

  mutable std::mutex mu_;
  std::condition_variable cv_;
  sensorhand::ReplyDecoder decoder_;  // I/O thread only
  bool stop_ = false;
  bool shutting_down_ = false;
  bool send_dump_stop_ = false;
  bool dump_stopped_ = false;
  device::Status link_status_ = device::Status::kOk;
  std::deque<Sample> history_;  ///< the latest samples, newest last
  std::uint64_t samples_ = 0;
  std::uint64_t decided_samples_ = 0;  ///< samples_ at the last decision
  Clock::time_point last_empty_t_{};   ///< the last read that found nothing
  Clock::time_point last_sample_t_{};
  Clock::time_point last_stream_start_{};
  sensorhand::SpeedSetting known_;  ///< the hand's setting, as last seen
  std::uint8_t known_counter_ = 0;
  std::uint16_t setting_since_seq_ = 0;  ///< first sample number under the current setting
  std::optional<Pending> pending_;
  std::optional<sensorhand::SpeedSetting> last_lost_;  ///< the last command seen lost
  Goal goal_;
  std::uint64_t next_goal_id_ = 1;
  std::uint64_t acked_goal_id_ = 0;  ///< the newest goal whose first command the hand took
  std::vector<sensorhand::SpeedSetting> executed_;
  SensorHandStats stats_;
  std::thread thread_;
};

}  // namespace hgrasp::drivers
