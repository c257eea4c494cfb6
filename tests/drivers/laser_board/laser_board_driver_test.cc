// The laser board driver against the emulator on a simulated 115200-baud line (SimLine, in
// simulated time: label unit): every seam method the pipeline uses (StripeLaser::Read/SetLaser/
// MoveTo, Leds::Count/Set) and the core's operations (status, velocity, frame latches for the
// camera driver), checking the emulator's model and the driver's readings; the sequence-number
// memory across drivers. The real transport and the camera thread beside the task's (wall-clock
// time) are laser_board_pty_test.cc's.

#include <gtest/gtest.h>

#include "common/error.h"
#include "laser_board_rig.h"

namespace hgrasp::drivers {
namespace {

namespace lb = laser_board;
using device::Side;
using device::Status;
using testing::SimBoardRig;

class LaserBoardDriverTest : public ::testing::Test {
 protected:
  LaserBoardDriverTest()
      : board_(std::make_shared<LaserBoard>(rig_.Open(), LaserBoardOptions{}, rig_.clock)),
        laser_(board_),
        leds_(board_) {}

  // Reads until the motor stops (at most `timeout_s`).
  device::StripeLaserState WaitStopped(double timeout_s = 3.0) {
    device::StripeLaserState s;
    const Clock::TimePoint t0 = rig_.clock.Now();
    do {
      EXPECT_EQ(laser_.Read(&s), Status::kOk);
      rig_.clock.SleepFor(0.01);
    } while (s.moving && rig_.Since(t0) < timeout_s);
    EXPECT_FALSE(s.moving);
    return s;
  }

  SimBoardRig rig_;
  std::shared_ptr<LaserBoard> board_;
  BoardStripeLaser laser_;
  BoardLeds leds_;
};

TEST_F(LaserBoardDriverTest, StatusAndVersion) {
  lb::BoardStatus s;
  ASSERT_EQ(board_->GetStatus(&s), Status::kOk);
  EXPECT_EQ(s.protocol_version, lb::kProtocolVersion);
  EXPECT_EQ(s.firmware_major, 1);
  EXPECT_EQ(s.leds_left, 8);
  EXPECT_EQ(s.leds_right, 8);
  EXPECT_FALSE(s.laser_on);
}

TEST_F(LaserBoardDriverTest, SetLaserSwitchesTheDiode) {
  device::StripeLaserState s;
  ASSERT_EQ(laser_.SetLaser(true), Status::kOk);
  EXPECT_TRUE(rig_.With([](LaserBoardEmulator& e) { return e.hardware().LaserOn(); }));
  ASSERT_EQ(laser_.Read(&s), Status::kOk);
  EXPECT_TRUE(s.laser_on);
  ASSERT_EQ(laser_.SetLaser(false), Status::kOk);
  EXPECT_FALSE(rig_.With([](LaserBoardEmulator& e) { return e.hardware().LaserOn(); }));
  ASSERT_EQ(laser_.Read(&s), Status::kOk);
  EXPECT_FALSE(s.laser_on);
  const std::vector<lb::Command> expected = {lb::SetLaser{true}, lb::SetLaser{false}};
  EXPECT_EQ(rig_.Executed(), expected);
}

TEST_F(LaserBoardDriverTest, MoveToReachesTheCountAndReadsIt) {
  device::StripeLaserState s0, s;
  ASSERT_EQ(laser_.Read(&s0), Status::kOk);
  EXPECT_EQ(s0.encoder_count, 0);
  ASSERT_EQ(laser_.MoveTo(-1200, 4000), Status::kOk);
  ASSERT_EQ(laser_.Read(&s), Status::kOk);
  EXPECT_TRUE(s.moving);
  s = WaitStopped();
  EXPECT_EQ(s.encoder_count, -1200);
  EXPECT_GT(s.t_s, s0.t_s);  // the board's clock
  EXPECT_EQ(rig_.With([](LaserBoardEmulator& e) { return e.hardware().EncoderCount(); }), -1200);
  ASSERT_EQ(laser_.MoveTo(4500, 9000), Status::kOk);  // the end of the travel
  EXPECT_EQ(WaitStopped().encoder_count, 4500);
  const std::vector<lb::Command> expected = {lb::MotorGoTo{-1200, 4000}, lb::MotorGoTo{4500, 9000}};
  EXPECT_EQ(rig_.Executed(), expected);
}

TEST_F(LaserBoardDriverTest, MoveToChecksItsArguments) {
  EXPECT_EQ(laser_.MoveTo(100, 0.0), Status::kRejected);     // no I/O
  EXPECT_EQ(laser_.MoveTo(100, -5.0), Status::kRejected);    // no I/O
  EXPECT_EQ(laser_.MoveTo(4501, 100.0), Status::kRejected);  // the board's NAK: out of range
  EXPECT_EQ(laser_.MoveTo(-9000, 100.0), Status::kRejected);
  ASSERT_EQ(laser_.MoveTo(300, 1e6), Status::kOk);  // clamped to the top speed
  ASSERT_EQ(laser_.MoveTo(310, 0.2), Status::kOk);  // at least 1 count/s
  ASSERT_EQ(laser_.MoveTo(320, 1234.4), Status::kOk);
  const std::vector<lb::Command> expected = {lb::MotorGoTo{300, 9000}, lb::MotorGoTo{310, 1},
                                             lb::MotorGoTo{320, 1234}};
  EXPECT_EQ(rig_.Executed(), expected);
}

TEST_F(LaserBoardDriverTest, MotorVelocityRunsToTheLimit) {
  ASSERT_EQ(board_->SetMotorVelocity(9000), Status::kOk);
  EXPECT_EQ(WaitStopped().encoder_count, 4500);
  EXPECT_EQ(board_->SetMotorVelocity(-9001), Status::kRejected);
  ASSERT_EQ(board_->SetMotorVelocity(-9000), Status::kOk);
  rig_.clock.SleepFor(0.2);
  ASSERT_EQ(board_->SetMotorVelocity(0), Status::kOk);  // stop
  const auto s = WaitStopped();
  EXPECT_LT(s.encoder_count, 4500 - 1000);
  EXPECT_GT(s.encoder_count, -4500);
}

TEST_F(LaserBoardDriverTest, LedsPerGripper) {
  EXPECT_EQ(leds_.Count(Side::kLeft), 8);
  EXPECT_EQ(leds_.Count(Side::kRight), 8);
  ASSERT_EQ(leds_.Set(Side::kRight, 0x15), Status::kOk);
  ASSERT_EQ(leds_.Set(Side::kLeft, 0xFF), Status::kOk);
  EXPECT_EQ(rig_.With([](LaserBoardEmulator& e) { return e.hardware().LedMask(1); }), 0x15u);
  EXPECT_EQ(rig_.With([](LaserBoardEmulator& e) { return e.hardware().LedMask(0); }), 0xFFu);
  EXPECT_EQ(leds_.Set(Side::kLeft, 0x100), Status::kRejected);  // LED 8 does not exist
  ASSERT_EQ(leds_.Set(Side::kLeft, 0), Status::kOk);
  EXPECT_EQ(rig_.With([](LaserBoardEmulator& e) { return e.hardware().LedMask(0); }), 0u);
  const std::vector<lb::Command> expected = {lb::SetLeds{1, 0x15}, lb::SetLeds{0, 0xFF},
                                             lb::SetLeds{0, 0}};
  EXPECT_EQ(rig_.Executed(), expected);
}

TEST_F(LaserBoardDriverTest, LedCountIsAnOption) {
  LaserBoardOptions options;
  options.leds_per_gripper = 4;
  auto board = std::make_shared<LaserBoard>(rig_.Open(), options, rig_.clock);
  BoardLeds leds(board);
  EXPECT_EQ(leds.Count(Side::kLeft), 4);
  EXPECT_EQ(leds.Set(Side::kLeft, 0x10), Status::kRejected);
  options.leds_per_gripper = 33;
  EXPECT_THROW(LaserBoard(rig_.Open(), options, rig_.clock), InputError);
}

TEST_F(LaserBoardDriverTest, FrameLatchesFollowTheSweep) {
  FrameLatch none;
  // The first VSYNC comes at 40 ms of the emulator's clock; wait for a few.
  rig_.clock.SleepFor(0.2);
  ASSERT_EQ(laser_.MoveTo(-2000, 9000), Status::kOk);
  WaitStopped();
  ASSERT_EQ(laser_.SetLaser(true), Status::kOk);
  ASSERT_EQ(laser_.MoveTo(2000, 2000), Status::kOk);  // 2 s sweep, 80 counts per frame
  std::vector<FrameLatch> seen;
  for (int i = 0; i < 12; ++i) {
    rig_.clock.SleepFor(0.04);
    FrameLatch l;
    ASSERT_EQ(board_->LatestFrameLatch(&l), Status::kOk);
    seen.push_back(l);
  }
  for (std::size_t i = 1; i < seen.size(); ++i) {
    EXPECT_GE(seen[i].frame, seen[i - 1].frame);
    EXPECT_GE(seen[i].encoder_count, seen[i - 1].encoder_count);
  }
  EXPECT_GT(seen.back().encoder_count, seen.front().encoder_count);
  EXPECT_TRUE(seen.back().laser_on);
  // A specific frame: its latch is the emulator's, and the count moved 80 per frame.
  const std::uint32_t f = seen.back().frame;
  FrameLatch a, b;
  ASSERT_EQ(board_->FrameLatchOf(f - 2, &a), Status::kOk);
  ASSERT_EQ(board_->FrameLatchOf(f - 1, &b), Status::kOk);
  EXPECT_EQ(a.frame, f - 2);
  EXPECT_NEAR(b.encoder_count - a.encoder_count, 80, 1);
  const auto ring = rig_.With([](LaserBoardEmulator& e) { return e.latches(); });
  bool found = false;
  for (const auto& l : ring) {
    if (l.frame == a.frame) {
      EXPECT_EQ(l, a);
      found = true;
    }
  }
  EXPECT_TRUE(found);
  // Aged out of the 16-frame ring, or not happened yet.
  EXPECT_EQ(board_->FrameLatchOf(f - 40, &none), Status::kRejected);
  EXPECT_EQ(board_->FrameLatchOf(f + 1000, &none), Status::kRejected);
}

TEST_F(LaserBoardDriverTest, ANewDriverContinuesAfterTheBoardsLastSequenceNumber) {
  // The board remembers the last number; a driver that started again from 1 would see its first
  // command answered from that memory and not executed. The driver asks the board first.
  ASSERT_EQ(laser_.SetLaser(true), Status::kOk);
  const std::uint8_t last = rig_.With([](LaserBoardEmulator& e) { return e.last_seq(); });
  EXPECT_NE(last, lb::kUnsequenced);
  board_.reset();  // (the adapters still hold it; the new driver gets its own port)
  auto again = std::make_shared<LaserBoard>(rig_.Open(), LaserBoardOptions{}, rig_.clock);
  ASSERT_EQ(again->SetLaser(false), Status::kOk);
  EXPECT_FALSE(rig_.With([](LaserBoardEmulator& e) { return e.hardware().LaserOn(); }));
  EXPECT_NE(rig_.With([](LaserBoardEmulator& e) { return e.last_seq(); }), last);
  // Sequence numbers wrap 255 -> 1 (0 is the unsequenced number) without a hiccup.
  for (int i = 0; i < 300; ++i) {
    ASSERT_EQ(again->SetLeds(Side::kLeft, static_cast<std::uint32_t>(i % 64)), Status::kOk);
  }
  EXPECT_EQ(rig_.Executed().size(), 302u);
  EXPECT_EQ(again->stats().retransmissions, 0u);
}

}  // namespace
}  // namespace hgrasp::drivers
