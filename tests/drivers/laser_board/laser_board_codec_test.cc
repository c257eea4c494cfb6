// Codec tests of the laser board protocol: the CRC against the reveng catalogue's check value,
// golden frames (PROTOCOL.md's examples, their CRCs computed independently with Python's
// binascii.crc_hqx(data, 0xFFFF), which is CRC-16/CCITT-FALSE), round trips, strict parsing, and
// a seeded randomized garbage test (the CI-sized fuzzer).

#include "laser_board/laser_board_codec.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <string_view>
#include <vector>

namespace hgrasp::drivers::laser_board {
namespace {

using Bytes = std::vector<std::uint8_t>;

// Decodes `bytes` in one piece; returns the good frames.
std::vector<Frame> DecodeAll(const Bytes& bytes, FrameDecoder* decoder = nullptr) {
  FrameDecoder local;
  FrameDecoder& d = decoder ? *decoder : local;
  std::vector<DecodeEvent> events;
  d.Feed(bytes, &events);
  std::vector<Frame> frames;
  for (auto& e : events) {
    if (e.kind == DecodeEvent::Kind::kFrame) frames.push_back(e.frame);
  }
  return frames;
}

// The reveng CRC catalogue, CRC-16/IBM-3740 (alias CRC-16/CCITT-FALSE, CRC-16/AUTOSAR):
// width=16 poly=0x1021 init=0xffff refin=false refout=false xorout=0x0000 check=0x29b1
// residue=0x0000 (https://reveng.sourceforge.io/crc-catalogue/16.htm#crc.cat.crc-16-ibm-3740).
TEST(LaserBoardCodec, CrcCheckValueFromTheCatalogue) {
  constexpr std::string_view kCheck = "123456789";
  const Bytes check(kCheck.begin(), kCheck.end());
  EXPECT_EQ(Crc16CcittFalse(check), 0x29B1);
  // The catalogue's residue: the message followed by its CRC (MSB first) has CRC 0.
  Bytes with_crc = check;
  with_crc.push_back(0x29);
  with_crc.push_back(0xB1);
  EXPECT_EQ(Crc16CcittFalse(with_crc), 0x0000);
  // A running CRC over pieces equals the CRC of the whole.
  const std::uint16_t part = Crc16CcittFalse(std::span(check).first(4));
  EXPECT_EQ(Crc16CcittFalse(std::span(check).subspan(4), part), 0x29B1);
  EXPECT_EQ(Crc16CcittFalse({}), 0xFFFF);  // init, nothing shifted in
}

struct Golden {
  const char* name;
  Frame frame;
  Bytes bytes;
};

// PROTOCOL.md's examples. The CRC bytes come from Python's binascii.crc_hqx(frame[1:-2], 0xFFFF).
std::vector<Golden> Goldens() {
  return {
      {"SET_LASER on, SEQ 1",
       CommandFrame(1, SetLaser{true}),
       {0xA5, 0x01, 0x01, 0x10, 0x01, 0xD6, 0x16}},
      {"MOTOR_GOTO -1500 at 4500/s, SEQ 42",
       CommandFrame(0x2A, MotorGoTo{-1500, 4500}),
       {0xA5, 0x08, 0x2A, 0x12, 0xFF, 0xFF, 0xFA, 0x24, 0x00, 0x00, 0x11, 0x94, 0x1A, 0x99}},
      {"SET_LEDS right 0x2D, SEQ 7",
       CommandFrame(7, SetLeds{1, 0x2D}),
       {0xA5, 0x05, 0x07, 0x13, 0x01, 0x00, 0x00, 0x00, 0x2D, 0xEB, 0x3E}},
      {"GET_STATUS token 0x5C, unsequenced",
       CommandFrame(0, GetStatus{0x5C}),
       {0xA5, 0x01, 0x00, 0x01, 0x5C, 0x5A, 0x3C}},
      {"MOTOR_VELOCITY -9000/s, SEQ 9",
       CommandFrame(9, MotorVelocity{-9000}),
       {0xA5, 0x04, 0x09, 0x11, 0xFF, 0xFF, 0xDC, 0xD8, 0x48, 0x1E}},
      {"GET_ENCODER, SEQ 16",
       CommandFrame(0x10, GetEncoder{}),
       {0xA5, 0x00, 0x10, 0x20, 0xEB, 0x8D}},
      {"GET_LATCH latest, SEQ 3",
       CommandFrame(3, GetLatch{kLatestFrame}),
       {0xA5, 0x04, 0x03, 0x21, 0xFF, 0xFF, 0xFF, 0xFF, 0xC5, 0xC2}},
      {"ACK SET_LASER, SEQ 1",
       AckFrame(1, Code::kSetLaser),
       {0xA5, 0x01, 0x01, 0x06, 0x10, 0x7D, 0xD3}},
      {"NAK bad CRC, SEQ 1",
       NakFrame(1, 0x10, ErrorCode::kBadCrc),
       {0xA5, 0x02, 0x01, 0x15, 0x10, 0x01, 0x98, 0xFA}},
      {"NAK out of range, SEQ 42",
       NakFrame(0x2A, 0x12, ErrorCode::kOutOfRange),
       {0xA5, 0x02, 0x2A, 0x15, 0x12, 0x04, 0x87, 0x6C}},
      {"ACK GET_LATCH frame 123 count -1500 laser on, SEQ 3",
       AckFrame(3, Code::kGetLatch, EncodeLatch({123, -1500, true})),
       {0xA5, 0x0A, 0x03, 0x06, 0x21, 0x00, 0x00, 0x00, 0x7B, 0xFF, 0xFF, 0xFA, 0x24, 0x01, 0x62,
        0x11}},
      {"ACK GET_ENCODER 123456 ms count 1000 on+moving, SEQ 4",
       AckFrame(4, Code::kGetEncoder, EncodeEncoder({123456, 1000, true, true})),
       {0xA5, 0x0A, 0x04, 0x06, 0x20, 0x00, 0x01, 0xE2, 0x40, 0x00, 0x00, 0x03, 0xE8, 0x03, 0xC9,
        0x56}},
      {"ACK GET_STATUS token 0x5C v1 fw 1.0 last 42 laser on 6+6 LEDs, unsequenced",
       AckFrame(0, Code::kGetStatus, EncodeStatus({0x5C, 1, 1, 0, 0x2A, true, false, 6, 6})),
       {0xA5, 0x09, 0x00, 0x06, 0x01, 0x5C, 0x01, 0x01, 0x00, 0x2A, 0x01, 0x06, 0x06, 0x81, 0x1F}},
  };
}

TEST(LaserBoardCodec, GoldenFramesEncodeAndDecode) {
  for (const Golden& g : Goldens()) {
    SCOPED_TRACE(g.name);
    EXPECT_EQ(EncodeFrame(g.frame), g.bytes);
    const auto frames = DecodeAll(g.bytes);
    ASSERT_EQ(frames.size(), 1u);
    EXPECT_EQ(frames[0], g.frame);
    // The whole frame after the start byte has the catalogue's residue 0.
    EXPECT_EQ(Crc16CcittFalse(std::span(g.bytes).subspan(1)), 0);
  }
}

TEST(LaserBoardCodec, CommandsRoundTrip) {
  const std::vector<Command> commands = {GetStatus{0},
                                         GetStatus{255},
                                         SetLaser{false},
                                         SetLaser{true},
                                         MotorVelocity{0},
                                         MotorVelocity{-9000},
                                         MotorVelocity{INT32_MAX},
                                         MotorGoTo{4500, 1},
                                         MotorGoTo{INT32_MIN, UINT32_MAX},
                                         SetLeds{0, 0},
                                         SetLeds{1, 0x3F},
                                         GetEncoder{},
                                         GetLatch{0},
                                         GetLatch{kLatestFrame}};
  for (std::size_t i = 0; i < commands.size(); ++i) {
    SCOPED_TRACE(i);
    const Frame f = CommandFrame(static_cast<std::uint8_t>(i + 1), commands[i]);
    const auto decoded = DecodeAll(EncodeFrame(f));
    ASSERT_EQ(decoded.size(), 1u);
    ErrorCode error{};
    const auto parsed = ParseCommand(decoded[0], &error);
    ASSERT_TRUE(parsed.has_value());
    EXPECT_EQ(*parsed, commands[i]);
    EXPECT_EQ(CodeOf(*parsed), CodeOf(commands[i]));
  }
  EXPECT_TRUE(ChangesState(SetLaser{}));
  EXPECT_TRUE(ChangesState(MotorVelocity{}));
  EXPECT_TRUE(ChangesState(MotorGoTo{}));
  EXPECT_TRUE(ChangesState(SetLeds{}));
  EXPECT_FALSE(ChangesState(GetStatus{}));
  EXPECT_FALSE(ChangesState(GetEncoder{}));
  EXPECT_FALSE(ChangesState(GetLatch{}));
}

TEST(LaserBoardCodec, RepliesRoundTrip) {
  const BoardStatus status{7, kProtocolVersion, 2, 3, 200, false, true, 6, 4};
  const EncoderReading reading{UINT32_MAX, -4500, false, true};
  const FrameLatch latch{UINT32_MAX - 1, INT32_MIN, true};
  EXPECT_EQ(ParseStatus(EncodeStatus(status)), status);
  EXPECT_EQ(ParseEncoder(EncodeEncoder(reading)), reading);
  EXPECT_EQ(ParseLatch(EncodeLatch(latch)), latch);
  for (const Frame& f :
       {AckFrame(5, Code::kGetStatus, EncodeStatus(status)), AckFrame(6, Code::kMotorGoTo),
        NakFrame(7, 0x99, ErrorCode::kUnknownCommand),
        NakFrame(8, 0x21, ErrorCode::kNoSuchFrame)}) {
    const auto r = ParseReply(f);
    ASSERT_TRUE(r.has_value());
    EXPECT_EQ(r->seq, f.seq);
    EXPECT_EQ(ReplyFrame(*r), f);
  }
}

TEST(LaserBoardCodec, ParsingIsStrict) {
  ErrorCode e{};
  EXPECT_FALSE(ParseCommand(Frame{1, 0x10, {2}}, &e));  // laser flag must be 0 or 1
  EXPECT_EQ(e, ErrorCode::kOutOfRange);
  EXPECT_FALSE(ParseCommand(Frame{1, 0x10, {}}, &e));
  EXPECT_EQ(e, ErrorCode::kBadLength);
  EXPECT_FALSE(ParseCommand(Frame{1, 0x12, {0, 0, 0, 0, 0, 0, 1}}, &e));
  EXPECT_EQ(e, ErrorCode::kBadLength);
  EXPECT_FALSE(ParseCommand(Frame{1, 0x20, {0}}, &e));
  EXPECT_EQ(e, ErrorCode::kBadLength);
  EXPECT_FALSE(ParseCommand(Frame{1, 0x7E, {}}, &e));
  EXPECT_EQ(e, ErrorCode::kUnknownCommand);
  EXPECT_FALSE(ParseCommand(Frame{1, 0x06, {0x10}}, &e));  // a reply is not a command
  EXPECT_EQ(e, ErrorCode::kUnknownCommand);

  EXPECT_FALSE(ParseReply(Frame{1, 0x06, {}}));         // ACK without the echoed command
  EXPECT_FALSE(ParseReply(Frame{1, 0x15, {0x10}}));     // NAK without an error
  EXPECT_FALSE(ParseReply(Frame{1, 0x15, {0x10, 0}}));  // unknown error code
  EXPECT_FALSE(ParseReply(Frame{1, 0x15, {0x10, 8}}));
  EXPECT_FALSE(ParseReply(Frame{1, 0x15, {0x10, 1, 0}}));
  EXPECT_FALSE(ParseReply(Frame{1, 0x10, {1}}));  // a command is not a reply

  EXPECT_FALSE(ParseStatus(Bytes(7, 0)));
  EXPECT_FALSE(ParseStatus(Bytes{0, 1, 0, 0, 0, 0x04, 6, 6}));  // reserved flag bit
  EXPECT_FALSE(ParseEncoder(Bytes(10, 0)));
  EXPECT_FALSE(ParseEncoder(Bytes{0, 0, 0, 0, 0, 0, 0, 0, 0x80}));
  EXPECT_FALSE(ParseLatch(Bytes{0, 0, 0, 0, 0, 0, 0, 0, 0x02}));  // no "moving" in a latch
  EXPECT_FALSE(ParseLatch(Bytes(8, 0)));
}

TEST(LaserBoardCodec, DecoderTakesAnySplit) {
  Bytes stream;
  std::vector<Frame> sent;
  for (const Golden& g : Goldens()) {
    stream.insert(stream.end(), g.bytes.begin(), g.bytes.end());
    sent.push_back(g.frame);
  }
  for (std::size_t chunk = 1; chunk <= stream.size(); ++chunk) {
    SCOPED_TRACE(chunk);
    FrameDecoder d;
    std::vector<DecodeEvent> events;
    for (std::size_t at = 0; at < stream.size(); at += chunk) {
      d.Feed(std::span(stream).subspan(at, std::min(chunk, stream.size() - at)), &events);
    }
    std::vector<Frame> got;
    for (auto& e : events) {
      ASSERT_EQ(e.kind, DecodeEvent::Kind::kFrame);
      got.push_back(e.frame);
    }
    EXPECT_EQ(got, sent);
    EXPECT_FALSE(d.partial());
  }
}

TEST(LaserBoardCodec, DecoderResynchronises) {
  const Bytes good = EncodeFrame(CommandFrame(5, SetLaser{true}));
  // Garbage with false start bytes: one with an impossible LEN (0xFF), one with a plausible LEN
  // whose "frame" swallows the real frame's first bytes and fails its CRC.
  Bytes stream = {0x00, 0xA5, 0xFF, 0x13, 0xA5, 0x03, 0x01};
  stream.insert(stream.end(), good.begin(), good.end());
  FrameDecoder d;
  std::vector<DecodeEvent> events;
  d.Feed(stream, &events);
  std::vector<Frame> frames;
  int bad = 0;
  for (auto& e : events) {
    if (e.kind == DecodeEvent::Kind::kFrame) frames.push_back(e.frame);
    if (e.kind == DecodeEvent::Kind::kBadCrc) ++bad;
  }
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0], CommandFrame(5, SetLaser{true}));
  EXPECT_GE(bad, 1);
  EXPECT_GE(d.stats().bad_lengths, 1u);

  // A false start whose LEN waits for bytes that never come hides a complete frame until the
  // candidate is expired (the receiver's inter-byte timeout).
  FrameDecoder w;
  events.clear();
  Bytes hiding = {0xA5, 0x10};
  hiding.insert(hiding.end(), good.begin(), good.end());
  w.Feed(hiding, &events);
  EXPECT_TRUE(events.empty());
  EXPECT_TRUE(w.partial());
  w.Expire(&events);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, DecodeEvent::Kind::kFrame);
  EXPECT_EQ(events[0].frame, CommandFrame(5, SetLaser{true}));

  // A corrupted byte: the CRC catches it and the next frame still comes through.
  Bytes damaged = good;
  damaged[4] ^= 0x01;
  damaged.insert(damaged.end(), good.begin(), good.end());
  EXPECT_EQ(DecodeAll(damaged).size(), 1u);
}

// The CI-sized version of tests/fuzz/laser_board_fuzz.cc: seeded random garbage with valid
// frames spliced in, fed in random splits. No crash, every spliced frame recovered in order,
// the decoder's buffer bounded.
TEST(LaserBoardCodec, RandomGarbageWithSplicedFrames) {
  std::mt19937 rng(20240607);
  std::uniform_int_distribution<int> byte(0, 255);
  std::size_t recovered = 0, spliced = 0;
  for (int buffer = 0; buffer < 3000; ++buffer) {
    Bytes stream;
    std::vector<Frame> sent;
    const int n = 1 + static_cast<int>(rng() % 4);
    for (int k = 0; k < n; ++k) {
      const int garbage = static_cast<int>(rng() % 40);
      for (int i = 0; i < garbage; ++i) {
        // Plenty of false start bytes.
        stream.push_back(rng() % 5 == 0 ? kStartByte : static_cast<std::uint8_t>(byte(rng)));
      }
      Frame f;
      f.seq = static_cast<std::uint8_t>(byte(rng));
      f.code = static_cast<std::uint8_t>(byte(rng));
      f.payload.resize(rng() % (kMaxPayload + 1));
      for (auto& b : f.payload) b = static_cast<std::uint8_t>(byte(rng));
      AppendFrame(f, &stream);
      sent.push_back(f);
    }
    FrameDecoder d;
    std::vector<DecodeEvent> events;
    std::vector<Frame> got;
    for (std::size_t at = 0; at < stream.size();) {
      const std::size_t len = std::min<std::size_t>(1 + rng() % 30, stream.size() - at);
      d.Feed(std::span(stream).subspan(at, len), &events);
      at += len;
    }
    d.Expire(&events);  // end of stream: whatever is left waiting
    while (d.partial()) d.Expire(&events);
    for (auto& e : events) {
      if (e.kind == DecodeEvent::Kind::kFrame) got.push_back(e.frame);
    }
    // Every spliced frame comes out, in order. Garbage may (rarely, 2^-16 per candidate)
    // pass the CRC and add a frame; none did with this seed.
    std::size_t k = 0;
    for (const Frame& f : got) {
      if (k < sent.size() && f == sent[k]) ++k;
    }
    EXPECT_EQ(k, sent.size()) << "buffer " << buffer;
    recovered += k;
    spliced += sent.size();
  }
  EXPECT_EQ(recovered, spliced);
  std::printf("spliced %zu frames into 3000 garbage buffers, recovered %zu\n", spliced, recovered);
}

}  // namespace
}  // namespace hgrasp::drivers::laser_board
