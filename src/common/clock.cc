#include "common/clock.h"

#include <algorithm>
#include <atomic>
#include <thread>

namespace hgrasp {

namespace {

class WallClock final : public Clock {
 public:
  TimePoint Now() const override {
    return std::chrono::duration_cast<Duration>(
        std::chrono::steady_clock::now().time_since_epoch());
  }
  void SleepUntil(TimePoint t) override {
    const TimePoint now = Now();
    if (t > now) std::this_thread::sleep_for(t - now);
  }
  bool WaitUntil(std::unique_lock<std::mutex>& lock, std::condition_variable& cv,
                 TimePoint deadline, const std::function<bool()>& pred) override {
    return cv.wait_until(lock, std::chrono::steady_clock::time_point(deadline), pred);
  }
  std::unique_ptr<Worker> Start(Duration wait, std::function<bool(Duration)> turn) override {
    return std::make_unique<ThreadWorker>(wait, std::move(turn));
  }

 private:
  class ThreadWorker final : public Worker {
   public:
    ThreadWorker(Duration wait, std::function<bool(Duration)> turn)
        : thread_([this, wait, turn = std::move(turn)] {
            while (!stop_.load() && turn(wait)) {
            }
          }) {}
    ~ThreadWorker() override {
      stop_.store(true);
      thread_.join();
    }

   private:
    std::atomic<bool> stop_{false};
    std::thread thread_;
  };
};

}  // namespace

// A SimClock's worker: its next turn is an event; the handle cancels it.
struct SimClock::WorkerState {
  SimClock* clock;
  Duration wait;
  std::function<bool(Duration)> turn;
  EventId next = 0;
  bool stopped = false;
};

namespace {

class SimWorker final : public Clock::Worker {
 public:
  explicit SimWorker(std::shared_ptr<SimClock::WorkerState> state) : state_(std::move(state)) {}
  ~SimWorker() override {
    state_->stopped = true;
    state_->clock->Cancel(state_->next);
  }

 private:
  std::shared_ptr<SimClock::WorkerState> state_;
};

}  // namespace

Clock& Clock::Wall() {
  static WallClock wall;
  return wall;
}

bool SimClock::RunOne(TimePoint t) {
  if (events_.empty()) return false;
  auto it = events_.begin();
  if (it->first.first > t) return false;
  now_ = std::max(now_, it->first.first);
  std::function<void()> f = std::move(it->second);
  when_.erase(it->first.second);
  events_.erase(it);
  ++events_run_;
  f();
  return true;
}

void SimClock::SleepUntil(TimePoint t) {
  while (RunOne(t)) {
  }
  now_ = std::max(now_, t);
}

bool SimClock::RunUntil(TimePoint deadline, const std::function<bool()>& done) {
  for (;;) {
    if (done()) return true;
    if (!RunOne(deadline)) break;
  }
  now_ = std::max(now_, deadline);
  return done();
}

bool SimClock::WaitUntil(std::unique_lock<std::mutex>& lock, std::condition_variable& /*cv*/,
                         TimePoint deadline, const std::function<bool()>& pred) {
  lock.unlock();
  RunUntil(deadline, [&] {
    lock.lock();
    const bool done = pred();
    lock.unlock();
    return done;
  });
  lock.lock();
  return pred();
}

std::unique_ptr<Clock::Worker> SimClock::Start(Duration wait,
                                               std::function<bool(Duration)> turn) {
  auto state = std::make_shared<WorkerState>();
  state->clock = this;
  state->wait = std::max(Duration(1), std::min(wait, worker_poll_));
  state->turn = std::move(turn);
  ScheduleTurn(state, now_);
  return std::make_unique<SimWorker>(state);
}

void SimClock::ScheduleTurn(const std::shared_ptr<WorkerState>& state, TimePoint t) {
  std::weak_ptr<WorkerState> weak = state;
  state->next = At(t, [this, weak] {
    const std::shared_ptr<WorkerState> s = weak.lock();
    if (!s || s->stopped) return;
    if (!s->turn(Duration(0))) {
      s->stopped = true;
      return;
    }
    if (!s->stopped) ScheduleTurn(s, now_ + s->wait);
  });
}

SimClock::EventId SimClock::At(TimePoint t, std::function<void()> f) {
  const EventId id = next_id_++;
  const TimePoint when = std::max(t, now_);
  events_.emplace(std::make_pair(when, id), std::move(f));
  when_.emplace(id, when);
  return id;
}

bool SimClock::Cancel(EventId id) {
  const auto it = when_.find(id);
  if (it == when_.end()) return false;
  events_.erase({it->second, id});
  when_.erase(it);
  return true;
}

Clock::TimePoint SimClock::NextEvent() const {
  return events_.empty() ? TimePoint::max() : events_.begin()->first.first;
}

}  // namespace hgrasp
