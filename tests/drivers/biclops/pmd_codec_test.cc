// The PMD serial codec: golden packets built by hand from TRACLabs libPMD's layout
// (PMDSerial::BuildCommandBuffer: address, checksum, axis, opcode, words high byte first; the
// checksum is the negated sum of the other bytes) and its opcode table (PMDOPCodes.h), replies
// from C-Motion's PMDSerial_Send (status, checksum, words; an error status alone), round trips,
// and the decoders on damaged streams.

#include "biclops/pmd_codec.h"

#include <gtest/gtest.h>

#include <random>

namespace hgrasp::drivers::pmd {
namespace {

using Bytes = std::vector<std::uint8_t>;

TEST(BiclopsPmdCodec, GoldenCommands) {
  // NoOperation (0x00), axis 0: every byte 0.
  EXPECT_EQ(Encode(NoOperation()), (Bytes{0x00, 0x00, 0x00, 0x00}));
  // SetPosition (0x10), axis 1, 1000 counts = 0x000003E8 -> words 0x0000, 0x03E8 (high word
  // first). Sum without checksum: 01 + 10 + 03 + E8 = 0xFC; checksum 0x04.
  EXPECT_EQ(Encode(SetPosition(1, 1000)), (Bytes{0x00, 0x04, 0x01, 0x10, 0x00, 0x00, 0x03, 0xE8}));
  // SetPosition axis 0, -1000 = 0xFFFFFC18: 10 + FF + FF + FC + 18 = 0x322 -> 0x22; cs 0xDE.
  EXPECT_EQ(Encode(SetPosition(0, -1000)), (Bytes{0x00, 0xDE, 0x00, 0x10, 0xFF, 0xFF, 0xFC, 0x18}));
  // SetVelocity (0x11) axis 0, 50135 = 0x0000C3D7: 11 + C3 + D7 = 0x1AB -> cs 0x55.
  EXPECT_EQ(Encode(SetVelocity(0, 50135)), (Bytes{0x00, 0x55, 0x00, 0x11, 0x00, 0x00, 0xC3, 0xD7}));
  // SetAcceleration (0x90) axis 0, 15: 90 + 0F = 0x9F -> cs 0x61.
  EXPECT_EQ(Encode(SetAcceleration(0, 15)),
            (Bytes{0x00, 0x61, 0x00, 0x90, 0x00, 0x00, 0x00, 0x0F}));
  // SetProfileMode (0xA0) axis 1, trapezoidal (0), one word: 01 + A0 = 0xA1 -> cs 0x5F.
  EXPECT_EQ(Encode(SetProfileMode(1, kTrapezoidalProfile)),
            (Bytes{0x00, 0x5F, 0x01, 0xA0, 0x00, 0x00}));
  // Update (0x1A) axis 2: 02 + 1A = 0x1C -> cs 0xE4.
  EXPECT_EQ(Encode(Update(2)), (Bytes{0x00, 0xE4, 0x02, 0x1A}));
  // GetActualPosition (0x37) axis 0 -> cs 0xC9; GetActivityStatus (0xA6) axis 2 -> cs 0x58.
  EXPECT_EQ(Encode(Simple(0, op::kGetActualPosition)), (Bytes{0x00, 0xC9, 0x00, 0x37}));
  EXPECT_EQ(Encode(Simple(2, op::kGetActivityStatus)), (Bytes{0x00, 0x58, 0x02, 0xA6}));
  // Reset (0x39), axis 0 (libPMD PMD::Reset forces axis 0) -> cs 0xC7.
  EXPECT_EQ(Encode(Reset()), (Bytes{0x00, 0xC7, 0x00, 0x39}));
  // GetVersion (0x8F) -> cs 0x71; GetPosition (0x4A) axis 1 -> cs 0xB5.
  EXPECT_EQ(Encode(Simple(0, op::kGetVersion)), (Bytes{0x00, 0x71, 0x00, 0x8F}));
  EXPECT_EQ(Encode(Simple(1, op::kGetPosition)), (Bytes{0x00, 0xB5, 0x01, 0x4A}));
}

TEST(BiclopsPmdCodec, GoldenReplies) {
  Reply ok;
  EXPECT_EQ(Encode(ok), (Bytes{0x00, 0x00}));
  Reply bad;
  bad.status = status::kBadSerialChecksum;
  bad.words = {0x1234, 0x5678};  // an error reply carries no words
  bad.word_count = 2;
  EXPECT_EQ(Encode(bad), (Bytes{0x09, 0xF7}));
  // GetActualPosition -> 1000: 03 + E8 = 0xEB -> cs 0x15.
  Reply pos;
  pos.words = SplitLong(1000);
  pos.word_count = 2;
  EXPECT_EQ(Encode(pos), (Bytes{0x00, 0x15, 0x00, 0x00, 0x03, 0xE8}));
  // GetVersion -> 0x2130 (Navigator, brushed, 3 axes), 0x0015: 21 + 30 + 15 = 0x66 -> 0x9A.
  Reply version;
  version.words = {0x2130, 0x0015};
  version.word_count = 2;
  EXPECT_EQ(Encode(version), (Bytes{0x00, 0x9A, 0x21, 0x30, 0x00, 0x15}));
  // GetActivityStatus -> 0x0500 (in motion, motor on): cs 0xFB.
  Reply activity;
  activity.words[0] = activity::kInMotion | activity::kMotorOn;
  activity.word_count = 1;
  EXPECT_EQ(Encode(activity), (Bytes{0x00, 0xFB, 0x05, 0x00}));
}

TEST(BiclopsPmdCodec, OpcodeTableMatchesLibPmd) {
  // Values from PMDOPCodes.h; word counts from PMD.cpp's SendCommand* variants.
  struct Row {
    std::uint8_t opcode;
    int args, results;
    bool changes;
  };
  const Row rows[] = {
      {0x00, 0, 0, false}, {0x10, 2, 0, true},  {0x11, 2, 0, true},  {0x1A, 0, 0, true},
      {0x1D, 0, 2, false}, {0x37, 0, 2, false}, {0x39, 0, 0, true},  {0x4A, 0, 2, false},
      {0x4B, 0, 2, false}, {0x4C, 0, 2, false}, {0x61, 0, 1, false}, {0x8F, 0, 2, false},
      {0x90, 2, 0, true},  {0xA0, 1, 0, true},  {0xA1, 0, 1, false}, {0xA6, 0, 1, false}};
  for (const Row& r : rows) {
    const OpcodeInfo* info = FindOpcode(r.opcode);
    ASSERT_NE(info, nullptr) << int(r.opcode);
    EXPECT_EQ(info->argument_words, r.args) << info->name;
    EXPECT_EQ(info->result_words, r.results) << info->name;
    EXPECT_EQ(info->changes_state, r.changes) << info->name;
    EXPECT_EQ(info->replies, r.opcode != op::kReset) << info->name;
  }
  EXPECT_EQ(FindOpcode(0x01), nullptr);
  EXPECT_EQ(FindOpcode(0xFF), nullptr);
  // What libBiclops sends during configuration, homing and moves (libPMD PMD.cpp's transport
  // calls): words out and back.
  const Row vendor[] = {
      {0x31, 0, 1, false}, {0x34, 1, 0, true},  {0x36, 0, 2, true}, {0x4D, 2, 0, true},
      {0x5B, 1, 0, true},  {0x80, 1, 0, true},  {0x82, 2, 0, true}, {0x83, 1, 1, false},
      {0x87, 1, 0, true},  {0x95, 2, 0, true},  {0x97, 2, 0, true}, {0xA2, 1, 0, true},
      {0xA3, 0, 1, false}, {0xA4, 0, 1, false}, {0xC0, 3, 0, true}, {0xC8, 3, 0, true},
      {0xC9, 1, 2, true},  {0xD2, 1, 0, true},  {0xD4, 2, 0, true}, {0xD6, 3, 0, true},
      {0xD8, 1, 0, true},  {0xD9, 0, 1, false}, {0xDC, 1, 0, true}, {0xDD, 0, 1, false},
      {0xE0, 1, 0, true},  {0xED, 1, 0, true},  {0xF5, 2, 0, true}, {0x25, 1, 0, true},
      {0x9E, 1, 0, true},  {0x49, 0, 2, false}};
  for (const Row& r : vendor) {
    const OpcodeInfo* info = FindOpcode(r.opcode);
    ASSERT_NE(info, nullptr) << int(r.opcode);
    EXPECT_EQ(info->argument_words, r.args) << info->name;
    EXPECT_EQ(info->result_words, r.results) << info->name;
    EXPECT_EQ(info->changes_state, r.changes) << info->name;
  }
  // The table is in opcode order, without repeats, within the packet limits.
  const std::span<const OpcodeInfo> all = AllOpcodes();
  EXPECT_GT(all.size(), 150u);
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (i > 0) {
      EXPECT_LT(all[i - 1].opcode, all[i].opcode);
    }
    EXPECT_LE(all[i].argument_words, static_cast<int>(kMaxArgumentWords)) << all[i].name;
    EXPECT_LE(all[i].result_words, 2) << all[i].name;
  }
  EXPECT_TRUE(StatusNeedsResync(status::kBadSerialChecksum));
  EXPECT_TRUE(StatusNeedsResync(status::kInvalidInstruction));
  EXPECT_TRUE(StatusNeedsResync(status::kInvalidAxis));
  EXPECT_FALSE(StatusNeedsResync(status::kInvalidNegativeValue));
}

TEST(BiclopsPmdCodec, LongsAndValues) {
  EXPECT_EQ(SplitLong(0x12345678u), (std::array<std::uint16_t, 2>{0x1234, 0x5678}));
  EXPECT_EQ(JoinLong(0xFFFF, 0xFC18), 0xFFFFFC18u);
  EXPECT_EQ(CommandValue(SetPosition(0, -1000)), -1000);
  EXPECT_EQ(CommandValue(SetVelocity(0, -5)), -5);
  EXPECT_EQ(CommandValue(SetAcceleration(0, 0xFFFFFFFFu)), 0xFFFFFFFFll);
  EXPECT_EQ(CommandValue(SetProfileMode(0, 2)), 2);
  EXPECT_EQ(CommandValue(Update(1)), 0);
  Reply r;
  r.words = SplitLong(static_cast<std::uint32_t>(-123456));
  r.word_count = 2;
  EXPECT_EQ(ReplyLong(r), -123456);
}

Command RandomCommand(std::mt19937& rng) {
  static const std::uint8_t kOps[] = {op::kNoOperation,
                                      op::kSetPosition,
                                      op::kSetVelocity,
                                      op::kUpdate,
                                      op::kGetCommandedPosition,
                                      op::kGetActualPosition,
                                      op::kReset,
                                      op::kGetPosition,
                                      op::kGetVelocity,
                                      op::kGetAcceleration,
                                      op::kGetSampleTime,
                                      op::kGetVersion,
                                      op::kSetAcceleration,
                                      op::kSetProfileMode,
                                      op::kGetProfileMode,
                                      op::kGetActivityStatus};
  std::uniform_int_distribution<int> pick(0, std::size(kOps) - 1), axis(0, 2), word(0, 0xFFFF);
  Command c;
  c.opcode = kOps[pick(rng)];
  c.axis = static_cast<std::uint8_t>(axis(rng));
  c.word_count = FindOpcode(c.opcode)->argument_words;
  for (int i = 0; i < c.word_count; ++i) c.words[i] = static_cast<std::uint16_t>(word(rng));
  return c;
}

TEST(BiclopsPmdCodec, CommandRoundTripInAnySplit) {
  std::mt19937 rng(11);
  CommandDecoder decoder;
  for (int i = 0; i < 2000; ++i) {
    const Command c = RandomCommand(rng);
    const Bytes bytes = Encode(c);
    ASSERT_TRUE(SumIsZero(bytes));
    std::vector<CommandDecoder::Packet> packets;
    std::size_t at = 0;
    while (at < bytes.size()) {
      const std::size_t n = std::uniform_int_distribution<std::size_t>(1, bytes.size() - at)(rng);
      decoder.Feed(std::span(bytes).subspan(at, n), &packets);
      at += n;
      if (at < bytes.size()) {
        ASSERT_TRUE(packets.empty());
      }
    }
    ASSERT_EQ(packets.size(), 1u);
    EXPECT_TRUE(packets[0].checksum_ok);
    EXPECT_TRUE(packets[0].known_opcode);
    EXPECT_EQ(packets[0].command, c);
    EXPECT_EQ(Bytes(packets[0].raw.begin(), packets[0].raw.begin() + packets[0].size), bytes);
  }
}

TEST(BiclopsPmdCodec, ReplyRoundTrip) {
  std::mt19937 rng(12);
  ReplyDecoder decoder;
  for (int i = 0; i < 2000; ++i) {
    Reply r;
    r.word_count = static_cast<int>(rng() % 3);
    for (int w = 0; w < r.word_count; ++w) r.words[w] = static_cast<std::uint16_t>(rng());
    const Bytes bytes = Encode(r);
    decoder.Expect(r.word_count);
    for (std::size_t k = 0; k + 1 < bytes.size(); ++k) {
      ASSERT_EQ(decoder.Push(bytes[k]), ReplyDecoder::Result::kNeedMore);
    }
    ASSERT_EQ(decoder.Push(bytes.back()), ReplyDecoder::Result::kReply);
    EXPECT_EQ(decoder.reply(), r);
    EXPECT_EQ(Bytes(decoder.raw().begin(), decoder.raw().end()), bytes);
    EXPECT_EQ(decoder.Push(0), ReplyDecoder::Result::kGarbled);  // surplus
  }
  // An error status ends the reply after two bytes whatever was expected.
  decoder.Expect(2);
  EXPECT_EQ(decoder.Push(0x09), ReplyDecoder::Result::kNeedMore);
  EXPECT_EQ(decoder.Push(0xF7), ReplyDecoder::Result::kReply);
  EXPECT_EQ(decoder.reply().status, status::kBadSerialChecksum);
  EXPECT_EQ(decoder.reply().word_count, 0);
}

TEST(BiclopsPmdCodec, ReplyDecoderFlagsEveryCorruptedByte) {
  // One damaged byte always spoils the sum: never taken for a good reply.
  std::mt19937 rng(13);
  ReplyDecoder decoder;
  for (int i = 0; i < 3000; ++i) {
    Reply r;
    r.word_count = static_cast<int>(rng() % 3);
    for (int w = 0; w < r.word_count; ++w) r.words[w] = static_cast<std::uint16_t>(rng());
    Bytes bytes = Encode(r);
    const std::size_t k = rng() % bytes.size();
    bytes[k] = static_cast<std::uint8_t>(bytes[k] ^ (1 + rng() % 255));
    decoder.Expect(r.word_count);
    ReplyDecoder::Result result = ReplyDecoder::Result::kNeedMore;
    for (std::uint8_t b : bytes) {
      result = decoder.Push(b);
      if (result != ReplyDecoder::Result::kNeedMore) break;
    }
    if (result == ReplyDecoder::Result::kReply) {
      // Only as an error status whose two bytes happen to sum to 0: never as status 0.
      EXPECT_NE(decoder.reply().status, status::kOk);
      EXPECT_EQ(decoder.reply().word_count, 0);
    }
  }
}

TEST(BiclopsPmdCodec, UnknownOpcodesAreFramedByTheirChecksum) {
  // Issue 16: an opcode the decoder did not know was framed as its 4 header bytes, so its
  // argument words started the next packet, and the valid commands after it were answered with
  // checksum errors. Now a byte that is no opcode ends its packet at the first whole word with
  // a zero sum, whatever it carries, and the next packet decodes exactly.
  CommandDecoder decoder;
  for (int words = 0; words <= static_cast<int>(kMaxArgumentWords); ++words) {
    SCOPED_TRACE(words);
    Command unknown;
    unknown.opcode = 0x01;  // no opcode of PMDOPCodes.h
    unknown.axis = 1;
    unknown.word_count = words;
    for (int i = 0; i < words; ++i)
      unknown.words[i] = static_cast<std::uint16_t>(0x1234 + 0x1111 * i);
    Bytes stream = Encode(unknown);
    for (const Command& c : {SetPosition(0, 1000), Simple(2, op::kGetActualPosition)}) {
      const Bytes b = Encode(c);
      stream.insert(stream.end(), b.begin(), b.end());
    }
    std::vector<CommandDecoder::Packet> packets;
    decoder.Feed(stream, &packets);
    ASSERT_EQ(packets.size(), 3u);
    EXPECT_FALSE(packets[0].known_opcode);
    EXPECT_TRUE(packets[0].checksum_ok);
    EXPECT_EQ(packets[0].size, 4u + 2u * static_cast<std::size_t>(words));
    EXPECT_EQ(packets[1].command, SetPosition(0, 1000));
    EXPECT_TRUE(packets[1].checksum_ok);
    EXPECT_EQ(packets[2].command, Simple(2, op::kGetActualPosition));
    EXPECT_EQ(decoder.pending(), 0u);
  }
  // A known opcode with arguments: its length comes from the table (SetBreakpointValue: 3).
  const std::uint16_t w[] = {0, 8, 8};
  const Bytes bp = Encode(WithWords(0, op::kSetBreakpointValue, w));
  EXPECT_EQ(bp.size(), 10u);
  std::vector<CommandDecoder::Packet> packets;
  decoder.Feed(bp, &packets);
  ASSERT_EQ(packets.size(), 1u);
  EXPECT_TRUE(packets[0].known_opcode);
  EXPECT_EQ(CommandValue(packets[0].command), 0x00080008);
}

TEST(BiclopsPmdCodec, ZerosResynchroniseTheChipFromAnyPartialPacket) {
  // Whatever partial packet the chip holds, at most one longest packet's length of single 0x00
  // bytes completes it; after the first answer the next packet decodes exactly.
  std::mt19937 rng(14);
  for (int i = 0; i < 5000; ++i) {
    CommandDecoder decoder;
    CommandDecoder::Packet p;
    const int garbage = static_cast<int>(rng() % 40);
    for (int k = 0; k < garbage; ++k) decoder.Push(static_cast<std::uint8_t>(rng()), &p);
    int zeros = 0;
    while (!decoder.Push(0x00, &p)) ++zeros;
    ASSERT_LE(zeros + 1, static_cast<int>(kMaxCommandBytes));
    EXPECT_EQ(decoder.pending(), 0u);
    const Command c = RandomCommand(rng);
    const Bytes bytes = Encode(c);
    std::vector<CommandDecoder::Packet> packets;
    decoder.Feed(bytes, &packets);
    ASSERT_EQ(packets.size(), 1u);
    EXPECT_EQ(packets[0].command, c);
    EXPECT_TRUE(packets[0].checksum_ok);
  }
}

TEST(BiclopsPmdCodec, RandomGarbageWithFramesSplicedIn) {
  // The CI-sized fuzzer: random buffers, each followed by the host's resynchronisation (0x00
  // bytes until a packet completes) and a valid frame, fed in random splits; every frame is
  // recovered and every decoded packet re-encodes to the bytes it came from.
  std::mt19937 rng(15);
  CommandDecoder decoder;
  int recovered = 0, frames = 0;
  for (int i = 0; i < 4000; ++i) {
    Bytes stream(rng() % 64);
    for (std::uint8_t& b : stream) b = static_cast<std::uint8_t>(rng());
    std::vector<CommandDecoder::Packet> packets;
    std::size_t at = 0;
    while (at < stream.size()) {
      const std::size_t n = 1 + rng() % (stream.size() - at);
      decoder.Feed(std::span(stream).subspan(at, n), &packets);
      at += n;
    }
    CommandDecoder::Packet p;
    while (!decoder.Push(0x00, &p)) {
    }
    packets.push_back(p);
    for (const CommandDecoder::Packet& q : packets) {
      // Re-encoded, a packet gives back its bytes (the checksum byte aside when it was wrong).
      const Bytes raw(q.raw.begin(), q.raw.begin() + static_cast<std::ptrdiff_t>(q.size));
      Bytes again = Encode(q.command);
      ASSERT_EQ(again.size(), raw.size());
      EXPECT_EQ(again[1] == raw[1], q.checksum_ok);
      again[1] = raw[1];
      EXPECT_EQ(again, raw);
      EXPECT_EQ(SumIsZero(raw), q.checksum_ok);
    }
    const Command c = RandomCommand(rng);
    const Bytes frame = Encode(c);
    std::vector<CommandDecoder::Packet> got;
    at = 0;
    while (at < frame.size()) {
      const std::size_t n = 1 + rng() % (frame.size() - at);
      decoder.Feed(std::span(frame).subspan(at, n), &got);
      at += n;
    }
    ++frames;
    if (got.size() == 1 && got[0].command == c && got[0].checksum_ok) ++recovered;
  }
  EXPECT_EQ(recovered, frames);
}

}  // namespace
}  // namespace hgrasp::drivers::pmd
