// libFuzzer target for the SensorHand Speed decoders (drivers/sensorhand/sensorhand_codec.h):
// the host's ReplyDecoder (echoes and stream frames) and the hand's CommandDecoder, each fed
// the same bytes whole and in pseudo-random splits (the first input byte seeds the splits).
// Checked, with __builtin_trap on a violation:
//  - the splits give exactly the frames the whole buffer gives;
//  - every decoded frame is valid (speed bytes; a stream frame's 9 data bytes may take any
//    value) and re-encodes to bytes found in the input, in order;
//  - nothing is lost or invented: the decoded frames' sizes, the discarded bytes and the bytes
//    still held add up to the input size.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "sensorhand/sensorhand_codec.h"

namespace {

using namespace hgrasp::drivers::sensorhand;

bool ValidItem(const Command& c) { return c.kind != Command::Kind::kSpeed || IsValid(c.speed); }

bool ValidItem(const Reply& r) {
  switch (r.kind) {
    case Reply::Kind::kSpeedEcho:
      return IsValid(r.speed);
    case Reply::Kind::kDump:
      return true;  // a stock frame's 9 data bytes may take any value
    default:
      return true;
  }
}

template <class Decoder, class Item>
void Check(std::span<const std::uint8_t> in, std::uint32_t seed) {
  Decoder whole;
  std::vector<Item> a;
  whole.Push(in, &a);

  Decoder split;
  std::vector<Item> b;
  std::uint32_t x = seed * 2654435761u + 1u;
  for (std::size_t at = 0; at < in.size();) {
    x = x * 1103515245u + 12345u;
    const std::size_t k = std::min<std::size_t>(1 + (x >> 16) % 23, in.size() - at);
    split.Push(in.subspan(at, k), &b);
    at += k;
  }
  if (!(a == b)) __builtin_trap();
  if (whole.discarded() != split.discarded() || whole.buffered() != split.buffered()) {
    __builtin_trap();
  }

  std::size_t consumed = 0;
  auto from = in.begin();
  for (const Item& item : a) {
    if (!ValidItem(item)) __builtin_trap();
    const std::vector<std::uint8_t> f = Encode(item);
    const auto hit = std::search(from, in.end(), f.begin(), f.end());
    if (hit == in.end()) __builtin_trap();
    from = hit + static_cast<std::ptrdiff_t>(f.size());
    consumed += f.size();
  }
  if (consumed + whole.discarded() + whole.buffered() != in.size()) __builtin_trap();
  if (whole.frames() != a.size()) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::uint32_t seed = data[0];
  const std::span<const std::uint8_t> in(data + 1, size - 1);
  Check<ReplyDecoder, Reply>(in, seed);
  Check<CommandDecoder, Command>(in, seed);
  return 0;
}
