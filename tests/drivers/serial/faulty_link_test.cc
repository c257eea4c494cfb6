// FaultyLink and LineFaults: corruption, garbage, cuts and dropouts as a FaultPlan asks, the
// same damage from the same seed. Dropouts are timed on the clock the faults are given: a
// SimClock here, so that every figure is exact and none depends on the machine's load.

#include "serial/faulty_link.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <deque>
#include <optional>
#include <vector>

#include "common/clock.h"

namespace hgrasp::drivers {
namespace {

using device::Status;

// A loopback: what is written comes back on Read (at once; nothing there is a timeout).
class Loopback final : public ByteLink {
 public:
  Status Write(std::span<const std::uint8_t> bytes) override {
    q.insert(q.end(), bytes.begin(), bytes.end());
    return Status::kOk;
  }
  Status Read(std::span<std::uint8_t> buf, double /*timeout_s*/, std::size_t* n) override {
    *n = 0;
    if (q.empty()) return Status::kTimeout;
    while (*n < buf.size() && !q.empty()) {
      buf[(*n)++] = q.front();
      q.pop_front();
    }
    return Status::kOk;
  }
  void Discard() override { q.clear(); }
  std::deque<std::uint8_t> q;
};

std::vector<std::uint8_t> Pattern(std::size_t n) {
  std::vector<std::uint8_t> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<std::uint8_t>(i * 7 + 3);
  return v;
}

TEST(FaultyLink, CleanPlanPassesEverything) {
  auto inner = std::make_unique<Loopback>();
  Loopback* loop = inner.get();
  FaultyLink link(std::move(inner), FaultPlan{});
  const auto data = Pattern(1000);
  ASSERT_EQ(link.Write(data), Status::kOk);
  EXPECT_EQ(std::vector<std::uint8_t>(loop->q.begin(), loop->q.end()), data);
  std::vector<std::uint8_t> buf(2000);
  std::size_t n = 0;
  std::vector<std::uint8_t> got;
  while (link.Read(buf, 0.01, &n) == Status::kOk)
    got.insert(got.end(), buf.begin(), buf.begin() + n);
  EXPECT_EQ(got, data);
  EXPECT_EQ(link.counts().bytes, 2000u);
  EXPECT_EQ(link.counts().corrupted, 0u);
}

TEST(FaultyLink, CorruptsAboutTheAskedFractionAndInsertsGarbage) {
  auto inner = std::make_unique<Loopback>();
  Loopback* loop = inner.get();
  FaultyLink link(std::move(inner), FaultPlan{.corrupt_probability = 0.01, .seed = 7});
  const auto data = Pattern(100000);
  ASSERT_EQ(link.Write(data), Status::kOk);
  std::size_t differ = 0;
  for (std::size_t i = 0; i < data.size(); ++i) differ += loop->q[i] != data[i];
  EXPECT_EQ(differ, link.counts().corrupted);  // a corrupted byte always changes
  EXPECT_NEAR(static_cast<double>(differ) / data.size(), 0.01, 0.0015);

  auto inner2 = std::make_unique<Loopback>();
  Loopback* loop2 = inner2.get();
  FaultyLink garbage(std::move(inner2), FaultPlan{.garbage_probability = 0.02, .seed = 3});
  ASSERT_EQ(garbage.Write(data), Status::kOk);
  EXPECT_EQ(loop2->q.size(), data.size() + garbage.counts().inserted);
  EXPECT_NEAR(static_cast<double>(garbage.counts().inserted) / data.size(), 0.02, 0.002);
}

TEST(FaultyLink, SameSeedSameDamage) {
  std::vector<std::uint8_t> runs[2];
  for (auto& run : runs) {
    auto inner = std::make_unique<Loopback>();
    Loopback* loop = inner.get();
    FaultyLink link(
        std::move(inner),
        FaultPlan{.corrupt_probability = 0.05, .garbage_probability = 0.05, .seed = 11});
    ASSERT_EQ(link.Write(Pattern(5000)), Status::kOk);
    run.assign(loop->q.begin(), loop->q.end());
  }
  EXPECT_EQ(runs[0], runs[1]);
}

TEST(FaultyLink, CutLosesEverythingBothWaysUntilMended) {
  auto inner = std::make_unique<Loopback>();
  Loopback* loop = inner.get();
  FaultyLink link(std::move(inner), FaultPlan{});
  link.Cut(true);
  ASSERT_EQ(link.Write(Pattern(10)), Status::kOk);  // the sender cannot tell
  EXPECT_TRUE(loop->q.empty());
  loop->q.assign(5, 0x55);
  std::uint8_t buf[16];
  std::size_t n = 0;
  EXPECT_EQ(link.Read(buf, 0.05, &n), Status::kTimeout);
  EXPECT_EQ(link.counts().dropped, 15u);
  link.Cut(false);
  ASSERT_EQ(link.Write(Pattern(3)), Status::kOk);
  EXPECT_EQ(loop->q.size(), 3u);
}

TEST(FaultyLink, DropoutsLastTheirLengthAndRecur) {
  auto inner = std::make_unique<Loopback>();
  Loopback* loop = inner.get();
  SimClock clock;
  FaultyLink link(std::move(inner), FaultPlan{.dropouts_per_s = 10.0, .dropout_s = 0.05, .seed = 5},
                  clock);
  // Over 1 s, write a byte every ms: about 1 / (0.1 + 0.05) = 6.7 dropouts, each losing about
  // 50 bytes: a third of the traffic.
  std::size_t sent = 0;
  while (clock.NowSeconds() < 1.0) {
    const std::uint8_t b[] = {1};
    ASSERT_EQ(link.Write(b), Status::kOk);
    ++sent;
    clock.SleepFor(0.001);
  }
  const FaultCounts c = link.counts();
  EXPECT_GE(c.dropouts, 3u);
  EXPECT_LE(c.dropouts, 12u);
  EXPECT_EQ(loop->q.size() + c.dropped, sent);
  const double lost = static_cast<double>(c.dropped) / sent;
  EXPECT_GT(lost, 0.15);
  EXPECT_LT(lost, 0.55);
}

// With a least gap, the line works at least that long between two dropouts: each outage is one
// dropout long. (Without it, at 50 dropouts/s a third of the gaps are under 7 ms.)
TEST(FaultyLink, DropoutsKeepTheirLeastGap) {
  for (const double min_gap : {0.0, 0.03}) {
    SCOPED_TRACE(min_gap);
    SimClock clock;
    LineFaults faults(
        FaultPlan{
            .dropouts_per_s = 50.0, .dropout_s = 0.03, .min_dropout_gap_s = min_gap, .seed = 9},
        clock);
    // The passed bytes' times, and the longest wait between two samples.
    std::vector<std::pair<double, bool>> samples;
    while (clock.NowSeconds() < 1.0) {
      const std::uint8_t b[] = {1};
      std::vector<std::uint8_t> out;
      faults.Pass(b, false, &out);
      samples.emplace_back(clock.NowSeconds(), !out.empty());
      clock.SleepFor(0.001);
    }
    double step = 0.0;
    for (std::size_t k = 1; k < samples.size(); ++k) {
      step = std::max(step, samples[k].first - samples[k - 1].first);
    }
    // Each run of passed bytes between two dropouts: from its first byte to its last.
    std::vector<double> gaps;
    std::optional<double> first, last;
    bool after_dropout = false;
    for (const auto& [t, passed] : samples) {
      if (passed) {
        if (!first) first = t;
        last = t;
      } else {
        if (first && after_dropout) gaps.push_back(*last - *first);
        first.reset();
        after_dropout = true;
      }
    }
    ASSERT_GE(gaps.size(), 5u);
    const double shortest = *std::min_element(gaps.begin(), gaps.end());
    std::printf("least gap %.0f ms: %zu gaps, the shortest %.1f ms (samples up to %.1f ms apart)\n",
                1e3 * min_gap, gaps.size(), 1e3 * shortest, 1e3 * step);
    if (min_gap > 0.0) {
      EXPECT_GE(shortest, min_gap - 2.0 * step);
    } else {
      EXPECT_LT(shortest, 0.01);
    }
  }
}

}  // namespace
}  // namespace hgrasp::drivers
