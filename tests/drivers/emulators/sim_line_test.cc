// SimLine: a device on a simulated 8N1 wire, worked out by hand. At 9600 baud a byte takes
// 10 / 9600 s = 1.0417 ms each way; an echoing device answers a byte as it arrives.

#include "emulators/sim_line.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace hgrasp::drivers {
namespace {

using device::Status;

// Echoes every byte at once; sends "T" on its own at every Advance after `talk_at_s`, once.
class Echo final : public DeviceEmulator {
 public:
  void Receive(std::span<const std::uint8_t> in, double t_s,
               std::vector<std::uint8_t>* out) override {
    for (std::uint8_t b : in) {
      out->push_back(b);
      received.emplace_back(b, t_s);
    }
  }
  void Advance(double t_s, std::vector<std::uint8_t>* out) override {
    last_advance_s = t_s;
    if (talk_at_s >= 0 && t_s >= talk_at_s) {
      out->push_back('T');
      talk_at_s = -1;
    }
  }
  std::vector<std::pair<std::uint8_t, double>> received;
  double talk_at_s = -1, last_advance_s = -1;
};

constexpr double kByteS = 10.0 / 9600;

std::string ReadAll(ByteLink& link, double timeout_s, Status* status = nullptr) {
  std::string got;
  std::uint8_t buf[64];
  std::size_t n = 0;
  Status s;
  while ((s = link.Read(buf, timeout_s, &n)) == Status::kOk) got.append(buf, buf + n);
  if (status) *status = s;
  return got;
}

TEST(SimLine, BytesTakeTheirTimeBothWays) {
  SimClock clock;
  auto echo_owned = std::make_unique<Echo>();
  Echo* echo = echo_owned.get();
  SimLine line(clock, std::move(echo_owned), 9600);
  auto link = line.Open();
  const std::uint8_t ab[2] = {'a', 'b'};
  ASSERT_EQ(link->Write(ab), Status::kOk);
  EXPECT_EQ(clock.Now(), Clock::TimePoint{0});  // a write does not wait for the wire
  std::uint8_t buf[8];
  std::size_t n = 0;
  // 'a' reaches the device at 1 byte time and is back at 2; nothing before.
  EXPECT_EQ(link->Read(buf, 1.5 * kByteS, &n), Status::kTimeout);
  EXPECT_EQ(n, 0u);
  EXPECT_NEAR(clock.NowSeconds(), 1.5 * kByteS, 1e-9);
  ASSERT_EQ(link->Read(buf, 1.0, &n), Status::kOk);
  EXPECT_EQ(n, 1u);
  EXPECT_EQ(buf[0], 'a');
  EXPECT_NEAR(clock.NowSeconds(), 2 * kByteS, 1e-8);  // returned as the byte arrived
  ASSERT_EQ(link->Read(buf, 1.0, &n), Status::kOk);
  EXPECT_EQ(buf[0], 'b');
  EXPECT_NEAR(clock.NowSeconds(), 3 * kByteS, 1e-8);
  ASSERT_EQ(echo->received.size(), 2u);
  EXPECT_NEAR(echo->received[0].second, kByteS, 1e-8);
  EXPECT_NEAR(echo->received[1].second, 2 * kByteS, 1e-8);
  // The device's ticks ran meanwhile (every 2 ms), on the same clock.
  clock.SleepUntil(Clock::FromSeconds(0.0105));
  EXPECT_NEAR(echo->last_advance_s, 0.010, 1e-9);
}

TEST(SimLine, WhatTheDeviceSaysOnItsOwnArrivesAtItsTime) {
  SimClock clock;
  auto echo_owned = std::make_unique<Echo>();
  echo_owned->talk_at_s = 0.1;
  SimLine line(clock, std::move(echo_owned), 9600);
  auto link = line.Open();
  std::uint8_t buf[8];
  std::size_t n = 0;
  ASSERT_EQ(link->Read(buf, 1.0, &n), Status::kOk);
  EXPECT_EQ(buf[0], 'T');
  // Said at the first tick at or after 0.1 s (ticks every 2 ms), one byte time on the wire.
  EXPECT_NEAR(clock.NowSeconds(), 0.1 + kByteS, 1e-8);
}

TEST(SimLine, ACutLineLosesEverythingAndAMendedOneCarriesOn) {
  SimClock clock;
  SimLine line(clock, std::make_unique<Echo>(), 9600);
  auto link = line.Open();
  line.Cut(true);
  ASSERT_EQ(WriteText(*link, "lost"), Status::kOk);  // the sender cannot tell
  Status s;
  EXPECT_EQ(ReadAll(*link, 0.05, &s), "");
  EXPECT_EQ(s, Status::kTimeout);
  EXPECT_NEAR(clock.NowSeconds(), 0.05, 1e-9);
  line.Cut(false);
  ASSERT_EQ(WriteText(*link, "ok"), Status::kOk);
  EXPECT_EQ(ReadAll(*link, 0.05), "ok");
  // Cut from the device only: the device hears, the host does not.
  line.CutFromDevice(true);
  ASSERT_EQ(WriteText(*link, "x"), Status::kOk);
  EXPECT_EQ(ReadAll(*link, 0.05), "");
  EXPECT_EQ(dynamic_cast<Echo&>(line.device()).received.back().first, 'x');
}

TEST(SimLine, AVanishedPortIsDisconnectedUntilItComesBack) {
  SimClock clock;
  SimLine line(clock, std::make_unique<Echo>(), 9600);
  auto link = line.Open();
  ASSERT_EQ(WriteText(*link, "abc"), Status::kOk);
  line.Vanish();
  std::uint8_t buf[8];
  std::size_t n = 0;
  EXPECT_EQ(link->Read(buf, 0.1, &n), Status::kDisconnected);
  EXPECT_EQ(WriteText(*link, "d"), Status::kDisconnected);
  line.Reappear();
  EXPECT_EQ(ReadAll(*link, 0.05), "");  // what was on the wire is lost
  ASSERT_EQ(WriteText(*link, "e"), Status::kOk);
  EXPECT_EQ(ReadAll(*link, 0.05), "e");
}

// One seed, one run: the same plan gives the same damaged bytes at the same times.
TEST(SimLine, FaultsReplayFromTheSeed) {
  auto run = [](std::uint64_t seed) {
    SimClock clock;
    FaultPlan plan;
    plan.corrupt_probability = 0.05;
    plan.dropouts_per_s = 2.0;
    plan.dropout_s = 0.05;
    plan.seed = seed;
    SimLine line(clock, std::make_unique<Echo>(), 9600, plan);
    auto link = line.Open();
    std::string got;
    for (int k = 0; k < 50; ++k) {
      EXPECT_EQ(WriteText(*link, "The quick brown fox " + std::to_string(k)), Status::kOk);
      got += ReadAll(*link, 0.01) + "|" + std::to_string(clock.Now().count()) + "\n";
    }
    const FaultCounts c = line.counts();
    EXPECT_GT(c.corrupted, 0u);
    EXPECT_GT(c.dropouts, 0u);
    return got;
  };
  const std::string a = run(5), b = run(5), c = run(6);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

}  // namespace
}  // namespace hgrasp::drivers
