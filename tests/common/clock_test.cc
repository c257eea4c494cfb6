// Clock: the wall clock moves on its own; a SimClock only when its caller waits, running the
// events due in time order (ties in the order scheduled).

#include "common/clock.h"

#include <gtest/gtest.h>

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>
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

// A worker's turns on a SimClock: one at the start, then every `wait`, each given 0 (its input
// has arrived); it stops when a turn says so, or when its handle goes.
TEST(SimClock, AWorkerTurnsEveryWaitUntilItStops) {
  SimClock clock(milliseconds(50));  // polls finer than 50 ms only when asked to
  std::vector<double> turns;
  auto worker = clock.Start(milliseconds(3), [&](Clock::Duration wait) {
    EXPECT_EQ(wait, Clock::Duration(0));
    turns.push_back(clock.NowSeconds());
    return turns.size() < 4;
  });
  EXPECT_TRUE(turns.empty());  // nothing runs until the caller waits
  clock.SleepFor(0.1);
  ASSERT_EQ(turns.size(), 4u);
  EXPECT_DOUBLE_EQ(turns[0], 0.0);
  EXPECT_DOUBLE_EQ(turns[3], 0.009);

  int more = 0;
  auto other = clock.Start(milliseconds(10), [&](Clock::Duration) { return ++more, true; });
  clock.SleepFor(0.0251);  // at 0.1, 0.11, 0.12
  EXPECT_EQ(more, 3);
  other.reset();
  clock.SleepFor(1.0);
  EXPECT_EQ(more, 3);
  EXPECT_EQ(clock.NextEvent(), Clock::TimePoint::max());

  // A worker that would wait longer than worker_poll turns every worker_poll: a blocking read
  // would have answered what arrived meanwhile at once.
  int slow = 0;
  auto lazy = clock.Start(milliseconds(200), [&](Clock::Duration) { return ++slow, true; });
  clock.SleepFor(0.12);  // at +0, +0.05, +0.1
  EXPECT_EQ(slow, 3);
}

// A party waiting on a condition while a worker (an event) takes the same lock to change it:
// on a SimClock the lock is free while the events run, so neither waits on the other.
TEST(SimClock, WaitUntilLetsTheWorkersTakeTheLock) {
  SimClock clock(milliseconds(5));
  std::mutex mu;
  std::condition_variable cv;
  int count = 0;
  auto worker = clock.Start(milliseconds(5), [&](Clock::Duration) {
    std::lock_guard<std::mutex> lock(mu);
    ++count;
    return true;
  });
  std::unique_lock<std::mutex> lock(mu);
  EXPECT_TRUE(clock.WaitUntil(lock, cv, clock.Now() + milliseconds(100), [&] { return count == 3; }));
  EXPECT_TRUE(lock.owns_lock());
  EXPECT_EQ(clock.Now(), milliseconds(10));  // the third turn
  EXPECT_FALSE(clock.WaitUntil(lock, cv, clock.Now() + milliseconds(7), [&] { return count > 9; }));
  EXPECT_EQ(clock.Now(), milliseconds(17));
  EXPECT_EQ(count, 4);  // at 15 ms
}

// The wall clock's worker is a thread whose turns wait themselves; its handle joins it.
TEST(WallClock, AWorkerRunsInAThreadUntilItsHandleGoes) {
  Clock& wall = Clock::Wall();
  std::mutex mu;
  std::condition_variable cv;
  int turns = 0;
  auto worker = wall.Start(milliseconds(1), [&](Clock::Duration wait) {
    EXPECT_EQ(wait, milliseconds(1));
    std::this_thread::sleep_for(wait);  // as a read with that timeout would
    {
      std::lock_guard<std::mutex> lock(mu);
      ++turns;
    }
    cv.notify_all();
    return true;
  });
  {
    std::unique_lock<std::mutex> lock(mu);
    EXPECT_TRUE(wall.WaitUntil(lock, cv, wall.Now() + std::chrono::seconds(10),
                               [&] { return turns >= 3; }));
  }
  worker.reset();  // joined: no turn runs after this
  int at_stop = 0;
  {
    std::lock_guard<std::mutex> lock(mu);
    at_stop = turns;
  }
  std::this_thread::sleep_for(milliseconds(10));
  std::lock_guard<std::mutex> lock(mu);
  EXPECT_EQ(turns, at_stop);
}

}  // namespace
}  // namespace hgrasp
