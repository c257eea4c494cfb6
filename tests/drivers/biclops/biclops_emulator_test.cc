// The emulated PMD chip, byte for byte, without a pty: replies, strict packet checks, the
// trapezoidal profile after Update, status bits, Reset, and the log of executed commands.

#include "emulators/biclops_emulator.h"

#include <gtest/gtest.h>

#include <cmath>

namespace hgrasp::drivers {
namespace {

using Bytes = std::vector<std::uint8_t>;
namespace op = pmd::op;

Bytes Send(BiclopsEmulator& e, const pmd::Command& c, double t_s) {
  Bytes out;
  e.Receive(pmd::Encode(c), t_s, &out);
  return out;
}

Bytes SendRaw(BiclopsEmulator& e, const Bytes& bytes, double t_s) {
  Bytes out;
  e.Receive(bytes, t_s, &out);
  return out;
}

std::int64_t Long(const Bytes& reply) {
  pmd::ReplyDecoder d;
  d.Expect(2);
  for (std::uint8_t b : reply) d.Push(b);
  return pmd::ReplyLong(d.reply());
}

std::uint16_t Word(const Bytes& reply) {
  EXPECT_EQ(reply.size(), 4u);
  return static_cast<std::uint16_t>((reply[2] << 8) | reply[3]);
}

TEST(BiclopsEmulator, AnswersNoOperationVersionAndSampleTime) {
  BiclopsEmulator e;
  EXPECT_EQ(Send(e, pmd::NoOperation(), 0.0), (Bytes{0x00, 0x00}));
  EXPECT_EQ(Send(e, pmd::Simple(0, op::kGetVersion), 0.0),
            (Bytes{0x00, 0x9A, 0x21, 0x30, 0x00, 0x15}));
  // 153 us = 0x0099: cs 0x67.
  EXPECT_EQ(Send(e, pmd::Simple(0, op::kGetSampleTime), 0.0), (Bytes{0x00, 0x67, 0x00, 0x99}));
  EXPECT_TRUE(e.executed().empty());
}

TEST(BiclopsEmulator, RejectsDamagedPacketsWithoutExecuting) {
  BiclopsEmulator e;
  Bytes bad = pmd::Encode(pmd::SetPosition(0, 1000));
  bad[6] ^= 0x40;                                        // a data byte
  EXPECT_EQ(SendRaw(e, bad, 0.0), (Bytes{0x09, 0xF7}));  // BadSerialChecksum
  // Unknown opcode 0x01 with a right sum: InvalidInstruction after the 4 header bytes.
  EXPECT_EQ(SendRaw(e, {0x00, 0xFF, 0x00, 0x01}, 0.0), (Bytes{0x02, 0xFE}));
  // Axis 3 on a three-axis chip: InvalidAxis.
  EXPECT_EQ(Send(e, pmd::Update(3), 0.0), (Bytes{0x03, 0xFD}));
  // A multidrop address in point-to-point mode.
  pmd::Command addressed = pmd::Update(0);
  addressed.address = 5;
  EXPECT_EQ(Send(e, addressed, 0.0), (Bytes{0x02, 0xFE}));
  // Negative velocity in trapezoidal mode (libPMD "Invalid Negative Value for Profile Mode").
  EXPECT_EQ(Send(e, pmd::SetVelocity(0, -100), 0.0), (Bytes{0x0B, 0xF5}));
  // Only trapezoidal profiles are modelled.
  EXPECT_EQ(Send(e, pmd::SetProfileMode(0, 1), 0.0), (Bytes{0x04, 0xFC}));
  EXPECT_TRUE(e.executed().empty());
  EXPECT_EQ(e.counts().checksum_errors, 1u);
  EXPECT_EQ(e.counts().invalid_instructions, 2u);
}

TEST(BiclopsEmulator, UpdateStartsATrapezoidalMove) {
  BiclopsEmulator e;
  const double cycle = 153e-6;
  // 3000 counts/s and 6000 counts/s^2 in chip units.
  const auto v = static_cast<std::int32_t>(3000.0 * cycle * 65536.0);
  const auto a = static_cast<std::uint32_t>(6000.0 * cycle * cycle * 65536.0 + 0.5);
  EXPECT_EQ(Send(e, pmd::SetVelocity(0, v), 0.0), (Bytes{0x00, 0x00}));
  EXPECT_EQ(Send(e, pmd::SetAcceleration(0, a), 0.0), (Bytes{0x00, 0x00}));
  EXPECT_EQ(Send(e, pmd::SetPosition(0, 1500), 0.0), (Bytes{0x00, 0x00}));
  // Buffered, not active, until Update.
  EXPECT_EQ(Long(Send(e, pmd::Simple(0, op::kGetPosition), 0.0)), 1500);
  EXPECT_FALSE(e.chip().moving(0));
  EXPECT_EQ(Send(e, pmd::Update(0), 0.0), (Bytes{0x00, 0x00}));
  EXPECT_TRUE(e.chip().moving(0));
  Bytes out;
  e.Advance(0.5, &out);
  const std::uint16_t moving = Word(Send(e, pmd::Simple(0, op::kGetActivityStatus), 0.5));
  EXPECT_NE(moving & pmd::activity::kInMotion, 0);
  EXPECT_EQ(moving & pmd::activity::kAxisSettled, 0);
  const std::int64_t mid = Long(Send(e, pmd::Simple(0, op::kGetActualPosition), 0.5));
  EXPECT_GT(mid, 0);
  EXPECT_LT(mid, 1500);
  // The registers hold 2999.9 counts/s and 5866 counts/s^2 (9 in chip units): 1500 counts is a
  // triangular profile of 2 sqrt(1500 / 5866) = 1.01 s.
  e.Advance(1.05, &out);
  const std::uint16_t done = Word(Send(e, pmd::Simple(0, op::kGetActivityStatus), 1.05));
  EXPECT_EQ(done & pmd::activity::kInMotion, 0);
  EXPECT_NE(done & pmd::activity::kAxisSettled, 0);
  EXPECT_EQ(Long(Send(e, pmd::Simple(0, op::kGetActualPosition), 1.05)), 1500);
  EXPECT_EQ(Long(Send(e, pmd::Simple(0, op::kGetCommandedPosition), 1.05)), 1500);
  const std::vector<PmdExecuted> expect = {{0, 0, op::kSetVelocity, v},
                                           {0, 0, op::kSetAcceleration, a},
                                           {0, 0, op::kSetPosition, 1500},
                                           {0, 0, op::kUpdate, 0}};
  EXPECT_EQ(e.executed(), expect);
}

TEST(BiclopsEmulator, StopsAtTheHardRange) {
  BiclopsEmulator e;
  // Tilt ends at +60 deg = 2000 counts.
  Send(e, pmd::SetVelocity(1, 50000), 0.0);
  Send(e, pmd::SetAcceleration(1, 100), 0.0);
  Send(e, pmd::SetPosition(1, 5000), 0.0);
  Send(e, pmd::Update(1), 0.0);
  Bytes out;
  e.Advance(5.0, &out);
  EXPECT_EQ(Long(Send(e, pmd::Simple(1, op::kGetActualPosition), 5.0)), 2000);
  EXPECT_NE(
      Word(Send(e, pmd::Simple(1, op::kGetActivityStatus), 5.0)) & pmd::activity::kInPositiveLimit,
      0);
}

TEST(BiclopsEmulator, ResetAnswersNothingAndClearsTheRegisters) {
  BiclopsEmulator e;
  Send(e, pmd::SetVelocity(2, 1234), 0.0);
  EXPECT_EQ(Send(e, pmd::Reset(), 0.0), Bytes{});
  EXPECT_EQ(e.chip().resets(), 1);
  EXPECT_EQ(Long(Send(e, pmd::Simple(2, op::kGetVelocity), 0.0)), 0);
  // Reset must name axis 0 (libPMD).
  pmd::Command reset1 = pmd::Reset();
  reset1.axis = 1;
  EXPECT_EQ(Send(e, reset1, 0.0), (Bytes{0x03, 0xFD}));
  ASSERT_EQ(e.executed().size(), 2u);
  EXPECT_EQ(e.executed()[1].opcode, op::kReset);
}

TEST(BiclopsEmulator, AnswersEachPacketOfAStreamInAnySplit) {
  BiclopsEmulator e;
  Bytes stream;
  for (const pmd::Command& c :
       {pmd::SetPosition(2, 300), pmd::Simple(2, op::kGetPosition), pmd::NoOperation()}) {
    const Bytes b = pmd::Encode(c);
    stream.insert(stream.end(), b.begin(), b.end());
  }
  Bytes out;
  for (std::uint8_t b : stream) e.Receive(std::span(&b, 1), 0.0, &out);
  EXPECT_EQ(out, (Bytes{0x00, 0x00, 0x00, 0xD3, 0x00, 0x00, 0x01, 0x2C, 0x00, 0x00}));
}

TEST(BiclopsEmulator, UnknownOpcodesKeepThePacketFraming) {
  // Issue 16: an opcode the emulator did not know was framed as 4 bytes; its argument words
  // began the next packet and the valid commands after it were answered with checksum errors.
  BiclopsEmulator e;
  pmd::Command unknown;
  unknown.opcode = 0x01;  // no Navigator opcode
  unknown.words = {0xABCD, 0x0102, 0x0304};
  unknown.word_count = 3;
  Bytes stream = pmd::Encode(unknown);
  // A Magellan-only instruction with its argument (SetOperatingMode): known length, refused.
  const Bytes magellan = pmd::Encode(pmd::WithWord(0, op::kSetOperatingMode, 7));
  stream.insert(stream.end(), magellan.begin(), magellan.end());
  for (const pmd::Command& c : {pmd::SetPosition(2, 300), pmd::Simple(2, op::kGetPosition)}) {
    const Bytes b = pmd::Encode(c);
    stream.insert(stream.end(), b.begin(), b.end());
  }
  Bytes out;
  for (std::uint8_t b : stream) e.Receive(std::span(&b, 1), 0.0, &out);
  EXPECT_EQ(out, (Bytes{0x02, 0xFE, 0x02, 0xFE, 0x00, 0x00, 0x00, 0xD3, 0x00, 0x00, 0x01, 0x2C}));
  EXPECT_EQ(e.counts().invalid_instructions, 2u);
  EXPECT_EQ(e.counts().checksum_errors, 0u);
}

TEST(BiclopsEmulator, PowersUpWithRelativeEncodersIndexPulsesAndAHomeSensor) {
  BiclopsEmulatorConfig config = PoweredUpBiclopsEmulatorConfig(3);
  BiclopsEmulator e(config);
  for (int a = 0; a < 3; ++a) {
    // The encoder reads 0 where the head powered up, away from home.
    EXPECT_EQ(e.chip().encoder_counts(a), 0);
    EXPECT_EQ(e.chip().position_counts(a), config.start_counts[a]);
    EXPECT_NE(config.start_counts[a], 0.0);
  }
  // The same seed gives the same head; another seed another.
  EXPECT_EQ(PoweredUpBiclopsEmulatorConfig(3).start_counts, config.start_counts);
  EXPECT_NE(PoweredUpBiclopsEmulatorConfig(4).start_counts, config.start_counts);
  // Tilt: drive it with index capture armed across its true home: the capture holds the
  // encoder reading of the index at home, exactly -start.
  const int tilt = 1;
  const auto start = static_cast<std::int32_t>(config.start_counts[tilt]);
  EXPECT_EQ(Send(e, pmd::WithWord(tilt, op::kSetCaptureSource, pmd::kCaptureIndex), 0.0),
            (Bytes{0x00, 0x00}));
  Send(e, pmd::Simple(tilt, op::kGetCaptureValue), 0.0);  // arm
  Send(e, pmd::WithWord(tilt, op::kResetEventStatus, 0), 0.0);
  // Breakpoint 1: smooth stop on the capture-received event bit (libPMD's capture move).
  const std::uint16_t value[] = {0, pmd::event::kCaptureReceived, pmd::event::kCaptureReceived};
  Send(e, pmd::WithWords(tilt, op::kSetBreakpointValue, value), 0.0);
  const std::uint16_t bp[] = {0, static_cast<std::uint16_t>(tilt | pmd::kBreakpointSmoothStop << 4 |
                                                            pmd::kBreakpointEventStatus << 8)};
  Send(e, pmd::WithWords(tilt, op::kSetBreakpoint, bp), 0.0);
  Send(e, pmd::SetVelocity(tilt, 16000), 0.0);  // about 1000 counts/s
  Send(e, pmd::SetAcceleration(tilt, 15), 0.0);
  const std::int32_t target = -start + (start > 0 ? -1500 : 1500);  // beyond home
  Send(e, pmd::SetPosition(tilt, target), 0.0);
  Send(e, pmd::Update(tilt), 0.0);
  Bytes out;
  e.Advance(5.0, &out);
  EXPECT_FALSE(e.chip().moving(tilt));
  const std::uint16_t events = Word(Send(e, pmd::Simple(tilt, op::kGetEventStatus), 5.0));
  EXPECT_NE(events & pmd::event::kCaptureReceived, 0);
  EXPECT_NE(events & pmd::event::kBreakpoint1, 0);
  EXPECT_NE(events & pmd::event::kMotionComplete, 0);
  EXPECT_EQ(Long(Send(e, pmd::Simple(tilt, op::kGetCaptureValue), 5.0)), -start);
  // Smoothly stopped past the index, short of the target.
  const double stopped = e.chip().position_counts(tilt);
  EXPECT_GT(std::abs(stopped - target - start), 100.0);
  // AdjustActualPosition by minus the capture: the encoder now counts from the true home.
  Send(e, pmd::WithLong(tilt, op::kAdjustActualPosition, static_cast<std::uint32_t>(start)), 5.0);
  EXPECT_EQ(e.chip().encoder_counts(tilt), std::llround(stopped));
  // The home sensor: its status bit follows the signal sense (tilt's output is active high).
  Send(e, pmd::SetPosition(tilt, -300), 5.0);
  Send(e, pmd::Update(tilt), 5.0);
  e.Advance(8.0, &out);
  EXPECT_EQ(e.chip().encoder_counts(tilt), -300);
  EXPECT_NE(Word(Send(e, pmd::Simple(tilt, op::kGetSignalStatus), 8.0)) & pmd::signal::kHome, 0);
  Send(e, pmd::WithWord(tilt, op::kSetSignalSense, pmd::signal::kHome), 8.0);
  EXPECT_EQ(Word(Send(e, pmd::Simple(tilt, op::kGetSignalStatus), 8.0)) & pmd::signal::kHome, 0);
}

TEST(BiclopsEmulator, AStopModeIsExecutedByTheNextUpdateOnce) {
  BiclopsEmulator e;
  Send(e, pmd::SetVelocity(0, 50000), 0.0);
  Send(e, pmd::SetAcceleration(0, 15), 0.0);
  Send(e, pmd::SetPosition(0, 5000), 0.0);
  Send(e, pmd::Update(0), 0.0);
  Bytes out;
  e.Advance(0.5, &out);
  EXPECT_TRUE(e.chip().moving(0));
  Send(e, pmd::WithWord(0, op::kSetStopMode, pmd::kAbruptStop), 0.5);
  EXPECT_EQ(Word(Send(e, pmd::Simple(0, op::kGetStopMode), 0.5)), pmd::kAbruptStop);
  Send(e, pmd::Update(0), 0.5);
  EXPECT_EQ(Word(Send(e, pmd::Simple(0, op::kGetStopMode), 0.5)), pmd::kNoStop);
  e.Advance(1.0, &out);
  EXPECT_FALSE(e.chip().moving(0));
  const double stopped = e.chip().position_counts(0);
  EXPECT_LT(stopped, 3000.0);
  // The target is still buffered: the next Update moves on to it.
  Send(e, pmd::Update(0), 1.0);
  e.Advance(4.0, &out);
  EXPECT_EQ(e.chip().position_counts(0), 5000.0);
}

}  // namespace
}  // namespace hgrasp::drivers
