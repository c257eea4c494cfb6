// The SensorHand emulator without a pty: its protocol as a stock hand speaks it (echoes, the
// published 9-byte stream frame and nothing more, stream rate, strict frames, the state byte)
// and its mechanics (speeds, acceleration, range, object stiffness, stall force).

#include "emulators/sensorhand_emulator.h"

#include <gtest/gtest.h>

#include <cmath>

namespace hgrasp::drivers {
namespace {

using Bytes = std::vector<std::uint8_t>;
using sensorhand::Reply;
using sensorhand::SpeedSetting;

struct Rig {
  explicit Rig(double object_width_m = 0.0) {
    SensorHandMechanics m;
    m.object_width_m = object_width_m;
    auto model = std::make_unique<KinematicSensorHand>(m);
    hand = model.get();
    emu = std::make_unique<SensorHandEmulator>(std::move(model));
    emu->Advance(0.0, &out);
  }
  // Sends bytes at t; returns what the hand answered.
  std::vector<Reply> Send(const Bytes& b) {
    out.clear();
    emu->Advance(t, &out);
    emu->Receive(b, t, &out);
    return Decode();
  }
  // Runs the host's 2 ms tick for `s` seconds; returns the frames sent meanwhile.
  std::vector<Reply> Run(double s) {
    out.clear();
    const double end = t + s;
    while (t < end - 1e-9) {
      t += 0.002;
      emu->Advance(t, &out);
    }
    return Decode();
  }
  std::vector<Reply> Decode() {
    std::vector<Reply> r;
    dec.Push(out, &r);
    return r;
  }
  KinematicSensorHand* hand;
  std::unique_ptr<SensorHandEmulator> emu;
  sensorhand::ReplyDecoder dec;
  Bytes out;
  double t = 0.0;
};

TEST(SensorHandEmulator, EchoesEachCommand) {
  Rig rig;
  auto r = rig.Send(sensorhand::EncodeSpeed({0x85, 0}));
  EXPECT_EQ(rig.out, (Bytes{0x03, 0x85, 0x00, 0x88}));
  EXPECT_EQ(rig.emu->counter(), 1);
  r = rig.Send(sensorhand::EncodeDumpStart());
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].kind, Reply::Kind::kDumpStartEcho);
  EXPECT_EQ(rig.out, (Bytes{0x02, 0x73, 0x75}));
  rig.Run(0.1);
  r = rig.Send(sensorhand::EncodeDumpStop());
  ASSERT_FALSE(r.empty());
  EXPECT_EQ(r.back().kind, Reply::Kind::kDumpStopEcho);
  EXPECT_EQ(Bytes(rig.out.end() - 3, rig.out.end()), (Bytes{0x02, 0x7A, 0x7C}));
  EXPECT_FALSE(rig.emu->streaming());
  ASSERT_EQ(rig.emu->log().size(), 3u);
  EXPECT_EQ(rig.emu->speed_log(), (std::vector<SpeedSetting>{{0x85, 0}}));
}

TEST(SensorHandEmulator, StreamsEvery12Ms) {
  Rig rig;
  rig.Send(sensorhand::EncodeDumpStart());
  const auto frames = rig.Run(1.2);
  // 1.2 s / 12 ms = 100 frames (the first at once), 12 bytes each and nothing between.
  EXPECT_NEAR(static_cast<double>(frames.size()), 100.0, 1.0);
  EXPECT_EQ(rig.out.size(), frames.size() * sensorhand::kDumpFrameBytes);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    ASSERT_EQ(frames[i].kind, Reply::Kind::kDump);
    EXPECT_EQ(frames[i].dump.state, static_cast<std::uint8_t>(sensorhand::MotionState::kIdle));
    EXPECT_NEAR(sensorhand::BatteryV(frames[i].dump.v_bat), 7.4, 0.05);
  }
  rig.Send(sensorhand::EncodeDumpStop());
  EXPECT_TRUE(rig.Run(0.2).empty());
}

TEST(SensorHandEmulator, IgnoresDamagedAndStaleFrames) {
  Rig rig;
  Bytes bad = sensorhand::EncodeSpeed({0x85, 0});
  bad[2] ^= 0x40;
  EXPECT_TRUE(rig.Send(bad).empty());
  EXPECT_TRUE(rig.emu->log().empty());
  // Half a frame, then the rest after a pause longer than kFrameGapS: dropped.
  const Bytes cmd = sensorhand::EncodeSpeed({0, 0x85});
  rig.Send(Bytes(cmd.begin(), cmd.begin() + 2));
  rig.Run(0.1);
  EXPECT_TRUE(rig.Send(Bytes(cmd.begin() + 2, cmd.end())).empty());
  EXPECT_TRUE(rig.emu->log().empty());
  // Garbage, then a good frame: executed once.
  Bytes mixed = {0x00, 0x04, 0x99, 0xFF};
  mixed.insert(mixed.end(), cmd.begin(), cmd.end());
  const auto r = rig.Send(mixed);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].speed, (SpeedSetting{0, 0x85}));
  EXPECT_EQ(rig.emu->speed_log().size(), 1u);
  EXPECT_GT(rig.emu->discarded_bytes(), 0u);
}

TEST(SensorHandEmulator, SpeedsAccelerationAndRange) {
  Rig rig;
  rig.Send(sensorhand::EncodeSpeed({0x85, 0}));
  rig.Run(0.01);
  // 10 m/s^2 from rest: 0.1 m/s after 10 ms.
  EXPECT_NEAR(rig.hand->velocity_m_s(), 0.1, 0.005);
  rig.Run(0.2);
  EXPECT_DOUBLE_EQ(rig.hand->opening_m(), 0.10);  // the end stop
  rig.Send(sensorhand::EncodeSpeed({0, 0x85}));
  rig.Run(0.2);
  EXPECT_NEAR(rig.hand->velocity_m_s(), -0.30, 1e-9);  // full speed closing
  rig.Run(0.3);
  EXPECT_DOUBLE_EQ(rig.hand->opening_m(), 0.0);  // fingers meet
  EXPECT_EQ(rig.hand->grip_force_n(), 0.0);
  // Half speed: (0x5B - 0x30) / 85 of 0.3 m/s.
  rig.Send(sensorhand::EncodeSpeed({0x5B, 0}));
  rig.Run(0.1);
  EXPECT_NEAR(rig.hand->velocity_m_s(), 0.3 * 43.0 / 85.0, 1e-9);
  rig.Send(sensorhand::EncodeSpeed(sensorhand::kStop));
  rig.Run(0.05);
  EXPECT_EQ(rig.hand->velocity_m_s(), 0.0);
}

TEST(SensorHandEmulator, GripSettlesAtTheStallForceOfTheCloseSpeed) {
  for (double force : {20.0, 40.0, 100.0}) {
    Rig rig(0.05);
    const std::uint8_t b = sensorhand::SpeedByteAtMost(force / 100.0);
    const double stall = 100.0 * sensorhand::SpeedFraction(b);
    rig.Send(sensorhand::EncodeDumpStart());
    rig.Send(sensorhand::EncodeSpeed({0, b}));
    const auto frames = rig.Run(1.5);
    EXPECT_LE(rig.hand->grip_force_n(), stall + 1e-9) << force;
    EXPECT_GE(rig.hand->grip_force_n(), 0.97 * stall) << force;
    EXPECT_NEAR(rig.hand->opening_m(), 0.05 - rig.hand->grip_force_n() / 5000.0, 1e-9);
    ASSERT_FALSE(frames.empty());
    const auto& last = frames.back().dump;
    EXPECT_EQ(last.state, static_cast<std::uint8_t>(sensorhand::MotionState::kBlocked));
    EXPECT_NEAR(sensorhand::ForceN(last.f_bracket), rig.hand->grip_force_n(), 0.6);
    // Speed 0 holds the grip.
    rig.Send(sensorhand::EncodeSpeed(sensorhand::kStop));
    const double held = rig.hand->grip_force_n();
    rig.Run(0.5);
    EXPECT_NEAR(rig.hand->grip_force_n(), held, 1e-6);
    // Opening lets go.
    rig.Send(sensorhand::EncodeSpeed({0x85, 0}));
    rig.Run(0.3);
    EXPECT_EQ(rig.hand->grip_force_n(), 0.0);
  }
}

// Bug fix: a weaker close speed on a stronger grip used to move the fingers back out to the
// weaker speed's stall opening at once (the grip "sprang back"); the gear does not back-drive,
// so the grip holds where it is and the motor stalls.
TEST(SensorHandEmulator, WeakerCloseOnAStrongerGripHolds) {
  Rig rig(0.05);
  rig.Send(sensorhand::EncodeSpeed({0, 0x85}));  // 100 N stall
  rig.Run(1.0);
  const double y = rig.hand->opening_m();
  const double f = rig.hand->grip_force_n();
  ASSERT_GT(f, 90.0);
  rig.Send(sensorhand::EncodeSpeed({0, 0x3B}));  // 12.9 N stall
  rig.Run(0.3);
  EXPECT_NEAR(rig.hand->opening_m(), y, 1e-9);
  EXPECT_NEAR(rig.hand->grip_force_n(), f, 1e-6);
  EXPECT_EQ(rig.hand->velocity_m_s(), 0.0);
}

TEST(SensorHandEmulator, PowerCycleStopsTheStreamAndResetsCounters) {
  Rig rig;
  rig.Send(sensorhand::EncodeDumpStart());
  rig.Send(sensorhand::EncodeSpeed({0x40, 0}));
  rig.Run(0.1);
  rig.emu->PowerCycle();
  EXPECT_FALSE(rig.emu->streaming());
  EXPECT_EQ(rig.emu->counter(), 0);
  EXPECT_TRUE(rig.Run(0.1).empty());
  rig.Send(sensorhand::EncodeDumpStart());
  const auto frames = rig.Run(0.05);
  ASSERT_FALSE(frames.empty());
  // Speed 0 after the reset: the fingers stand still, the state byte says idle.
  EXPECT_EQ(rig.emu->speed(), sensorhand::kStop);
  EXPECT_EQ(frames.back().dump.state, static_cast<std::uint8_t>(sensorhand::MotionState::kIdle));
}

// The stock frame, byte for byte: [FF][0A][9 data bytes][CS], the data as publish_dump() reads
// them, and no trace of the finger position: the same forces and state at two openings give
// the same bytes.
TEST(SensorHandEmulator, SendsThePublishedFrameAndNothingMore) {
  Rig rig;
  rig.Send(sensorhand::EncodeDumpStart());
  rig.Run(0.05);
  const Bytes at_80mm(rig.out.end() - sensorhand::kDumpFrameBytes, rig.out.end());
  sensorhand::DumpSample want;
  want.v_bat = sensorhand::BatteryRaw(7.4);
  want.state = static_cast<std::uint8_t>(sensorhand::MotionState::kIdle);
  want.current = sensorhand::CurrentRaw(0.05);  // the electronics alone
  EXPECT_EQ(at_80mm, sensorhand::EncodeDump(want));
  EXPECT_EQ(at_80mm[1], 0x0A);
  // Close to 30 mm, stop, let the fingers settle: the frame is the same.
  rig.Send(sensorhand::EncodeSpeed({0, 0x85}));
  rig.Run(0.16);
  rig.Send(sensorhand::EncodeSpeed(sensorhand::kStop));
  rig.Run(0.1);
  EXPECT_LT(rig.hand->opening_m(), 0.05);
  const Bytes at_30mm(rig.out.end() - sensorhand::kDumpFrameBytes, rig.out.end());
  EXPECT_EQ(at_30mm, at_80mm);
}

// The state byte (values ours): opening or closing while a speed is set and the fingers move,
// or have not been still for kBlockedAfterS; blocked after that; idle at speed 0 once still.
TEST(SensorHandEmulator, StateByteTellsMotionBlockAndIdle) {
  using sensorhand::MotionState;
  Rig rig;
  rig.Send(sensorhand::EncodeDumpStart());
  rig.Run(0.03);
  rig.Send(sensorhand::EncodeSpeed({0x85, 0}));  // 20 mm to the end stop: about 80 ms
  std::vector<std::uint8_t> states;
  double t_stop = -1.0, t_blocked = -1.0;
  for (int i = 0; i < 100; ++i) {
    const auto f = rig.Run(0.002);
    if (t_stop < 0.0 && rig.hand->opening_m() >= 0.10) t_stop = rig.t;
    for (const Reply& r : f) {
      states.push_back(r.dump.state);
      if (t_blocked < 0.0 && r.dump.state == static_cast<std::uint8_t>(MotionState::kBlocked)) {
        t_blocked = rig.t;
      }
    }
  }
  ASSERT_FALSE(states.empty());
  // Never blocked at the start, though the first sample after the command sees the fingers
  // at rest.
  EXPECT_EQ(states.front(), static_cast<std::uint8_t>(MotionState::kOpening));
  ASSERT_GT(t_stop, 0.0);
  ASSERT_GT(t_blocked, 0.0);
  EXPECT_GE(t_blocked - t_stop, SensorHandEmulator::kBlockedAfterS - 1e-9);
  EXPECT_LE(t_blocked - t_stop, SensorHandEmulator::kBlockedAfterS + sensorhand::kDumpPeriodS);
  rig.Send(sensorhand::EncodeSpeed(sensorhand::kStop));
  const auto after = rig.Run(0.05);
  ASSERT_FALSE(after.empty());
  EXPECT_EQ(after.back().dump.state, static_cast<std::uint8_t>(MotionState::kIdle));
}

TEST(SensorHandEmulator, FactoryDefaults) {
  auto emu = MakeSensorHandEmulator();
  auto& hand = dynamic_cast<SensorHandEmulator&>(*emu);
  EXPECT_FALSE(hand.streaming());
  EXPECT_NEAR(hand.model().opening_m(), 0.08, 1e-12);
  auto& k = dynamic_cast<KinematicSensorHand&>(hand.model());
  EXPECT_EQ(k.mechanics().object_width_m, 0.05);
}

}  // namespace
}  // namespace hgrasp::drivers
