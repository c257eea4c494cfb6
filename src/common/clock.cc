#include "common/clock.h"

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
