// The laser board emulator on its own (no pty): bytes in, bytes out, model state. Strict frame
// checking, NAK codes, the sequence-number memory, the frame-latch ring and the motor model.

#include "emulators/laser_board_emulator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "laser_board/laser_board_codec.h"

namespace hgrasp::drivers {
namespace {

namespace lb = laser_board;
using Bytes = std::vector<std::uint8_t>;

// Sends one frame's bytes at time t and returns the parsed replies.
std::vector<lb::Reply> Send(LaserBoardEmulator& board, const Bytes& bytes, double t) {
  Bytes out;
  board.Advance(t, &out);
  board.Receive(bytes, t, &out);
  lb::FrameDecoder d;
  std::vector<lb::DecodeEvent> events;
  d.Feed(out, &events);
  std::vector<lb::Reply> replies;
  for (const auto& e : events) {
    EXPECT_EQ(e.kind, lb::DecodeEvent::Kind::kFrame);
    const auto r = lb::ParseReply(e.frame);
    EXPECT_TRUE(r.has_value());
    if (r) replies.push_back(*r);
  }
  return replies;
}

lb::Reply SendOne(LaserBoardEmulator& board, std::uint8_t seq, const lb::Command& c, double t) {
  const auto replies = Send(board, lb::EncodeFrame(lb::CommandFrame(seq, c)), t);
  EXPECT_EQ(replies.size(), 1u);
  return replies.empty() ? lb::Reply{} : replies[0];
}

TEST(LaserBoardEmulator, ExecutesAndAcknowledges) {
  LaserBoardEmulator board;
  auto r = SendOne(board, 1, lb::SetLaser{true}, 0.001);
  EXPECT_TRUE(r.ack);
  EXPECT_EQ(r.seq, 1);
  EXPECT_EQ(r.command, static_cast<std::uint8_t>(lb::Code::kSetLaser));
  EXPECT_TRUE(board.hardware().LaserOn());

  r = SendOne(board, 2, lb::SetLeds{1, 0x2D}, 0.002);
  EXPECT_TRUE(r.ack);
  EXPECT_EQ(board.hardware().LedMask(1), 0x2Du);
  EXPECT_EQ(board.hardware().LedMask(0), 0u);

  r = SendOne(board, 3, lb::GetStatus{0x42}, 0.003);
  ASSERT_TRUE(r.ack);
  const auto status = lb::ParseStatus(r.data);
  ASSERT_TRUE(status);
  EXPECT_EQ(status->token, 0x42);
  EXPECT_EQ(status->last_seq, 2);
  EXPECT_TRUE(status->laser_on);
  EXPECT_EQ(status->leds_left, 8);
  EXPECT_EQ(status->leds_right, 8);

  const std::vector<lb::Command> expected = {lb::SetLaser{true}, lb::SetLeds{1, 0x2D}};
  EXPECT_EQ(board.ExecutedCommands(), expected);
}

TEST(LaserBoardEmulator, RetransmissionIsAnsweredFromMemoryNotExecuted) {
  LaserBoardEmulator board;
  const Bytes move = lb::EncodeFrame(lb::CommandFrame(9, lb::MotorGoTo{1000, 9000}));
  const auto first = Send(board, move, 0.01);
  const auto again = Send(board, move, 0.02);
  ASSERT_EQ(first.size(), 1u);
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(first[0], again[0]);
  EXPECT_EQ(board.log().size(), 1u);
  EXPECT_EQ(board.counts().replayed, 1u);

  // The same number with another command: refused, not executed.
  const auto other = SendOne(board, 9, lb::MotorGoTo{-1000, 9000}, 0.03);
  EXPECT_FALSE(other.ack);
  EXPECT_EQ(other.error, lb::ErrorCode::kSequenceReused);
  EXPECT_EQ(board.log().size(), 1u);

  // Unsequenced: read-only commands only, never remembered.
  const auto status = SendOne(board, 0, lb::GetStatus{1}, 0.04);
  ASSERT_TRUE(status.ack);
  EXPECT_EQ(lb::ParseStatus(status.data)->last_seq, 9);
  const auto refused = SendOne(board, 0, lb::SetLaser{true}, 0.05);
  EXPECT_FALSE(refused.ack);
  EXPECT_EQ(refused.error, lb::ErrorCode::kUnsequenced);
  EXPECT_EQ(board.last_seq(), 9);
  EXPECT_FALSE(board.hardware().LaserOn());
}

TEST(LaserBoardEmulator, StrictFrameChecking) {
  LaserBoardEmulator board;
  // Bad CRC: NAK with the SEQ and code as received.
  Bytes bad = lb::EncodeFrame(lb::CommandFrame(4, lb::SetLaser{true}));
  bad.back() ^= 0x55;
  auto replies = Send(board, bad, 0.01);
  ASSERT_EQ(replies.size(), 1u);
  EXPECT_FALSE(replies[0].ack);
  EXPECT_EQ(replies[0].seq, 4);
  EXPECT_EQ(replies[0].error, lb::ErrorCode::kBadCrc);
  EXPECT_FALSE(board.hardware().LaserOn());
  // Unknown command, bad length, out of range.
  auto r = SendOne(board, 5, lb::Command{}, 0.02);  // GetStatus{0} for reference
  EXPECT_TRUE(r.ack);
  replies = Send(board, lb::EncodeFrame(lb::Frame{6, 0x7E, {}}), 0.03);
  ASSERT_EQ(replies.size(), 1u);
  EXPECT_EQ(replies[0].error, lb::ErrorCode::kUnknownCommand);
  EXPECT_EQ(replies[0].command, 0x7E);
  replies = Send(board, lb::EncodeFrame(lb::Frame{7, 0x10, {1, 0}}), 0.04);
  ASSERT_EQ(replies.size(), 1u);
  EXPECT_EQ(replies[0].error, lb::ErrorCode::kBadLength);
  std::uint8_t seq = 10;
  for (const lb::Command& c :
       {lb::Command{lb::MotorGoTo{4501, 100}}, lb::Command{lb::MotorGoTo{-4501, 100}},
        lb::Command{lb::MotorGoTo{0, 0}}, lb::Command{lb::MotorGoTo{0, 9001}},
        lb::Command{lb::MotorVelocity{-9001}}, lb::Command{lb::SetLeds{2, 1}},
        lb::Command{lb::SetLeds{0, 0x100}}}) {
    r = SendOne(board, seq++, c, 0.05);
    EXPECT_FALSE(r.ack);
    EXPECT_EQ(r.error, lb::ErrorCode::kOutOfRange);
  }
  EXPECT_TRUE(board.log().empty());
}

TEST(LaserBoardEmulator, MotorFollowsATrapezoidWithinLimits) {
  LaserBoardEmulator board;
  ASSERT_TRUE(SendOne(board, 1, lb::MotorGoTo{4500, 9000}, 0.0).ack);
  Bytes out;
  // 4500 counts at 9000 counts/s with 0.04 s ramps: 0.5 s + 0.04 s.
  board.Advance(0.25, &out);
  EXPECT_TRUE(board.hardware().Moving());
  const int mid = board.hardware().EncoderCount();
  EXPECT_GT(mid, 1500);
  EXPECT_LT(mid, 2500);
  board.Advance(0.6, &out);
  EXPECT_FALSE(board.hardware().Moving());
  EXPECT_EQ(board.hardware().EncoderCount(), 4500);
  // Velocity mode stops at the travel limit.
  ASSERT_TRUE(SendOne(board, 2, lb::MotorVelocity{-9000}, 0.6).ack);
  board.Advance(2.0, &out);
  EXPECT_EQ(board.hardware().EncoderCount(), -4500);
  const auto r = SendOne(board, 3, lb::GetEncoder{}, 2.0);
  const auto reading = lb::ParseEncoder(r.data);
  ASSERT_TRUE(reading);
  EXPECT_EQ(reading->count, -4500);
  EXPECT_EQ(reading->board_time_ms, 2000u);
}

TEST(LaserBoardEmulator, LatchesTheCountAtEachFrame) {
  LaserBoardEmulator board;
  // Constant speed 1000 counts/s from -2000 after the ramp: the latches step by 40 counts.
  Bytes out;
  ASSERT_TRUE(SendOne(board, 1, lb::MotorGoTo{-2000, 9000}, 0.0).ack);
  board.Advance(1.0, &out);
  ASSERT_TRUE(SendOne(board, 2, lb::MotorGoTo{2000, 1000}, 1.0).ack);
  for (double t = 1.0; t < 2.0; t += 0.002) board.Advance(t, &out);  // the host's 2 ms tick
  ASSERT_EQ(board.latches().size(), LaserBoardEmulator::kLatchRing);
  const FrameLatch last = board.latches().back();
  EXPECT_EQ(last.frame, board.frame());
  EXPECT_EQ(board.frame(), 49u);  // pulses at 0.04, 0.08, ..., 1.96 s
  for (std::size_t i = 1; i < board.latches().size(); ++i) {
    EXPECT_EQ(board.latches()[i].frame, board.latches()[i - 1].frame + 1);
    EXPECT_NEAR(board.latches()[i].encoder_count - board.latches()[i - 1].encoder_count, 40, 1);
  }
  auto r = SendOne(board, 3, lb::GetLatch{lb::kLatestFrame}, 1.999);
  ASSERT_TRUE(r.ack);
  EXPECT_EQ(lb::ParseLatch(r.data), last);
  r = SendOne(board, 4, lb::GetLatch{last.frame - 15}, 1.999);
  ASSERT_TRUE(r.ack);
  EXPECT_EQ(lb::ParseLatch(r.data)->frame, last.frame - 15);
  r = SendOne(board, 5, lb::GetLatch{last.frame - 16}, 1.999);  // aged out
  EXPECT_FALSE(r.ack);
  EXPECT_EQ(r.error, lb::ErrorCode::kNoSuchFrame);
  r = SendOne(board, 6, lb::GetLatch{last.frame + 1}, 1.999);  // not yet
  EXPECT_EQ(r.error, lb::ErrorCode::kNoSuchFrame);
}

TEST(LaserBoardEmulator, NoLatchBeforeTheFirstFrame) {
  LaserBoardEmulator board;
  const auto r = SendOne(board, 1, lb::GetLatch{lb::kLatestFrame}, 0.01);
  EXPECT_FALSE(r.ack);
  EXPECT_EQ(r.error, lb::ErrorCode::kNoSuchFrame);
}

TEST(LaserBoardEmulator, InterByteTimeoutReleasesAHiddenFrame) {
  LaserBoardEmulator board;
  Bytes stream = {0xA5, 0x10};  // a false start announcing 16 bytes
  const Bytes good = lb::EncodeFrame(lb::CommandFrame(1, lb::SetLaser{true}));
  stream.insert(stream.end(), good.begin(), good.end());
  EXPECT_TRUE(Send(board, stream, 0.100).empty());
  EXPECT_FALSE(board.hardware().LaserOn());
  Bytes out;
  board.Advance(0.105, &out);
  EXPECT_TRUE(out.empty());
  board.Advance(0.120, &out);  // 20 ms of silence
  EXPECT_TRUE(board.hardware().LaserOn());
  EXPECT_FALSE(out.empty());
}

}  // namespace
}  // namespace hgrasp::drivers
