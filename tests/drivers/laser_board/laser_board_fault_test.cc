// Fault injection on the laser board link, on a simulated 115200-baud line in simulated time
// (SimLine: one run per seed, whatever the machine's load): 1% corrupted bytes and random
// 200 ms dropouts for 1000 commands (none lost, duplicated or altered); lost replies (the
// board executed, the driver never heard); a cut cable reported within 0.5 s and mended; the
// port vanishing and coming back.

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

#include "laser_board_rig.h"

namespace hgrasp::drivers {
namespace {

namespace lb = laser_board;
using device::Side;
using device::Status;
using testing::SimBoardRig;
using testing::ReplyEater;

// Retries `call` through the driver's own API until it returns kOk (at most `tries` times).
template <class F>
Status UntilOk(F&& call, int tries, int* failures) {
  Status s = Status::kTimeout;
  for (int i = 0; i < tries; ++i) {
    s = call();
    if (s == Status::kOk) return s;
    ++*failures;
  }
  return s;
}

// 1000 commands over a link with 1% of the bytes corrupted (each way) and 200 ms dropouts
// at `dropouts_per_s`, the driver on `options`; each failed call is retried through the
// driver's API.
void ThousandCommands(const std::string& name, const LaserBoardOptions& options,
                      double dropouts_per_s, std::uint64_t seed) {
  SimBoardRig rig;
  FaultPlan plan;
  plan.corrupt_probability = 0.01;
  plan.dropouts_per_s = dropouts_per_s;
  plan.dropout_s = 0.2;
  plan.seed = seed;
  auto faulty = std::make_unique<FaultyLink>(rig.Open(), plan, rig.clock);
  FaultyLink* link = faulty.get();
  auto board = std::make_shared<LaserBoard>(std::move(faulty), options, rig.clock);
  BoardStripeLaser laser(board);
  BoardLeds leds(board);
  // The first camera frame (VSYNC at 40 ms), so that latches exist.
  while (rig.With([](LaserBoardEmulator& e) { return e.frame(); }) == 0) {
    rig.clock.SleepFor(0.005);
  }

  // A deterministic mix: state-changing commands with distinct values, and reads.
  std::vector<lb::Command> commanded;
  int failures = 0, reads = 0;
  bool laser_on = false;
  const auto t0 = rig.clock.Now();
  for (int i = 0; i < 1000; ++i) {
    Status s = Status::kOk;
    switch (i % 6) {
      case 0:
        laser_on = !laser_on;
        s = UntilOk([&] { return laser.SetLaser(laser_on); }, 50, &failures);
        commanded.push_back(lb::SetLaser{laser_on});
        break;
      case 1: {
        const std::int32_t count = (i * 397) % 9001 - 4500;
        const double speed = 3000 + i % 6000;
        s = UntilOk([&] { return laser.MoveTo(count, speed); }, 50, &failures);
        commanded.push_back(lb::MotorGoTo{count, static_cast<std::uint32_t>(speed)});
        break;
      }
      case 2:
      case 4: {
        const Side side = (i % 4 == 0) ? Side::kLeft : Side::kRight;
        const std::uint32_t mask = static_cast<std::uint32_t>(i / 6) % 64;
        s = UntilOk([&] { return leds.Set(side, mask); }, 50, &failures);
        commanded.push_back(
            lb::SetLeds{static_cast<std::uint8_t>(side == Side::kLeft ? 0 : 1), mask});
        break;
      }
      case 3: {
        device::StripeLaserState st;
        s = UntilOk([&] { return laser.Read(&st); }, 50, &failures);
        if (s == Status::kOk) {
          EXPECT_EQ(st.laser_on, laser_on);
        }
        ++reads;
        break;
      }
      case 5: {
        FrameLatch l;
        s = UntilOk([&] { return board->LatestFrameLatch(&l); }, 50, &failures);
        ++reads;
        break;
      }
    }
    ASSERT_EQ(s, Status::kOk) << "command " << i;
  }
  const double elapsed = rig.Since(t0);
  const FaultCounts fc = link->counts();
  const LaserBoardStats st = board->stats();
  const auto counts = rig.With([](LaserBoardEmulator& e) { return e.counts(); });
  using ull = unsigned long long;
  std::printf(
      "[%s] 1000 commands (%zu state-changing, %d reads) in %.1f s; call budget %.2f s, "
      "%.1f dropouts/s; failed calls retried: %d\n"
      "  link: %llu bytes, %llu corrupted, %llu dropouts, %llu bytes dropped\n"
      "  driver: %llu sends, %llu retransmissions, %llu syncs, %llu replayed, %llu bad frames, "
      "%llu NAKs\n"
      "  board: %llu frames, %llu CRC errors, %llu NAKs, %llu answered from memory\n",
      name.c_str(), commanded.size(), reads, elapsed, options.call_timeout_s, dropouts_per_s,
      failures, ull{fc.bytes}, ull{fc.corrupted}, ull{fc.dropouts}, ull{fc.dropped}, ull{st.sends},
      ull{st.retransmissions}, ull{st.syncs}, ull{st.replayed}, ull{st.bad_frames}, ull{st.naks},
      ull{counts.frames}, ull{counts.crc_errors}, ull{counts.naks}, ull{counts.replayed});
  // The faults did happen...
  EXPECT_GT(fc.corrupted, 50u);
  EXPECT_GT(st.retransmissions, 0u);
  // ...and the board executed exactly what was commanded: none lost, duplicated or altered.
  EXPECT_EQ(rig.Executed(), commanded);
  // The driver's own log says the same, each entry confirmed (every failed call was retried).
  const auto driver_log = board->command_log().Snapshot();
  std::vector<lb::Command> logged;
  for (const auto& e : driver_log) {
    EXPECT_TRUE(e.confirmed);
    logged.push_back(e.command);
  }
  EXPECT_EQ(logged, commanded);
}

TEST(LaserBoardFaults, ThousandCommandsThroughCorruptionAndDropouts) {
  ThousandCommands("faults", LaserBoardOptions{}, 0.5, 6);
}

// Harsher: a call budget shorter than a dropout and four times the dropouts. Calls fail, some
// after the board executed them; the test retries them through the driver, whose
// sequence-number sync keeps every command to exactly one execution.
TEST(LaserBoardFaults, ThousandCommandsWithCallsFailingInDropouts) {
  LaserBoardOptions options;
  options.call_timeout_s = 0.12;
  options.reply_timeout_s = 0.04;
  ThousandCommands("failing_calls", options, 2.0, 7);
}

TEST(LaserBoardFaults, LostReplyIsNeverExecutedTwice) {
  SimBoardRig rig;
  auto eater = std::make_unique<ReplyEater>(rig.Open());
  ReplyEater* link = eater.get();
  auto board = std::make_shared<LaserBoard>(std::move(eater), LaserBoardOptions{}, rig.clock);
  BoardStripeLaser laser(board);
  ASSERT_EQ(laser.SetLaser(false), Status::kOk);

  // The board executes, every reply is lost: the call fails...
  link->eat = true;
  EXPECT_EQ(laser.MoveTo(1000, 9000), Status::kTimeout);
  EXPECT_EQ(laser.MoveTo(1000, 9000), Status::kTimeout);  // a retry while still deaf
  link->eat = false;
  // ...and its retry is answered from the board's memory, not executed again.
  EXPECT_EQ(laser.MoveTo(1000, 9000), Status::kOk);
  EXPECT_GE(board->stats().replayed, 1u);

  // A lost reply followed by another command: that one is new and runs.
  link->eat = true;
  EXPECT_EQ(laser.SetLaser(true), Status::kTimeout);
  link->eat = false;
  EXPECT_EQ(laser.MoveTo(-500, 9000), Status::kOk);
  // The same command as before the failure, but not a retry: it runs again.
  EXPECT_EQ(laser.MoveTo(1000, 9000), Status::kOk);

  const std::vector<lb::Command> expected = {lb::SetLaser{false}, lb::MotorGoTo{1000, 9000},
                                             lb::SetLaser{true}, lb::MotorGoTo{-500, 9000},
                                             lb::MotorGoTo{1000, 9000}};
  EXPECT_EQ(rig.Executed(), expected);
  // The driver logged each once, confirmed: the lost SET_LASER when the sync before the next
  // command showed the board's last number to be its own.
  std::vector<lb::Command> logged;
  for (const auto& e : board->command_log().Snapshot()) {
    EXPECT_TRUE(e.confirmed);
    logged.push_back(e.command);
  }
  EXPECT_EQ(logged, expected);
  const auto replayed = rig.With([](LaserBoardEmulator& e) { return e.counts().replayed; });
  EXPECT_GE(replayed, 1u);
}

TEST(LaserBoardFaults, CutLinkReportedWithinHalfASecondAndMended) {
  SimBoardRig rig;
  auto faulty = std::make_unique<FaultyLink>(rig.Open(), FaultPlan{}, rig.clock);
  FaultyLink* link = faulty.get();
  auto board = std::make_shared<LaserBoard>(std::move(faulty), LaserBoardOptions{}, rig.clock);
  BoardStripeLaser laser(board);
  device::StripeLaserState s;
  ASSERT_EQ(laser.Read(&s), Status::kOk);

  link->Cut(true);
  double worst = 0;
  for (int i = 0; i < 3; ++i) {
    const auto t0 = rig.clock.Now();
    EXPECT_EQ(laser.SetLaser(true), Status::kTimeout);
    worst = std::max(worst, rig.Since(t0));
    const auto t1 = rig.clock.Now();
    EXPECT_EQ(laser.Read(&s), Status::kTimeout);
    worst = std::max(worst, rig.Since(t1));
  }
  std::printf("cut link reported after at most %.3f s\n", worst);
  EXPECT_LT(worst, 0.5);
  EXPECT_TRUE(rig.Executed().empty());

  link->Cut(false);
  const auto t2 = rig.clock.Now();
  EXPECT_EQ(laser.SetLaser(true), Status::kOk);  // the first call after mending
  std::printf("mended link: first command done in %.3f s\n", rig.Since(t2));
  ASSERT_EQ(laser.Read(&s), Status::kOk);
  EXPECT_TRUE(s.laser_on);
  EXPECT_EQ(rig.Executed(), std::vector<lb::Command>{lb::SetLaser{true}});
}

TEST(LaserBoardFaults, VanishedPortReportedAndRecovered) {
  SimBoardRig rig;
  auto board = std::make_shared<LaserBoard>(rig.Open(), LaserBoardOptions{}, rig.clock);
  BoardStripeLaser laser(board);
  BoardLeds leds(board);
  ASSERT_EQ(leds.Set(Side::kLeft, 1), Status::kOk);

  rig.line().Vanish();
  double worst = 0;
  for (int i = 0; i < 3; ++i) {
    const auto t0 = rig.clock.Now();
    EXPECT_EQ(leds.Set(Side::kLeft, 2), Status::kDisconnected);
    worst = std::max(worst, rig.Since(t0));
  }
  std::printf("vanished port reported after at most %.3f s\n", worst);
  EXPECT_LT(worst, 0.5);

  rig.line().Reappear();
  const auto t1 = rig.clock.Now();
  Status s = Status::kDisconnected;
  int calls = 0;
  while (s != Status::kOk && rig.Since(t1) < 2.0) {
    s = leds.Set(Side::kLeft, 2);
    ++calls;
  }
  std::printf("port back: recovered after %d call(s), %.3f s\n", calls, rig.Since(t1));
  ASSERT_EQ(s, Status::kOk);
  EXPECT_EQ(rig.With([](LaserBoardEmulator& e) { return e.hardware().LedMask(0); }), 2u);
  const std::vector<lb::Command> expected = {lb::SetLeds{0, 1}, lb::SetLeds{0, 2}};
  EXPECT_EQ(rig.Executed(), expected);
}

}  // namespace
}  // namespace hgrasp::drivers
