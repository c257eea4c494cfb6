// The SensorHand Speed codec: golden bytes from the protocol source, our stream layout, round
// trips, and the CI-sized garbage test of both decoders.
//
// Source of the golden bytes (drivers/sensorhand/PROTOCOL.md, "Sources"): the ROS driver node
// hex_serial/hand_node (A. Reiter, JKU Linz ROBIN, January 2014) linked from
// wiki.ros.org/Robots/sensorhand_speed: sendCommand() builds [LEN][payload][CS] with CS the sum
// of all bytes before it, LEN counting the checksum; the expected replies are in its
// cmd->response tables; publish_dump() gives the stream's 9 data bytes and their scales, and
// its reader the frame: dump symbol 0xFF, LEN (data + checksum: 10), data, checksum.

#include "sensorhand/sensorhand_codec.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <vector>

namespace hgrasp::drivers::sensorhand {
namespace {

using Bytes = std::vector<std::uint8_t>;

// --- Golden bytes from the source -------------------------------------------------------------

TEST(SensorHandCodecSource, DumpStartAndStopCommandsAndEchoes) {
  // sendCommand(START_DUMP): cmd_size 2, 0x73; expected response {2, 0x73}.
  EXPECT_EQ(EncodeDumpStart(), (Bytes{0x02, 0x73, 0x75}));
  // sendCommand(STOP_DUMP): cmd_size 2, 0x7a; expected response {2, 0x7a}.
  EXPECT_EQ(EncodeDumpStop(), (Bytes{0x02, 0x7A, 0x7C}));
}

TEST(SensorHandCodecSource, SpeedCommands) {
  // OPEN with param 1.0: 0x31 + 1.0 * (0x85 - 0x31) = 0x85 in the open byte, close byte 0.
  EXPECT_EQ(EncodeSpeed({0x85, 0x00}), (Bytes{0x04, 0x75, 0x85, 0x00, 0xFE}));
  // OPEN with param 0.5: 0x31 + 42 = 0x5B.
  EXPECT_EQ(EncodeSpeed({0x5B, 0x00}), (Bytes{0x04, 0x75, 0x5B, 0x00, 0xD4}));
  // OPEN with param 0: the slowest, 0x31.
  EXPECT_EQ(EncodeSpeed({0x31, 0x00}), (Bytes{0x04, 0x75, 0x31, 0x00, 0xAA}));
  // CLOSE with param 1.0: open byte 0, close byte 0x85.
  EXPECT_EQ(EncodeSpeed({0x00, 0x85}), (Bytes{0x04, 0x75, 0x00, 0x85, 0xFE}));
  // STOP: both 0.
  EXPECT_EQ(EncodeSpeed(kStop), (Bytes{0x04, 0x75, 0x00, 0x00, 0x79}));
}

TEST(SensorHandCodecSource, SpeedEcho) {
  // Expected response to 0x75: {3, open byte, close byte}: the frame [03][open][close][CS].
  EXPECT_EQ(EncodeSpeedEcho({0x85, 0x00}), (Bytes{0x03, 0x85, 0x00, 0x88}));
  EXPECT_EQ(EncodeSpeedEcho({0x00, 0x5B}), (Bytes{0x03, 0x00, 0x5B, 0x5E}));
  EXPECT_EQ(EncodeSpeedEcho(kStop), (Bytes{0x03, 0x00, 0x00, 0x03}));
}

TEST(SensorHandCodecSource, ChecksumCountsTheLengthByte) {
  // "The last symbol ... is the check sum of all previously sent symbols of the current frame
  // (including the length symbol)" (wiki.ros.org/Robots/sensorhand_speed), mod 256.
  const Bytes f = {0x04, 0x75, 0x85, 0x00};
  EXPECT_EQ(Checksum(f), 0xFE);
  const Bytes wrap = {0xFF, 0x02};
  EXPECT_EQ(Checksum(wrap), 0x01);
  const std::uint8_t payload[] = {0x61, 0x02};  // PRGM 2: [03][61][02][66]
  EXPECT_EQ(EncodeFrame(payload), (Bytes{0x03, 0x61, 0x02, 0x66}));
}

TEST(SensorHandCodecSource, StreamScales) {
  // publish_dump(): F = 120/110 * byte, V_bat = 8.4/238 * byte, I = 1.5/141 * byte.
  EXPECT_DOUBLE_EQ(ForceN(110), 120.0);
  EXPECT_DOUBLE_EQ(ForceN(0), 0.0);
  EXPECT_NEAR(BatteryV(238), 8.4, 1e-12);
  EXPECT_NEAR(BatteryV(140), 4.94, 0.01);  // the source's comment: "140 -> 4.9 V"
  EXPECT_NEAR(CurrentA(141), 1.5, 1e-12);
  EXPECT_EQ(ForceRaw(120.0), 110);
  EXPECT_EQ(BatteryRaw(8.4), 238);
  EXPECT_EQ(CurrentRaw(1.5), 141);
}

TEST(SensorHandCodecSource, StreamFrameMarkerIsOutsideTheChecksum) {
  // The source's reader: 0xFF is the "dump symbol"; the checksum starts at the LEN byte that
  // follows it. Same rule in ours: the last byte is LEN + data, without the marker.
  DumpSample d;
  d.f_bracket = 0x10;
  const Bytes f = EncodeDump(d);
  ASSERT_EQ(f.size(), kDumpFrameBytes);
  EXPECT_EQ(f[0], kDumpMarker);
  EXPECT_EQ(f[1], kDumpLen);
  EXPECT_EQ(f.back(), static_cast<std::uint8_t>(kDumpLen + 0x10));
}

TEST(SensorHandCodecSource, StockStreamFrameGolden) {
  // The frame a stock hand sends: publish_dump() reads data[0..8] (V_open, V_close, V_bat,
  // state, F_bracket, F_pad1..3, I), so LEN = 9 + 1 = 0x0A; 12 bytes with marker and checksum.
  DumpSample d;
  d.v_open = 0;
  d.v_close = 0;
  d.v_bat = 210;  // 7.4 V
  d.state = static_cast<std::uint8_t>(MotionState::kClosing);
  d.f_bracket = 37;  // 40.4 N
  d.f_pad = {12, 12, 12};
  d.current = 46;
  // CS = 0x0A + 0xD2 + 0x02 + 0x25 + 3 * 0x0C + 0x2E = 0x155 -> 0x55.
  const Bytes golden = {0xFF, 0x0A, 0x00, 0x00, 0xD2, 0x02, 0x25, 0x0C, 0x0C, 0x0C, 0x2E, 0x55};
  EXPECT_EQ(kDumpLen, 0x0A);
  EXPECT_EQ(kDumpFrameBytes, 12u);
  EXPECT_EQ(EncodeDump(d), golden);
  ReplyDecoder dec;
  std::vector<Reply> got;
  dec.Push(golden, &got);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].kind, Reply::Kind::kDump);
  EXPECT_EQ(got[0].dump, d);
  EXPECT_NEAR(ForceN(got[0].dump.f_bracket), 40.36, 0.01);
  EXPECT_EQ(dec.discarded(), 0u);
}

TEST(SensorHandCodecSource, StreamFrameBytesMayTakeAnyValue) {
  // The source publishes the state byte "no conversion" and gives no values: a stock hand's
  // frame with a state we do not know is still a frame (the driver ignores the state then).
  DumpSample d;
  d.state = 0xC7;
  d.v_open = 0x55;
  d.current = 0xFF;
  ReplyDecoder dec;
  std::vector<Reply> got;
  dec.Push(EncodeDump(d), &got);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dump, d);
}

// --- Our scales -------------------------------------------------------------------------------

TEST(SensorHandCodecOurs, SpeedScale) {
  EXPECT_EQ(SpeedFraction(0), 0.0);
  EXPECT_NEAR(SpeedFraction(kSpeedMin), 1.0 / 85.0, 1e-12);
  EXPECT_EQ(SpeedFraction(kSpeedMax), 1.0);
  EXPECT_EQ(SpeedByteAtMost(0.0), 0);
  EXPECT_EQ(SpeedByteAtMost(1.0), kSpeedMax);
  EXPECT_EQ(SpeedByteAtMost(5.0), kSpeedMax);
  EXPECT_EQ(SpeedByteAtMost(0.001), kSpeedMin);  // raised to the smallest step
  EXPECT_EQ(SpeedByteAtMost(0.4), 0x30 + 34);
  for (int b = kSpeedMin; b <= kSpeedMax; ++b) {
    EXPECT_EQ(SpeedByteAtMost(SpeedFraction(static_cast<std::uint8_t>(b))), b);
    EXPECT_LE(SpeedFraction(SpeedByteAtMost(b / 85.0 - 0.3 / 85.0)), b / 85.0);
  }
}

TEST(SensorHandCodecOurs, Validity) {
  EXPECT_TRUE(IsValid({0, 0}));
  EXPECT_TRUE(IsValid({0x85, 0}));
  EXPECT_TRUE(IsValid({0, 0x31}));
  EXPECT_FALSE(IsValid({0x31, 0x31}));  // both ways at once
  EXPECT_FALSE(IsValid({0x30, 0}));
  EXPECT_FALSE(IsValid({0, 0x86}));
}

// --- Decoders ---------------------------------------------------------------------------------

std::vector<Command> DecodeCommands(const Bytes& b) {
  CommandDecoder dec;
  std::vector<Command> out;
  dec.Push(b, &out);
  return out;
}

std::vector<Reply> DecodeReplies(const Bytes& b) {
  ReplyDecoder dec;
  std::vector<Reply> out;
  dec.Push(b, &out);
  return out;
}

TEST(SensorHandCodecDecoder, CommandsRoundTrip) {
  const std::vector<Command> cmds = {
      {Command::Kind::kDumpStart, {}},    {Command::Kind::kSpeed, {0x85, 0}},
      {Command::Kind::kSpeed, {0, 0x52}}, {Command::Kind::kSpeed, kStop},
      {Command::Kind::kDumpStop, {}},
  };
  Bytes all;
  for (const Command& c : cmds) {
    const Bytes b = Encode(c);
    all.insert(all.end(), b.begin(), b.end());
  }
  EXPECT_EQ(DecodeCommands(all), cmds);
  // Byte by byte gives the same.
  CommandDecoder dec;
  std::vector<Command> out;
  for (std::uint8_t b : all) dec.Push(std::span<const std::uint8_t>(&b, 1), &out);
  EXPECT_EQ(out, cmds);
  EXPECT_EQ(dec.discarded(), 0u);
  EXPECT_EQ(dec.buffered(), 0u);
}

TEST(SensorHandCodecDecoder, RepliesRoundTrip) {
  DumpSample d;
  d.v_bat = 210;
  d.f_bracket = 110;
  d.f_pad = {36, 37, 38};
  d.current = 141;
  d.state = 1;
  std::vector<Reply> replies = {
      {Reply::Kind::kDumpStartEcho, {}, {}},
      {Reply::Kind::kSpeedEcho, {0x85, 0}, {}},
      {Reply::Kind::kDump, {}, d},
      {Reply::Kind::kDumpStopEcho, {}, {}},
  };
  Bytes all;
  for (const Reply& r : replies) {
    const Bytes b = Encode(r);
    all.insert(all.end(), b.begin(), b.end());
  }
  EXPECT_EQ(DecodeReplies(all), replies);
}

TEST(SensorHandCodecDecoder, RejectsDamagedAndUnknownFrames) {
  Bytes bad_cs = EncodeSpeed({0x85, 0});
  bad_cs.back() ^= 1;
  EXPECT_TRUE(DecodeCommands(bad_cs).empty());
  // Both speeds at once: checksum right, refused.
  const std::uint8_t both[] = {kOpSpeed, 0x40, 0x40};
  EXPECT_TRUE(DecodeCommands(EncodeFrame(both)).empty());
  // A speed byte between 1 and 0x30: refused.
  const std::uint8_t slow[] = {kOpSpeed, 0x10, 0x00};
  EXPECT_TRUE(DecodeCommands(EncodeFrame(slow)).empty());
  // Commands we do not use (serial number 0x76, reset 0x6D): dropped as garbage.
  const std::uint8_t sn[] = {0x76};
  EXPECT_TRUE(DecodeCommands(EncodeFrame(sn)).empty());
  // A stream frame of the stock length (LEN 10: 9 data bytes) decodes...
  Bytes stock = {0xFF, 0x0A, 0, 0, 200, 0, 10, 0, 0, 0, 20};
  stock.push_back(Checksum(std::span<const std::uint8_t>(stock).subspan(1)));
  ASSERT_EQ(DecodeReplies(stock).size(), 1u);
  EXPECT_EQ(DecodeReplies(stock)[0].dump.f_bracket, 10);
  // ... with a damaged byte it does not; nor with another LEN (the 17-byte frame this driver
  // once had, LEN 0x11, which no stock hand sends).
  Bytes damaged = stock;
  damaged[6] ^= 0x10;
  EXPECT_TRUE(DecodeReplies(damaged).empty());
  Bytes longer = {0xFF, 0x11, 0, 0, 200, 0, 10, 0, 0, 0, 20, 0x1F, 0x40, 0, 0, 1, 0, 7};
  longer.push_back(Checksum(std::span<const std::uint8_t>(longer).subspan(1)));
  EXPECT_TRUE(DecodeReplies(longer).empty());
}

TEST(SensorHandCodecDecoder, ResynchronisesAfterAFrameCutShort) {
  const Bytes a = EncodeSpeed({0, 0x85});
  const Bytes b = EncodeSpeed({0x85, 0});
  Bytes stream(a.begin(), a.begin() + 3);  // [04][75][00] ... lost
  stream.insert(stream.end(), b.begin(), b.end());
  const auto got = DecodeCommands(stream);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].speed, (SpeedSetting{0x85, 0}));
}

// The CI-sized version of tests/fuzz/sensorhand_fuzz.cc: random buffers with valid frames
// spliced in, fed in random splits.
template <class Decoder, class Item>
void GarbageTest(std::uint64_t seed, const std::vector<std::uint8_t>& starts,
                 Item (*random_item)(std::mt19937_64&), bool only_safe_garbage, int* recovered,
                 int* spliced, int* false_frames) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> byte(0, 255), len(0, 40), frames(1, 6), split(1, 23);
  for (int buffer = 0; buffer < 2000; ++buffer) {
    Bytes bytes;
    std::vector<Item> want;
    const int n = frames(rng);
    for (int i = 0; i < n; ++i) {
      const int g = len(rng);
      for (int k = 0; k < g; ++k) {
        std::uint8_t b = static_cast<std::uint8_t>(byte(rng));
        if (only_safe_garbage) {
          // Garbage that cannot begin a frame.
          while (std::find(starts.begin(), starts.end(), b) != starts.end()) {
            b = static_cast<std::uint8_t>(byte(rng));
          }
        }
        bytes.push_back(b);
      }
      const Item item = random_item(rng);
      want.push_back(item);
      const Bytes f = Encode(item);
      bytes.insert(bytes.end(), f.begin(), f.end());
    }
    Decoder dec;
    std::vector<Item> got;
    for (std::size_t at = 0; at < bytes.size();) {
      const std::size_t k = std::min<std::size_t>(split(rng), bytes.size() - at);
      dec.Push(std::span<const std::uint8_t>(bytes.data() + at, k), &got);
      at += k;
    }
    // Every decoded frame is a whole frame of the input...
    for (const Item& item : got) {
      const Bytes f = Encode(item);
      ASSERT_NE(std::search(bytes.begin(), bytes.end(), f.begin(), f.end()), bytes.end());
    }
    // ... and the spliced frames come out in order.
    std::size_t j = 0;
    for (const Item& item : got) {
      if (j < want.size() && item == want[j]) {
        ++j;
      } else {
        ++*false_frames;
      }
    }
    *recovered += static_cast<int>(j);
    *spliced += static_cast<int>(want.size());
  }
}

Command RandomCommand(std::mt19937_64& rng) {
  std::uniform_int_distribution<int> kind(0, 5), speed(kSpeedMin, kSpeedMax);
  switch (kind(rng)) {
    case 0:
      return {Command::Kind::kDumpStart, {}};
    case 1:
      return {Command::Kind::kDumpStop, {}};
    case 2:
      return {Command::Kind::kSpeed, kStop};
    case 3:
      return {Command::Kind::kSpeed, {static_cast<std::uint8_t>(speed(rng)), 0}};
    default:
      return {Command::Kind::kSpeed, {0, static_cast<std::uint8_t>(speed(rng))}};
  }
}

Reply RandomReply(std::mt19937_64& rng) {
  std::uniform_int_distribution<int> kind(0, 5), speed(kSpeedMin, kSpeedMax), byte(0, 255);
  Reply r;
  switch (kind(rng)) {
    case 0:
      r.kind = Reply::Kind::kDumpStartEcho;
      return r;
    case 1:
      r.kind = Reply::Kind::kDumpStopEcho;
      return r;
    case 2:
      r.kind = Reply::Kind::kSpeedEcho;
      r.speed = {0, static_cast<std::uint8_t>(speed(rng))};
      return r;
    default: {
      r.kind = Reply::Kind::kDump;
      DumpSample& d = r.dump;
      d.v_bat = static_cast<std::uint8_t>(byte(rng));
      d.state = static_cast<std::uint8_t>(byte(rng) % 4);
      d.f_bracket = static_cast<std::uint8_t>(byte(rng));
      d.f_pad = {static_cast<std::uint8_t>(byte(rng)), 0, 3};
      d.current = static_cast<std::uint8_t>(byte(rng));
      return r;
    }
  }
}

TEST(SensorHandCodecDecoder, RandomGarbageWithFramesSplicedIn) {
  for (bool safe : {true, false}) {
    int recovered = 0, spliced = 0, false_frames = 0;
    GarbageTest<CommandDecoder, Command>(safe ? 11 : 12, {0x02, 0x04}, RandomCommand, safe,
                                         &recovered, &spliced, &false_frames);
    const int c_rec = recovered, c_spl = spliced, c_false = false_frames;
    recovered = spliced = false_frames = 0;
    GarbageTest<ReplyDecoder, Reply>(safe ? 13 : 14, {0x02, 0x03, 0xFF}, RandomReply, safe,
                                     &recovered, &spliced, &false_frames);
    std::printf(
        "garbage %s: commands %d/%d recovered, %d false frames; replies %d/%d recovered, "
        "%d false frames\n",
        safe ? "that cannot start a frame" : "of any value", c_rec, c_spl, c_false, recovered,
        spliced, false_frames);
    if (safe) {
      EXPECT_EQ(c_rec, c_spl);
      EXPECT_EQ(recovered, spliced);
      EXPECT_EQ(c_false, 0);
      EXPECT_EQ(false_frames, 0);
    } else {
      // An 8-bit sum lets about 1 in 256 random starts pass as a short frame, which may then
      // swallow the first bytes of a real one (PROTOCOL.md, "Resynchronisation").
      EXPECT_GE(c_rec, c_spl * 98 / 100);
      EXPECT_GE(recovered, spliced * 98 / 100);
    }
  }
}

}  // namespace
}  // namespace hgrasp::drivers::sensorhand
