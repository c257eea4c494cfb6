#pragma once
/// @file The time a device's code reads and waits on (DESIGN.md rule 10: time is handed in).
///
/// Every driver, emulator host and link takes a Clock. A real robot gets the wall clock
/// (Clock::Wall(), std::chrono::steady_clock). Tests of the protocols, and the twin in lockstep,
/// get a SimClock: one discrete-event scheduler in which time advances only when the party that
/// runs waits, to the earliest scheduled event (a byte arriving, an emulator's tick), so that a
/// run does not depend on how busy the machine is and one seed replays one run exactly.
///
/// Time points are durations since the clock's epoch (the wall clock's: steady_clock's; a
/// SimClock's: its construction, 0).

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <utility>

namespace hgrasp {

class Clock {
 public:
  using Duration = std::chrono::nanoseconds;
  using TimePoint = Duration;  ///< since the clock's epoch

  virtual ~Clock() = default;

  /// Now.
  virtual TimePoint Now() const = 0;
  /// Returns at `t` (at once when `t` has passed). On a SimClock the events due by `t` run
  /// first, in time order.
  virtual void SleepUntil(TimePoint t) = 0;

  /// Waits on `cv` (as std::condition_variable::wait_until; `lock` held on entry and on
  /// return) until `pred()` holds or `deadline` passes; returns `pred()`. `pred` is called
  /// with the lock held. On a SimClock the lock is released while the events due run (a party
  /// that would take it to change what `pred` reads is one of them), so no party waits on a
  /// lock held by another.
  virtual bool WaitUntil(std::unique_lock<std::mutex>& lock, std::condition_variable& cv,
                         TimePoint deadline, const std::function<bool()>& pred) = 0;

  /// A party that acts on its own (a driver's I/O loop). Destroying the handle stops it: no
  /// turn runs after the destructor returns.
  class Worker {
   public:
    virtual ~Worker() = default;
  };
  /// Runs `turn(wait)` again and again until it returns false or the handle is destroyed. On
  /// the wall clock, in a thread of its own, each turn waiting up to `wait` for its input itself
  /// (a read's timeout) so that it answers what arrives at once; on a SimClock, as an event
  /// every `wait` of simulated time (or more often: SimClock's worker_poll) on the thread that
  /// waits, given 0 (what arrived meanwhile is there to be read).
  virtual std::unique_ptr<Worker> Start(Duration wait, std::function<bool(Duration)> turn) = 0;

  void SleepFor(Duration d) { SleepUntil(Now() + d); }
  void SleepFor(double seconds) { SleepFor(FromSeconds(seconds)); }
  /// Seconds since the epoch.
  double NowSeconds() const { return ToSeconds(Now()); }

  /// The process's one wall clock (std::chrono::steady_clock; thread-safe).
  static Clock& Wall();

  static constexpr double ToSeconds(Duration d) {
    return std::chrono::duration<double>(d).count();
  }
  static constexpr Duration FromSeconds(double s) {
    return std::chrono::duration_cast<Duration>(std::chrono::duration<double>(s));
  }
};

/// Simulated time: a discrete-event scheduler for one thread of control. The code under test
/// (a driver) runs on the calling thread; everything else that would act on its own (an
/// emulated device's ticks, bytes travelling down a wire) is an event scheduled at its time and
/// run on that same thread when the driver waits past it. Events at equal times run in the
/// order they were scheduled. No thread, no lock: not thread-safe, and it needs none.
class SimClock final : public Clock {
 public:
  using EventId = std::uint64_t;

  /// A worker (Start) turns at least every `worker_poll` of simulated time, whatever wait it
  /// asks for: on the wall clock its turn wakes as soon as its input arrives (a blocking read
  /// returns within the scheduler's latency, tens of microseconds), and a worker that dates what
  /// it reads by the time it reads it must see it as promptly here. 100 us by default.
  explicit SimClock(Duration worker_poll = std::chrono::microseconds(100))
      : worker_poll_(worker_poll) {}

  TimePoint Now() const override { return now_; }
  /// Runs every event due by `t` in time order, then sets the time to `t` (never backwards).
  void SleepUntil(TimePoint t) override;
  /// RunUntil(deadline, pred) with `lock` released while events run (taken again for `pred`).
  bool WaitUntil(std::unique_lock<std::mutex>& lock, std::condition_variable& cv,
                 TimePoint deadline, const std::function<bool()>& pred) override;
  std::unique_ptr<Worker> Start(Duration wait, std::function<bool(Duration)> turn) override;

  /// Runs events in time order until `done()` holds (checked first and after each event) or
  /// the next event lies past `deadline`; the time then stays at the last event run when
  /// `done()` holds, or becomes `deadline`. Returns `done()`. What a blocking read with a
  /// timeout does: wait for bytes, or for the timeout.
  bool RunUntil(TimePoint deadline, const std::function<bool()>& done);

  /// Schedules `f` at `t` (at Now() when `t` has passed). `f` may schedule events itself.
  EventId At(TimePoint t, std::function<void()> f);
  /// Removes a scheduled event; false when it has run or was never scheduled.
  bool Cancel(EventId id);

  /// The time of the earliest event; TimePoint::max() when none.
  TimePoint NextEvent() const;
  /// Events run so far.
  std::uint64_t events_run() const { return events_run_; }

  struct WorkerState;

 private:
  void ScheduleTurn(const std::shared_ptr<WorkerState>& state, TimePoint t);
  // Runs the earliest event when it is due by `t`; false when none is.
  bool RunOne(TimePoint t);

  Duration worker_poll_;
  TimePoint now_{0};
  // (time, sequence) -> event: equal times in the order scheduled.
  std::map<std::pair<TimePoint, EventId>, std::function<void()>> events_;
  std::map<EventId, TimePoint> when_;
  EventId next_id_ = 1;
  std::uint64_t events_run_ = 0;
};

}  // namespace hgrasp
