// libFuzzer target for the PMD (Biclops) decoders: the chip-side CommandDecoder, the host-side
// ReplyDecoder and the emulated chip behind them, on arbitrary bytes in arbitrary splits.
// Invariants (a violation traps):
//  - a split never changes what the command decoder finds;
//  - every decoded packet re-encodes to the bytes it came from (the checksum byte aside when it
//    was wrong), its checksum flag is its byte sum, its length follows from its opcode;
//  - every reply the reply decoder accepts re-encodes to its bytes; a status-0 reply has the
//    expected length;
//  - the emulated chip answers each packet with one well-formed reply (none for a good Reset)
//    whose status agrees with the packet's checks, and logs only state-changing opcodes.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "biclops/pmd_codec.h"
#include "emulators/biclops_emulator.h"

namespace {

using hgrasp::drivers::BiclopsEmulator;
namespace pmd = hgrasp::drivers::pmd;

void Check(bool ok) {
  if (!ok) __builtin_trap();
}

struct Rng {
  std::uint32_t s;
  std::uint32_t Next() {
    s ^= s << 13;
    s ^= s >> 17;
    s ^= s << 5;
    return s;
  }
};

void CheckPacket(const pmd::CommandDecoder::Packet& p) {
  Check(p.size >= 4 && p.size <= pmd::kMaxCommandBytes);
  const std::vector<std::uint8_t> raw(p.raw.begin(), p.raw.begin() + p.size);
  const pmd::OpcodeInfo* info = pmd::FindOpcode(raw[3]);
  Check((info != nullptr) == p.known_opcode);
  if (info != nullptr) {
    Check(p.size == 4 + 2 * static_cast<std::size_t>(info->argument_words));
  } else {
    // An unknown opcode ends at the first whole word with a zero sum, or at the longest packet.
    Check((p.size - 4) % 2 == 0 || p.size == pmd::kMaxCommandBytes);
    for (std::size_t n = 4; n < p.size; n += 2) Check(!pmd::SumIsZero({raw.data(), n}));
    Check(p.checksum_ok || p.size == pmd::kMaxCommandBytes);
  }
  Check(pmd::SumIsZero(raw) == p.checksum_ok);
  std::vector<std::uint8_t> again = pmd::Encode(p.command);
  Check(again.size() == raw.size());
  Check((again[1] == raw[1]) == p.checksum_ok);
  again[1] = raw[1];
  Check(again == raw);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  Rng rng{0x9E3779B9u ^ data[0]};
  const std::span<const std::uint8_t> bytes(data + 1, size - 1);

  // Command decoder: byte by byte, then in random splits; the same packets.
  std::vector<pmd::CommandDecoder::Packet> one, split;
  pmd::CommandDecoder a, b;
  for (std::uint8_t x : bytes) {
    pmd::CommandDecoder::Packet p;
    if (a.Push(x, &p)) one.push_back(p);
    Check(a.pending() < pmd::kMaxCommandBytes);
  }
  for (std::size_t at = 0; at < bytes.size();) {
    const std::size_t n = 1 + rng.Next() % (bytes.size() - at);
    b.Feed(bytes.subspan(at, n), &split);
    at += n;
  }
  Check(one.size() == split.size() && a.pending() == b.pending());
  for (std::size_t i = 0; i < one.size(); ++i) {
    CheckPacket(one[i]);
    Check(one[i].command == split[i].command && one[i].size == split[i].size &&
          one[i].raw == split[i].raw && one[i].checksum_ok == split[i].checksum_ok);
  }

  // Reply decoder: replies of 0..2 words back to back, restarting after each verdict.
  pmd::ReplyDecoder replies;
  int words = data[0] % 3;
  replies.Expect(words);
  for (std::uint8_t x : bytes) {
    const pmd::ReplyDecoder::Result r = replies.Push(x);
    if (r == pmd::ReplyDecoder::Result::kNeedMore) continue;
    if (r == pmd::ReplyDecoder::Result::kReply) {
      const pmd::Reply& reply = replies.reply();
      const std::vector<std::uint8_t> raw(replies.raw().begin(), replies.raw().end());
      Check(pmd::Encode(reply) == raw);
      Check(reply.status == pmd::status::kOk
                ? raw.size() == 2 + 2 * static_cast<std::size_t>(words) && reply.word_count == words
                : raw.size() == 2 && reply.word_count == 0);
    } else {
      Check(!pmd::SumIsZero(replies.raw()) || replies.raw()[0] != pmd::status::kOk ||
            replies.raw().size() != 2 + 2 * static_cast<std::size_t>(words));
    }
    words = static_cast<int>(rng.Next() % 3);
    replies.Expect(words);
  }

  // The emulated chip: one reply per packet, in order.
  BiclopsEmulator chip;
  std::vector<std::uint8_t> out;
  double t = 0.0;
  for (std::size_t at = 0; at < bytes.size();) {
    const std::size_t n = 1 + rng.Next() % (bytes.size() - at);
    t += (rng.Next() % 100) * 1e-3;
    chip.Advance(t, &out);
    chip.Receive(bytes.subspan(at, n), t, &out);
    at += n;
  }
  std::size_t pos = 0;
  for (const pmd::CommandDecoder::Packet& p : one) {
    const bool valid = p.checksum_ok && p.known_opcode && p.command.address == 0;
    if (valid && p.command.opcode == pmd::op::kReset && p.command.axis == 0) continue;
    Check(pos + 2 <= out.size());
    const std::uint8_t status = out[pos];
    if (!p.checksum_ok) Check(status == pmd::status::kBadSerialChecksum);
    if (p.checksum_ok && !valid) Check(status == pmd::status::kInvalidInstruction);
    if (valid && p.command.axis > 2) Check(status == pmd::status::kInvalidAxis);
    const std::size_t len =
        status == pmd::status::kOk
            ? 2 + 2 * static_cast<std::size_t>(pmd::FindOpcode(p.command.opcode)->result_words)
            : 2;
    Check(pos + len <= out.size());
    Check(pmd::SumIsZero({out.data() + pos, len}));
    pos += len;
  }
  Check(pos == out.size());
  for (const auto& e : chip.executed()) {
    const pmd::OpcodeInfo* info = pmd::FindOpcode(e.opcode);
    Check(info != nullptr && info->changes_state && e.axis >= 0 && e.axis <= 2);
  }
  return 0;
}
