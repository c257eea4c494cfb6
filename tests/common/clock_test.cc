// Clock: the wall clock moves on its own; a SimClock only when its caller waits, running the
// events due in time order (ties in the order scheduled).

#include "common/clock.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace hgrasp {
namespace {

using std::chrono::milliseconds;

TEST(WallClock, SleepForWaitsAtLeastThatLong) {
  Clock& wall = Clock::Wall();
  const Clock::TimePoint t0 = wall.Now();
  wall.SleepFor(0.002);
  EXPECT_GE(wall.Now() - t0, milliseconds(2));
  EXPECT_EQ(&Clock::Wall(), &wall);  // one wall clock for the process
}

TEST(SimClock, StandsStillUntilItsCallerWaits) {
  SimClock clock;
  EXPECT_EQ(clock.Now(), Clock::TimePoint{0});
  EXPECT_EQ(clock.Now(), Clock::TimePoint{0});
  clock.SleepFor(0.25);
  EXPECT_EQ(clock.Now(), milliseconds(250));
  EXPECT_DOUBLE_EQ(clock.NowSeconds(), 0.25);
  clock.SleepUntil(milliseconds(100));  // never backwards
  EXPECT_EQ(clock.Now(), milliseconds(250));
}

TEST(SimClock, RunsEventsInTimeOrderAndTiesInTheOrderScheduled) {
  SimClock clock;
  std::vector<std::string> ran;
  std::vector<Clock::TimePoint> at;
  auto record = [&](std::string name) {
    return [&, name] {
      ran.push_back(name);
      at.push_back(clock.Now());
    };
  };
  clock.At(milliseconds(30), record("c"));
  clock.At(milliseconds(10), record("a"));
  clock.At(milliseconds(30), record("d"));
  clock.At(milliseconds(20), record("b"));
  clock.At(milliseconds(50), record("late"));
  EXPECT_EQ(clock.NextEvent(), milliseconds(10));
  clock.SleepUntil(milliseconds(40));
  EXPECT_EQ(ran, (std::vector<std::string>{"a", "b", "c", "d"}));
  EXPECT_EQ(at, (std::vector<Clock::TimePoint>{milliseconds(10), milliseconds(20),
                                               milliseconds(30), milliseconds(30)}));
  EXPECT_EQ(clock.Now(), milliseconds(40));
  EXPECT_EQ(clock.NextEvent(), milliseconds(50));
  EXPECT_EQ(clock.events_run(), 4u);
}

TEST(SimClock, AnEventMayScheduleAnotherWithinTheSameWait) {
  SimClock clock;
  int ticks = 0;
  std::function<void()> tick = [&] {
    ++ticks;
    clock.At(clock.Now() + milliseconds(2), tick);
  };
  clock.At(milliseconds(2), tick);
  clock.SleepFor(0.1);
  EXPECT_EQ(ticks, 50);  // 2, 4, ..., 100 ms
}

TEST(SimClock, RunUntilStopsAtTheEventThatSatisfiesIt) {
  SimClock clock;
  bool arrived = false;
  clock.At(milliseconds(7), [] {});
  clock.At(milliseconds(12), [&] { arrived = true; });
  clock.At(milliseconds(15), [] {});
  EXPECT_TRUE(clock.RunUntil(milliseconds(50), [&] { return arrived; }));
  EXPECT_EQ(clock.Now(), milliseconds(12));
  EXPECT_EQ(clock.NextEvent(), milliseconds(15));
}

TEST(SimClock, RunUntilTimesOutAtItsDeadline) {
  SimClock clock;
  bool arrived = false;
  clock.At(milliseconds(80), [&] { arrived = true; });
  EXPECT_FALSE(clock.RunUntil(milliseconds(50), [&] { return arrived; }));
  EXPECT_EQ(clock.Now(), milliseconds(50));
  EXPECT_FALSE(arrived);
  // Already true: no event runs and no time passes.
  bool yes = true;
  EXPECT_TRUE(clock.RunUntil(milliseconds(100), [&] { return yes; }));
  EXPECT_EQ(clock.Now(), milliseconds(50));
}

TEST(SimClock, CancelledEventsDoNotRun) {
  SimClock clock;
  int runs = 0;
  const SimClock::EventId id = clock.At(milliseconds(5), [&] { ++runs; });
  clock.At(milliseconds(6), [&] { runs += 10; });
  EXPECT_TRUE(clock.Cancel(id));
  EXPECT_FALSE(clock.Cancel(id));
  clock.SleepFor(0.01);
  EXPECT_EQ(runs, 10);
}

TEST(SimClock, AnEventInThePastRunsAtTheNextWaitAtNow) {
  SimClock clock;
  clock.SleepFor(0.5);
  Clock::TimePoint ran_at{-1};
  clock.At(milliseconds(100), [&] { ran_at = clock.Now(); });
  clock.SleepFor(0.0);
  EXPECT_EQ(ran_at, milliseconds(500));
}

}  // namespace
}  // namespace hgrasp
