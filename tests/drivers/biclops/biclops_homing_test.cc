// Issue 16: the Biclops as the real head. A host program written from TRACLabs' libBiclops /
// libPMD source configures, homes, moves and reads the emulated head, and survives unknown
// opcodes in its command stream; BiclopsHead::ConfigureAndHome homes the emulated head, which
// powers up away from home with relative encoders, to within one count; a head whose index never
// comes reports a failure instead of hanging. All over a simulated 9600-baud line (SimLine) in
// simulated time (SimClock): every figure below is exact and replays run after run, whatever the
// machine's load.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "biclops/biclops_head.h"
#include "biclops_vendor_host.h"
#include "common/clock.h"
#include "common/error.h"
#include "emulators/biclops_emulator.h"
#include "serial/faulty_link.h"
#include "tests/drivers/biclops/biclops_rig.h"

namespace hgrasp::drivers {
namespace {

using device::Status;
using testing::BiclopsLineRig;
using testing::BiclopsRig;
constexpr double kPi = 3.14159265358979323846;
constexpr double kCountsPerDeg = 12000.0 / 360.0;

// The vendor's axes (BiclopsDefault.cfg), with homing and run profiles fast enough for a test:
// 120 deg/s and 600 deg/s^2 (the emulated motors' limits are 150 deg/s and 600 deg/s^2).
std::array<VendorAxisConfig, 3> VendorAxes() {
  std::array<VendorAxisConfig, 3> axes{};
  const std::int32_t widths[3] = {50, 860, 300};
  const bool active_low[3] = {true, false, true};
  for (std::size_t a = 0; a < 3; ++a) {
    axes[a].home_sensor_width = widths[a];
    axes[a].home_active_low = active_low[a];
    axes[a].homing_vel = 90.0 * kCountsPerDeg;
    axes[a].homing_acc = 600.0 * kCountsPerDeg;
    axes[a].run_vel = 90.0 * kCountsPerDeg;
    axes[a].run_acc = 600.0 * kCountsPerDeg;
  }
  // Verge: -5..25 deg; libPMD's rangeOfMotion is one axis cycle for every axis.
  return axes;
}

TEST(BiclopsVendorHost, InitializesHomesMovesAndReadsAllThreeAxes) {
  const BiclopsEmulatorConfig config = PoweredUpBiclopsEmulatorConfig(3);
  BiclopsLineRig rig(config);
  VendorHost vendor(rig.Open(), rig.clock);
  const Clock::TimePoint t0 = rig.clock.Now();
  ASSERT_TRUE(vendor.Initialize(VendorAxes())) << vendor.error();
  ASSERT_TRUE(vendor.HomeAxes()) << vendor.error();
  const double homing_s = rig.Since(t0);
  // Homed: each axis stands at its true home, and its encoder reads 0 there.
  for (int a = 0; a < 3; ++a) {
    SCOPED_TRACE(a);
    std::int32_t counts = -1;
    ASSERT_TRUE(vendor.ReadPosition(a, &counts)) << vendor.error();
    EXPECT_EQ(counts, 0);
    EXPECT_NEAR(rig.ChipCounts(a), 0.0, 1.0);
    // The zero was found where the head powered up away from home.
    EXPECT_EQ(vendor.zero_position(a), -static_cast<std::int32_t>(config.start_counts[a]));
  }
  // A move of all three axes with one MultiUpdate, waited for on the event status.
  const std::array<std::int32_t, 3> target{1500, -700, 400};
  ASSERT_TRUE(vendor.Move(0b111, target)) << vendor.error();
  for (int a = 0; a < 3; ++a) {
    std::int32_t counts = 0;
    ASSERT_TRUE(vendor.ReadPosition(a, &counts)) << vendor.error();
    EXPECT_EQ(counts, target[a]);
    EXPECT_EQ(rig.ChipCounts(a), target[a]);
  }

  // An opcode libPMD's table does not have (0x01), with two argument words, in the middle of
  // the stream: the chip answers "invalid instruction" and keeps the framing, so the next
  // commands are answered right (before issue 16 its arguments began the next packet, which
  // then failed its checksum). A Magellan-only instruction with an argument likewise.
  pmd::Command unknown;
  unknown.opcode = 0x01;
  unknown.axis = 0;
  unknown.words = {0x1234, 0x0010, 0};
  unknown.word_count = 2;
  std::uint8_t status = 0xFF;
  ASSERT_TRUE(vendor.SendRaw(pmd::Encode(unknown), 0, &status)) << vendor.error();
  EXPECT_EQ(status, pmd::status::kInvalidInstruction);
  std::int32_t counts = 0;
  ASSERT_TRUE(vendor.ReadPosition(0, &counts)) << vendor.error();
  EXPECT_EQ(counts, target[0]);
  ASSERT_TRUE(
      vendor.SendRaw(pmd::Encode(pmd::WithWord(1, pmd::op::kSetOperatingMode, 0x33)), 0, &status));
  EXPECT_EQ(status, pmd::status::kInvalidInstruction);
  const std::array<std::int32_t, 3> back{0, 0, 0};
  ASSERT_TRUE(vendor.Move(0b111, back)) << vendor.error();
  for (int a = 0; a < 3; ++a) {
    ASSERT_TRUE(vendor.ReadPosition(a, &counts)) << vendor.error();
    EXPECT_EQ(counts, 0);
  }
  const BiclopsEmulator::Counts k = rig.With([](BiclopsEmulator& e) { return e.counts(); });
  EXPECT_EQ(k.checksum_errors, 0u);
  EXPECT_EQ(k.invalid_instructions, 2u);
  std::printf("vendor host: %d packets, homing took %.3f s (start %.0f %.0f %.0f counts)\n",
              vendor.packets(), homing_s, config.start_counts[0], config.start_counts[1],
              config.start_counts[2]);
}

BiclopsOptions FastHoming() {
  BiclopsOptions o = DefaultBiclopsOptions();
  for (BiclopsAxisOptions& x : o.axes) {
    x.homing_speed_rad_s = 90.0 * kPi / 180.0;
    x.homing_accel_rad_s2 = 600.0 * kPi / 180.0;
  }
  return o;
}

TEST(BiclopsHomingDriver, HomesThePoweredUpHeadToWithinOneCount) {
  for (std::uint64_t seed : {1u, 7u}) {
    SCOPED_TRACE(seed);
    const BiclopsEmulatorConfig config = PoweredUpBiclopsEmulatorConfig(seed);
    BiclopsRig rig(config, FastHoming());
    // Before homing the head reads 0 wherever it stands.
    device::HeadState s;
    ASSERT_EQ(rig.head.Read(&s), Status::kOk);
    EXPECT_EQ(s.q.pan, 0.0);
    EXPECT_FALSE(rig.head.homed());
    const Clock::TimePoint t0 = rig.clock.Now();
    ASSERT_EQ(rig.head.ConfigureAndHome(), Status::kOk) << rig.head.last_error();
    const double took = rig.Since(t0);
    EXPECT_TRUE(rig.head.homed());
    EXPECT_EQ(rig.head.last_error(), "");
    ASSERT_EQ(rig.head.Read(&s), Status::kOk);
    EXPECT_FALSE(s.moving);
    double worst = 0.0;
    const double q[3] = {s.q.pan, s.q.tilt, s.q.verge};
    for (int a = 0; a < 3; ++a) {
      const double truth = rig.ChipCounts(a);
      EXPECT_NEAR(truth, 0.0, 1.0) << "axis " << a;
      EXPECT_NEAR(q[a], 0.0, 2.0 * kPi / 12000.0 + 1e-12);  // one count
      worst = std::max(worst, std::abs(truth));
    }
    // The configuration reached the chip (libPMD's values: signal sense, filter, output mode).
    EXPECT_EQ(rig.With([](BiclopsEmulator& e) {
      return e.chip().EventStatus(0) & pmd::event::kMotionError;
    }),
              0);
    // Then moves land where device/head.h says, in the true frame.
    const device::HeadJoints target{0.4, -0.2, 0.1};
    ASSERT_EQ(rig.head.MoveTo(target), Status::kOk);
    const Clock::TimePoint t1 = rig.clock.Now();
    do {
      ASSERT_EQ(rig.head.Read(&s), Status::kOk);
    } while (s.moving && rig.Since(t1) < 10.0);
    const double move_s = rig.Since(t1);
    EXPECT_FALSE(s.moving) << "still moving after " << move_s << " s";
    const std::array<std::int32_t, 3> counts = rig.head.ToCounts(target);
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(rig.ChipCounts(a), counts[a], 1.0);
    std::printf("seed %llu: homed in %.3f s, worst error %.0f counts (start %.0f %.0f %.0f)\n",
                static_cast<unsigned long long>(seed), took, worst, config.start_counts[0],
                config.start_counts[1], config.start_counts[2]);
  }
}

// The `hgrasp emulate biclops` head homed at BiclopsDefault.cfg's own homing profiles (pan 50
// deg/s at 10 deg/s^2, tilt and verge 15 deg/s at 20 deg/s^2): 30 s of simulated time (27 s of
// wall time on a pty, so it was disabled), milliseconds of wall time here.
TEST(BiclopsHomingDriver, HomesAtTheVendorsHomingProfiles) {
  BiclopsRig rig(PoweredUpBiclopsEmulatorConfig(1));  // as MakeBiclopsEmulator()
  const Clock::TimePoint t0 = rig.clock.Now();
  ASSERT_EQ(rig.head.ConfigureAndHome(), Status::kOk) << rig.head.last_error();
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(rig.ChipCounts(a), 0.0, 1.0);
  std::printf("homed at the vendor's profiles in %.3f s\n", rig.Since(t0));
}

TEST(BiclopsHomingDriver, AHeadWithoutAnIndexPulseFailsInsteadOfHanging) {
  BiclopsEmulatorConfig config = PoweredUpBiclopsEmulatorConfig(5);
  config.has_index[1] = false;  // tilt: a dead index channel
  BiclopsRig rig(config, FastHoming());
  const Clock::TimePoint t0 = rig.clock.Now();
  EXPECT_EQ(rig.head.ConfigureAndHome(), Status::kRejected);
  const double took = rig.Since(t0);
  EXPECT_FALSE(rig.head.homed());
  EXPECT_NE(rig.head.last_error().find("tilt"), std::string::npos) << rig.head.last_error();
  EXPECT_NE(rig.head.last_error().find("index"), std::string::npos) << rig.head.last_error();
  // Not a hang: 4.415 s in simulated time (the bound was 20 s in wall time).
  EXPECT_LT(took, 6.0);
  std::printf("no tilt index: %s after %.3f s\n", rig.head.last_error().c_str(), took);
  // The link is still good: the head answers.
  device::HeadState s;
  EXPECT_EQ(rig.head.Read(&s), Status::kOk);
}

TEST(BiclopsHomingDriver, ACutCableDuringHomingIsATimeoutNamingTheStep) {
  BiclopsLineRig rig(PoweredUpBiclopsEmulatorConfig(2));
  auto faulty = std::make_unique<FaultyLink>(rig.Open(), FaultPlan{}, rig.clock);
  FaultyLink* cable = faulty.get();
  BiclopsHead head(std::move(faulty), FastHoming(), rig.clock);
  // The cable is cut 1 s into homing, while an axis sweeps.
  const Clock::TimePoint t0 = rig.clock.Now();
  rig.clock.At(t0 + std::chrono::seconds(1), [cable] { cable->Cut(true); });
  const Status s = head.ConfigureAndHome();
  const double took = rig.Since(t0);
  EXPECT_EQ(s, Status::kTimeout) << device::ToString(s);
  // The silence limit (0.4 s) after the last byte heard, then one line probe (a resync round
  // the chip leaves unanswered: 12 zero waits of 8.9 ms), not a hang: 1.507 s in simulated
  // time, the last reply having ended just before the cut (at most one 9600-baud exchange,
  // 10 ms, before it). Before the probe (issue: homing through the grasp run's noisy line) it
  // was 1.399 s. The upper bound was 2 s in wall time.
  EXPECT_GT(took, 1.0 + 0.4 - 0.02);
  EXPECT_LT(took, 1.6);
  EXPECT_EQ(head.counters().line_probes, 1u);
  EXPECT_NE(head.last_error().find("timeout"), std::string::npos) << head.last_error();
  EXPECT_NE(head.last_error().find("biclops tilt"), std::string::npos) << head.last_error();
  EXPECT_FALSE(head.homed());
  std::printf("cut during homing: %s after %.3f s\n", head.last_error().c_str(), took);
  // Mended, the head homes.
  cable->Cut(false);
  EXPECT_EQ(head.ConfigureAndHome(), Status::kOk) << head.last_error();
  EXPECT_TRUE(head.homed());
}

// Deaf for 0.3 s after every Update the host sends (a dropout of the chip's transmit wire
// just then: the Update arrives, its reply is lost, and so are the answers for 0.3 s): each
// Update is resolved by the driver's check of whether the chip took it, made by then.
class UpdateReplyEater final : public ByteLink {
 public:
  UpdateReplyEater(std::unique_ptr<ByteLink> inner, const Clock& clock)
      : inner_(std::move(inner)), clock_(clock) {}
  Status Write(std::span<const std::uint8_t> bytes) override {
    if (bytes.size() == 4 && bytes[3] == pmd::op::kUpdate) {
      deaf_until_ = clock_.Now() + std::chrono::milliseconds(300);
      ++updates_;
    }
    return inner_->Write(bytes);
  }
  Status Read(std::span<std::uint8_t> buf, double timeout_s, std::size_t* n) override {
    const Status s = inner_->Read(buf, timeout_s, n);
    if (s == Status::kOk && clock_.Now() < deaf_until_) *n = 0;
    return s;
  }
  void Discard() override { inner_->Discard(); }
  int updates() const { return updates_; }

 private:
  std::unique_ptr<ByteLink> inner_;
  const Clock& clock_;
  Clock::TimePoint deaf_until_{};
  int updates_ = 0;
};

// Bug fix: an Update whose reply was lost, of a sweep that a capture breakpoint had stopped
// short of its target by the time the driver looked, was taken as not executed (at rest, not at
// the target) and sent again: the chip executed it twice and the axis swept on to the target.
// (With that, homing through this link failed.) Every Update's reply lost, and 0.3 s of answers
// after it: homing succeeds, and the chip executed exactly what the driver's command log says
// (no Update twice).
TEST(BiclopsHomingDriver, LostUpdateRepliesAreResolvedNeverSentTwice) {
  BiclopsLineRig rig(PoweredUpBiclopsEmulatorConfig(1));
  auto eater_owned = std::make_unique<UpdateReplyEater>(rig.Open(), rig.clock);
  UpdateReplyEater* eater = eater_owned.get();
  BiclopsHead head(std::move(eater_owned), FastHoming(), rig.clock);
  const Clock::TimePoint t0 = rig.clock.Now();
  ASSERT_EQ(head.ConfigureAndHome(), Status::kOk) << head.last_error();
  const double took = rig.Since(t0);
  EXPECT_GT(eater->updates(), 20);
  const std::vector<PmdExecuted> chip = rig.With([](BiclopsEmulator& e) { return e.executed(); });
  const auto log = head.command_log().Snapshot();
  EXPECT_TRUE(LogExplains<pmd::Command>(log, chip, [](const pmd::Command& c, const PmdExecuted& x) {
    return c.axis == x.axis && c.opcode == x.opcode && pmd::CommandValue(c) == x.value;
  }));
  int updates = 0, unconfirmed = 0;
  for (std::size_t i = 0; i < chip.size(); ++i) {
    if (chip[i].opcode != pmd::op::kUpdate) continue;
    ++updates;
    EXPECT_FALSE(i > 0 && chip[i - 1] == chip[i]) << "entry " << i << ": Update twice";
  }
  for (const auto& e : log) unconfirmed += e.confirmed ? 0 : 1;
  std::printf(
      "every Update reply lost: %d Updates executed, %d driver log entries unconfirmed, homed in "
      "%.3f s\n",
      updates, unconfirmed, took);
  // Only the filter's Updates at configuration (motor off, the axis at its target already)
  // cannot be told from a lost one.
  EXPECT_LE(unconfirmed, 3);
}

// The grasp run's serial lines (the twin with --corrupt 0.01 --dropouts 0.2): 1 % of the bytes
// corrupted each way, dropouts of 0.2 s at 0.2 per second with at least 0.2 s of working line
// between two (FaultPlan::min_dropout_gap_s, as the twin sets it).
FaultPlan GraspRunLine(std::uint64_t seed) {
  FaultPlan plan;
  plan.corrupt_probability = 0.01;
  plan.dropouts_per_s = 0.2;
  plan.dropout_s = 0.2;
  plan.min_dropout_gap_s = 0.2;
  plan.seed = seed;
  return plan;
}

// The twin's end of a serial line (sim/twin/serial_line.cc, in lockstep): the twin polls its
// lines once per physics step (2 ms), so what the host writes goes onto the wire at the next
// poll, and what the device sent reaches the host at the first poll after it arrived. Between
// SimLine (the wire, the chip) and the driver. Round trips grow by a few ms, and the driver's
// wait per resynchronisation zero with them (14.8 ms instead of 8.5-8.9 ms in the traces).
class PolledLink final : public ByteLink {
 public:
  PolledLink(std::unique_ptr<ByteLink> inner, SimClock& clock, double poll_s)
      : inner_(std::move(inner)), clock_(clock), poll_(Clock::FromSeconds(poll_s)) {}
  Status Write(std::span<const std::uint8_t> bytes) override {
    if (out_.empty()) {
      std::weak_ptr<bool> alive = alive_;
      clock_.At(NextPoll(), [this, alive] {
        if (alive.expired()) return;
        // The wire takes what the poll hands it; a wire that refuses loses it (the twin's
        // poll does the same), and the driver's own checks see the loss.
        static_cast<void>(inner_->Write(out_));
        out_.clear();
      });
    }
    out_.insert(out_.end(), bytes.begin(), bytes.end());
    return Status::kOk;
  }
  Status Read(std::span<std::uint8_t> buf, double timeout_s, std::size_t* n) override {
    *n = 0;
    const Clock::TimePoint deadline = clock_.Now() + Clock::FromSeconds(std::max(timeout_s, 0.0));
    for (;;) {
      if (!in_.empty() && clock_.Now() >= in_at_) {
        // What else arrived by this poll (nothing: kTimeout).
        if (const Status s = Take(0.0); s != Status::kOk && s != Status::kTimeout) return s;
        while (*n < buf.size() && !in_.empty()) {
          buf[(*n)++] = in_.front();
          in_.erase(in_.begin());
        }
        return Status::kOk;
      }
      if (!in_.empty()) {
        clock_.SleepUntil(std::min(in_at_, deadline));
      } else {
        const Status s = Take(Clock::ToSeconds(deadline - clock_.Now()));
        if (s != Status::kOk && s != Status::kTimeout) return s;
      }
      if (clock_.Now() >= deadline && (in_.empty() || clock_.Now() < in_at_)) {
        return Status::kTimeout;
      }
    }
  }
  void Discard() override {
    // What reached the twin's end since its last poll is not the host's yet: it stays.
    // A poll: nothing there is kTimeout, and a failed read leaves nothing to keep.
    static_cast<void>(Take(0.0));
    inner_->Discard();
    if (clock_.Now() >= in_at_) in_.clear();
  }

 private:
  Clock::TimePoint NextPoll() const {
    const Clock::TimePoint now = clock_.Now();
    return now - now % poll_ + poll_;
  }
  Status Take(double timeout_s) {
    std::uint8_t raw[64];
    std::size_t got = 0;
    const Status s = inner_->Read(raw, timeout_s, &got);
    if (s == Status::kOk && got > 0) {
      if (in_.empty()) in_at_ = NextPoll();
      in_.insert(in_.end(), raw, raw + got);
    }
    return s;
  }

  std::unique_ptr<ByteLink> inner_;
  SimClock& clock_;
  Clock::Duration poll_;
  std::vector<std::uint8_t> out_, in_;
  Clock::TimePoint in_at_{};
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
};

// What crossed the FaultyLink, for telling the line's doing from the driver's: whether the line
// altered a packet or a reply into one that passes PMD's 8-bit checksum, which no driver can
// tell from a clean one (PROTOCOL.md, "Never twice, never altered", residual risk). One tap
// above the FaultyLink (`below` false: what the host sent and got) and one below it (what the
// chip got and sent; the plan corrupts bytes one for one and inserts none).
struct WireWitness {
  std::vector<std::uint8_t> sent;             ///< the host's last packet (resync zeros aside)
  pmd::CommandDecoder chip;                   ///< frames what reached the chip, as the chip does
  std::vector<std::uint8_t> chunk;            ///< the chip's bytes of the last read below
  std::vector<std::uint8_t> heard, answered;  ///< since the host's last write: got, chip sent
  int undetectable = 0;

  // A packet the chip framed that passes its checksum but is not the one sent (zeros left over
  // make a NoOperation, which changes nothing).
  void Arrived(std::span<const std::uint8_t> bytes) {
    std::vector<pmd::CommandDecoder::Packet> packets;
    chip.Feed(bytes, &packets);
    for (const auto& p : packets) {
      const auto raw = std::span<const std::uint8_t>(p.raw.data(), p.size);
      if (p.checksum_ok && p.command.opcode != pmd::op::kNoOperation &&
          !std::equal(raw.begin(), raw.end(), sent.begin(), sent.end())) {
        ++undetectable;
      }
    }
  }
  // Whether the reply to the last write was altered with its sum kept at 0, as the host frames
  // it: 2 bytes after a non-zero status, else as long as the chip's reply (2, 4 or 6 bytes).
  bool ReplyAltered() const {
    if (heard.empty() || heard == answered) return false;
    const bool as_sent = heard[0] == 0 && answered[0] == 0 && answered.size() <= 6;
    for (std::size_t k = 2; k <= pmd::kMaxReplyBytes && k <= heard.size(); k += 2) {
      if ((heard[0] != 0 && k != 2) || (as_sent && k != answered.size())) continue;
      const auto got = std::span<const std::uint8_t>(heard.data(), k);
      if (pmd::SumIsZero(got) && !std::equal(got.begin(), got.end(), answered.begin())) {
        return true;
      }
    }
    return false;
  }
};

class WitnessTap final : public ByteLink {
 public:
  WitnessTap(std::unique_ptr<ByteLink> inner, WireWitness* witness, bool below)
      : inner_(std::move(inner)), w_(witness), below_(below) {}
  Status Write(std::span<const std::uint8_t> bytes) override {
    if (below_) {
      w_->Arrived(bytes);
    } else {
      if (w_->ReplyAltered()) ++w_->undetectable;
      if (bytes.size() >= 4) w_->sent.assign(bytes.begin(), bytes.end());
      w_->heard.clear();
      w_->answered.clear();
    }
    return inner_->Write(bytes);
  }
  Status Read(std::span<std::uint8_t> buf, double timeout_s, std::size_t* n) override {
    const Status s = inner_->Read(buf, timeout_s, n);
    if (s != Status::kOk) return s;
    const auto got = buf.first(*n);
    if (below_) {
      w_->chunk.assign(got.begin(), got.end());
    } else if (*n == w_->chunk.size()) {  // the last chunk below, as it came through
      w_->heard.insert(w_->heard.end(), got.begin(), got.end());
      w_->answered.insert(w_->answered.end(), w_->chunk.begin(), w_->chunk.end());
    }
    return s;
  }
  void Discard() override { inner_->Discard(); }

 private:
  std::unique_ptr<ByteLink> inner_;
  WireWitness* w_;
  bool below_;
};

struct NoisyHoming {
  Status status = Status::kOk;
  std::string error;
  double took_s = 0.0, worst_counts = 0.0;
  bool log_ok = true;    ///< the chip executed what the driver's log says, no Update twice
  int undetectable = 0;  ///< packets and replies the line altered past the checksum
  BiclopsCounters counters;
  std::uint64_t dropouts = 0;
};

// Homes the powered-up head (start positions from `seed` too) through the grasp run's line with
// fault seed `seed`; poll_s > 0: through the twin's end polled that often (PolledLink).
NoisyHoming HomeThroughNoise(std::uint64_t seed, double poll_s) {
  BiclopsLineRig rig(PoweredUpBiclopsEmulatorConfig(seed));
  std::unique_ptr<ByteLink> wire = rig.Open();
  if (poll_s > 0.0) wire = std::make_unique<PolledLink>(std::move(wire), rig.clock, poll_s);
  WireWitness witness;
  wire = std::make_unique<WitnessTap>(std::move(wire), &witness, /*below=*/true);
  auto faulty = std::make_unique<FaultyLink>(std::move(wire), GraspRunLine(seed), rig.clock);
  const FaultyLink* noisy = faulty.get();
  BiclopsHead head(std::make_unique<WitnessTap>(std::move(faulty), &witness, /*below=*/false),
                   FastHoming(), rig.clock);
  NoisyHoming r;
  const Clock::TimePoint t0 = rig.clock.Now();
  r.status = head.ConfigureAndHome();
  r.took_s = rig.Since(t0);
  r.error = head.last_error();
  r.counters = head.counters();
  r.dropouts = noisy->counts().dropouts;
  r.undetectable = witness.undetectable + (witness.ReplyAltered() ? 1 : 0);
  for (int a = 0; a < 3; ++a) {
    r.worst_counts = std::max(r.worst_counts, std::abs(rig.ChipCounts(a)));
  }
  const std::vector<PmdExecuted> chip = rig.With([](BiclopsEmulator& e) { return e.executed(); });
  r.log_ok = LogExplains<pmd::Command>(
      head.command_log().Snapshot(), chip, [](const pmd::Command& c, const PmdExecuted& x) {
        return c.axis == x.axis && c.opcode == x.opcode && pmd::CommandValue(c) == x.value;
      });
  for (std::size_t i = 1; i < chip.size(); ++i) {
    if (chip[i].opcode == pmd::op::kUpdate && chip[i - 1] == chip[i]) r.log_ok = false;
  }
  return r;
}

// Bug fix: one fault seed of 50 failed the grasp run at homing ("biclops verge: moving below
// the home sensor: timeout"): a packet the line damaged into one the chip waits on (no answer:
// the 0.1 s reply wait), then a dropout (0.2 s) over the resynchronisation's zeros, then the
// zeros the chip still needed: 0.4 s without a byte, and homing ended. Now such a silence gets
// a line probe (one resynchronisation round) and the step goes on. Homing the powered-up head
// through the run's line for fault seeds 301-500, through the twin's end of the line (polled
// every 2 ms, as in the run): each homes to within one count, and the chip executed exactly
// what the driver's log says (nothing twice). Seeds where the line altered a packet past the
// checksum are counted, not judged (no driver can see those). The range holds two of the six
// seeds of 1-1000 that timed out before the fix (417 and 418; 200 homings take about 0.8 s of
// wall time). HGRASP_BICLOPS_HOMING_SEEDS=A..B measures another range (nothing asserted);
// HGRASP_BICLOPS_HOMING_POLL_S=s another poll period (0: SimLine's end directly).
TEST(BiclopsHomingDriver, HomesThroughTheGraspRunsNoisyLineForEveryFaultSeed) {
  std::uint64_t first = 301, last = 500;
  const char* range = std::getenv("HGRASP_BICLOPS_HOMING_SEEDS");
  if (range != nullptr) {
    const std::string text = range;
    const std::size_t dots = text.find("..");
    first = std::stoull(text.substr(0, dots));
    last = dots == std::string::npos ? first : std::stoull(text.substr(dots + 2));
  }
  double poll_s = 0.002;
  if (const char* p = std::getenv("HGRASP_BICLOPS_HOMING_POLL_S")) poll_s = std::stod(p);
  int runs = 0, homed = 0, altered = 0, altered_failed = 0;
  std::uint64_t probes = 0, dropouts = 0;
  double longest = 0.0;
  for (std::uint64_t seed = first; seed <= last; ++seed) {
    const NoisyHoming r = HomeThroughNoise(seed, poll_s);
    const bool ok = r.status == Status::kOk && r.worst_counts <= 1.0 && r.log_ok;
    ++runs;
    homed += ok ? 1 : 0;
    altered += r.undetectable > 0 ? 1 : 0;
    altered_failed += r.undetectable > 0 && !ok ? 1 : 0;
    probes += r.counters.line_probes;
    dropouts += r.dropouts;
    longest = std::max(longest, r.took_s);
    if (!ok) {
      std::printf("fault seed %llu: %s (%s) after %.3f s, worst %.0f counts, log %s%s\n",
                  static_cast<unsigned long long>(seed),
                  std::string(device::ToString(r.status)).c_str(), r.error.c_str(), r.took_s,
                  r.worst_counts, r.log_ok ? "explained" : "NOT EXPLAINED",
                  r.undetectable > 0 ? " (a packet altered past the checksum)" : "");
    }
    if (range != nullptr || r.undetectable > 0) continue;
    SCOPED_TRACE(seed);
    EXPECT_EQ(r.status, Status::kOk) << r.error;
    EXPECT_LE(r.worst_counts, 1.0);
    EXPECT_TRUE(r.log_ok);
  }
  std::printf(
      "noisy line, polled every %.3f s: %d of %d fault seeds homed (%d with a packet altered past "
      "the checksum, %d of them failed), %llu line probes, %llu dropouts, longest %.3f s\n",
      poll_s, homed, runs, altered, altered_failed, static_cast<unsigned long long>(probes),
      static_cast<unsigned long long>(dropouts), longest);
  if (range == nullptr) {
    EXPECT_GT(probes, 0u);  // the seeds exercise the line probe
  }
}

TEST(BiclopsHomingDriver, BadHomingOptionsNameTheField) {
  BiclopsOptions o = DefaultBiclopsOptions();
  o.axes[2].home_sensor_width_rad = 2.0;  // wider than an encoder cycle
  try {
    BiclopsHead head(std::make_unique<FaultyLink>(nullptr, FaultPlan{}), o);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "biclops.axes.verge.home_sensor_width_rad");
  }
  o = DefaultBiclopsOptions();
  o.axes[0].filter_kp = 40000;
  try {
    BiclopsHead head(std::make_unique<FaultyLink>(nullptr, FaultPlan{}), o);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "biclops.axes.pan.filter_kp");
  }
}

}  // namespace
}  // namespace hgrasp::drivers
