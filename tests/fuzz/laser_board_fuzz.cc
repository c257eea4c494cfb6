// libFuzzer target for the laser board protocol (drivers/laser_board/PROTOCOL.md): arbitrary
// bytes through the frame decoder (in one piece and in input-dependent splits), the
// driver-side reply parser and the emulator-side command parser, and the whole emulator.
// Invariants (a violation traps):
//  - the decoder's output does not depend on how the bytes are split;
//  - it never buffers a whole frame's worth of bytes;
//  - every decoded frame re-encodes to a frame that decodes to itself, with CRC residue 0;
//  - every command/reply/payload the parsers accept re-encodes to the bytes it came from;
//  - everything the emulator answers is a well-formed ACK/NAK.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "emulators/laser_board_emulator.h"
#include "laser_board/laser_board_codec.h"

namespace lb = hgrasp::drivers::laser_board;

namespace {

void Require(bool ok) {
  if (!ok) __builtin_trap();
}

// Decodes `data` in pieces whose sizes come from `seed`, then expires what is left over.
std::vector<lb::DecodeEvent> Decode(const std::uint8_t* data, std::size_t size,
                                    std::uint32_t seed) {
  lb::FrameDecoder d;
  std::vector<lb::DecodeEvent> events;
  std::size_t at = 0;
  while (at < size) {
    std::size_t n = size - at;
    if (seed != 0) {
      seed ^= seed << 13;
      seed ^= seed >> 17;
      seed ^= seed << 5;
      n = std::min<std::size_t>(n, 1 + seed % 29);
    }
    d.Feed(std::span<const std::uint8_t>(data + at, n), &events);
    Require(d.buffered() < lb::kMaxFrameSize);
    at += n;
  }
  while (d.partial()) d.Expire(&events);
  return events;
}

void CheckFrame(const lb::Frame& f) {
  Require(f.payload.size() <= lb::kMaxPayload);
  const std::vector<std::uint8_t> bytes = lb::EncodeFrame(f);
  Require(bytes.size() == lb::kMinFrameSize + f.payload.size());
  Require(lb::Crc16CcittFalse(std::span<const std::uint8_t>(bytes).subspan(1)) == 0);
  lb::FrameDecoder d;
  std::vector<lb::DecodeEvent> again;
  d.Feed(bytes, &again);
  Require(again.size() == 1 && again[0].kind == lb::DecodeEvent::Kind::kFrame &&
          again[0].frame == f);

  // Emulator side: a command parses to something that encodes back to the same frame.
  lb::ErrorCode error{};
  if (const auto c = lb::ParseCommand(f, &error)) {
    Require(lb::CommandFrame(f.seq, *c) == f);
  } else {
    Require(error == lb::ErrorCode::kUnknownCommand || error == lb::ErrorCode::kBadLength ||
            error == lb::ErrorCode::kOutOfRange);
  }
  // Driver side: a reply, and the data of the ACKs the driver reads.
  if (const auto r = lb::ParseReply(f)) {
    Require(lb::ReplyFrame(*r) == f);
    if (r->ack) {
      if (const auto s = lb::ParseStatus(r->data)) Require(lb::EncodeStatus(*s) == r->data);
      if (const auto e = lb::ParseEncoder(r->data)) Require(lb::EncodeEncoder(*e) == r->data);
      if (const auto l = lb::ParseLatch(r->data)) Require(lb::EncodeLatch(*l) == r->data);
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::uint32_t seed = 2166136261u;  // FNV-1a of the input: the split pattern
  for (std::size_t i = 0; i < size; ++i) seed = (seed ^ data[i]) * 16777619u;
  seed |= 1u;

  const auto whole = Decode(data, size, 0);
  const auto split = Decode(data, size, seed);
  Require(whole.size() == split.size());
  for (std::size_t i = 0; i < whole.size(); ++i) {
    Require(whole[i].kind == split[i].kind);
    Require(whole[i].frame == split[i].frame);
    if (whole[i].kind == lb::DecodeEvent::Kind::kFrame) CheckFrame(whole[i].frame);
  }

  // The emulator on the same bytes (1 ms apart per piece): its answers are well formed.
  hgrasp::drivers::LaserBoardEmulator board;
  std::vector<std::uint8_t> out;
  double t = 0.0;
  for (std::size_t at = 0; at < size;) {
    const std::size_t n = std::min<std::size_t>(size - at, 1 + (seed >> (at % 24)) % 17);
    t += 0.001;
    board.Advance(t, &out);
    board.Receive(std::span<const std::uint8_t>(data + at, n), t, &out);
    at += n;
  }
  board.Advance(t + 1.0, &out);
  lb::FrameDecoder replies;
  std::vector<lb::DecodeEvent> events;
  replies.Feed(out, &events);
  Require(!replies.partial());
  for (const auto& e : events) {
    Require(e.kind == lb::DecodeEvent::Kind::kFrame);
    Require(lb::ParseReply(e.frame).has_value());
  }
  // State-changing commands only run with a sequence number.
  for (const auto& entry : board.log()) Require(entry.seq != lb::kUnsequenced);
  return 0;
}
